#!/usr/bin/python3
"""scripts/landscape-gallery.sh and the report's gallery.html on two cheap envs (standard library).

usage: /usr/bin/python3 tests/landscape_gallery_test.py BUILD_DIR SOURCE_DIR

Runs the script with --envs branin,pinball-1x2 --res 7 (49 points per slice), checks the CSVs
(N^2 rows, the grid over [-1, 1]^2, finite losses, branin's loss equal to `harness eval` at a grid
point), checks the script's plan (--list: every env of `harness list`, the seed's dims, the
particle envs at their -h5 variants), then builds a report with --landscapes and checks that
gallery.html shows each env's image under its gradient quality row and that index.html links it.
"""
import csv
import json
import math
import os
import re
import shutil
import subprocess
import sys
import tempfile
import unittest

BUILD = SRC = ""
RES = 7


class TestLandscapeGallery(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.tmp = tempfile.mkdtemp(prefix="dsb_gallery_test_")
        cls.harness = os.path.join(BUILD, "bin", "harness")
        cls.script = os.path.join(SRC, "scripts", "landscape-gallery.sh")
        cls.land = os.path.join(cls.tmp, "land")
        subprocess.run([cls.script, cls.land, "--build", BUILD, "--envs", "branin,pinball-1x2",
                        "--res", str(RES)], check=True, capture_output=True, text=True)
        db = os.path.join(cls.tmp, "db.sqlite")
        subprocess.run([cls.harness, "--env", "branin,pinball-1x2", "--optimizer", "random",
                        "--seeds", "1", "--budget", "5", "--quiet", "--db", db], check=True)
        cls.out = os.path.join(cls.tmp, "report")
        subprocess.run([sys.executable, os.path.join(SRC, "reports", "make_report.py"), "--db", db,
                        "--out", cls.out, "--landscapes", cls.land], check=True,
                       capture_output=True, text=True)
        with open(os.path.join(cls.out, "gallery.html"), encoding="utf-8") as f:
            cls.gallery = f.read()

    @classmethod
    def tearDownClass(cls):
        shutil.rmtree(cls.tmp, ignore_errors=True)

    def rows(self, name):
        with open(os.path.join(self.land, name), newline="") as f:
            return list(csv.DictReader(f))

    def test_csv_rows(self):
        self.assertEqual(sorted(os.listdir(self.land)), ["branin_0_1.csv", "pinball-1x2_0_1.csv"])
        grid = sorted({-1 + 2 * k / (RES - 1) for k in range(RES)})
        for name in os.listdir(self.land):
            rows = self.rows(name)
            self.assertEqual(len(rows), RES * RES, name)
            self.assertEqual(list(rows[0])[:7], ["i", "j", "xi", "xj", "loss", "grad_i", "grad_j"])
            for r in rows:
                self.assertTrue(math.isfinite(float(r["loss"])), f"{name}: {r}")
            for col in ("xi", "xj"):
                got = sorted({float(r[col]) for r in rows})
                self.assertEqual(len(got), RES)
                for a, b in zip(got, grid):
                    self.assertAlmostEqual(a, b, places=12)

    def test_branin_loss_equals_eval(self):
        r = self.rows("branin_0_1.csv")[RES + 2]   # some point off the corners
        out = subprocess.run([self.harness, "eval", "--env", "branin", "--x",
                              f"{r['xi']},{r['xj']}"], check=True, capture_output=True, text=True)
        self.assertEqual(float(r["loss"]), json.loads(out.stdout)["loss"])

    def test_plan_covers_every_env_with_the_seeds_dims(self):
        listed = subprocess.run([self.harness, "list"], check=True, capture_output=True,
                                text=True).stdout
        envs = []
        for line in listed.splitlines()[1:]:
            if not line.strip():
                break
            envs.append(line.split()[0])
        plan = subprocess.run([self.script, self.tmp, "--build", BUILD, "--list"], check=True,
                              capture_output=True, text=True).stdout.splitlines()[1:]
        got = {p.split()[0]: p.split()[1:] for p in plan}
        self.assertEqual(list(got), envs)
        self.assertEqual(got["fluid"], ["fluid-h5", "9", "0,1", "6,8", "8,9"])
        self.assertEqual(got["pinball-4x4"][2:], ["13,14"])
        self.assertEqual(got["plb-table"][0::2], ["plb-table-h5", "0,2", "12,13"])
        self.assertEqual(got["flip"][2:], ["0,1", "0,2", "1,2"])
        self.assertEqual(got["plb-writer"][2:], ["0,3", "1,4", "2,5"])
        for env, (variant, *_rest) in got.items():
            if env == "fluid" or env.startswith("plb-"):
                self.assertEqual(variant, env + "-h5")
            else:
                self.assertEqual(variant, env)

    def test_gallery_lists_each_envs_image_under_its_survey_row(self):
        for env in ("branin", "pinball-1x2"):
            start = self.gallery.index(f'<h2 id="gallery-{env}">')
            end = self.gallery.find("<h2", start + 1)
            sec = self.gallery[start:end if end > 0 else None]
            self.assertIn(f'<img src="landscape_{env}_0_1.png"', sec)
            self.assertTrue(os.path.isfile(os.path.join(self.out, f"landscape_{env}_0_1.png")))
            self.assertRegex(sec, rf"<tr[^>]*><td>{re.escape(env)}</td>")   # its survey row
        self.assertIn('<h2 id="gradient-quality">', self.gallery)
        with open(os.path.join(self.out, "index.html"), encoding="utf-8") as f:
            self.assertIn('href="gallery.html"', f.read())


if __name__ == "__main__":
    if len(sys.argv) != 3:
        print(__doc__, file=sys.stderr)
        sys.exit(2)
    BUILD, SRC = os.path.abspath(sys.argv[1]), os.path.abspath(sys.argv[2])
    sys.exit(0 if unittest.main(argv=sys.argv[:1], exit=False).result.wasSuccessful() else 1)
