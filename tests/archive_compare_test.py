#!/usr/bin/env python3
"""The published archive and the comparison against it (docs/results.md, "Compare your optimizer
with the published runs"), through the real harness on a cheap env:

- scripts/archive_runs.py writes a database's done runs with their per-episode losses; the file
  rebuilds every run's final best loss bit for bit, `check` finds each published run once, and a
  run whose loss differs from the published one is refused; `land` archives a rerun's finished
  pieces under the names of the runs CSVs that publish them; `runs-csv` gives back the runs CSV
  that `study_results.py export` wrote from the database, byte for byte;
- the README's newcomer path: an ext: random search (examples/ext/random_search.py) on sphere-2 for
  3 seeds, then `harness report --db mine --with ARCHIVE`: the archived optimizers beside it in the
  ranks and curves (marked archived), an archived run the database also holds counted once (the
  database's copy, which repeats it bit for bit), an env the archive lacks named, an archived run
  of other results versions left out and said;
- `harness export --format ioh --with ARCHIVE` with and without a database.

    archive_compare_test.py HARNESS
"""
import csv
import gzip
import json
import os
import shutil
import sqlite3
import subprocess
import sys
import tempfile
import unittest

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
HARNESS = sys.argv.pop(1) if len(sys.argv) > 1 else os.path.join(ROOT, "build", "bin", "harness")
PY = "/usr/bin/python3"
sys.path.insert(0, os.path.join(ROOT, "reports"))
from dsb_report import archive  # noqa: E402


def run(*args, cwd=ROOT, check=True):
    p = subprocess.run(list(args), cwd=cwd, capture_output=True, text=True)
    if check and p.returncode != 0:
        raise AssertionError(f"{args} exited {p.returncode}: {p.stdout}{p.stderr}")
    return p


class ArchiveCompare(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.tmp = tempfile.TemporaryDirectory()
        d = cls.d = cls.tmp.name
        # the "published" study: 3 optimizers on sphere-2, 3 seeds, and its runs CSV
        run(HARNESS, "--env", "sphere-2", "--optimizer", "random,cmaes,gd", "--seeds", "3", "--budget", "25",
            "--quiet", "--db", f"{d}/pub.sqlite")
        run(PY, "scripts/study_results.py", "export", f"{d}/pub.sqlite", f"{d}/pub.csv")
        os.mkdir(f"{d}/archive")
        cls.write = run(PY, "scripts/archive_runs.py", "write", f"{d}/pub.sqlite",
                        f"{d}/archive/sphere.runs.jsonl.gz", "--against", f"{d}/pub.csv")
        # the newcomer: a random search over the protocol, and random itself (the archived key)
        run(HARNESS, "--env", "sphere-2,branin", "--optimizer", "ext:rs,random", "--ext",
            "rs=/usr/bin/python3 examples/ext/random_search.py", "--seeds", "3", "--budget", "25", "--quiet",
            "--db", f"{d}/mine.sqlite")

    @classmethod
    def tearDownClass(cls):
        cls.tmp.cleanup()

    def test_the_archive_holds_every_published_run_with_its_losses(self):
        self.assertIn("9 of the 9 published runs found", self.write.stdout)
        runs = archive.read(f"{self.d}/archive/sphere.runs.jsonl.gz")
        self.assertEqual(len(runs), 9)
        with open(f"{self.d}/pub.csv", newline="") as f:
            pub = {(r["optimizer"], r["seed"]): r for r in csv.DictReader(f)}
        for r in runs:
            self.assertEqual(len(r["loss"]), 25)
            self.assertEqual(len(r["used_grad"]), 25)
            self.assertEqual(r["results_versions"], pub[(r["optimizer"], str(r["seed"]))]["results_versions"])
            best = archive.best_so_far(r["loss"])[-1]
            self.assertEqual(best.hex(), float(pub[(r["optimizer"], str(r["seed"]))]["best_loss"]).hex())
        self.assertEqual({r["optimizer"]: r["used_grad"].count("1") > 0 for r in runs},
                         {"random": False, "cmaes": False, "gd": True})
        ok = run(PY, "scripts/archive_runs.py", "check", f"{self.d}/archive", "--against", f"{self.d}/pub.csv")
        self.assertIn("9 of 9 published runs archived", ok.stdout)
        # the same bytes again: a file depends on its runs only
        again = f"{self.d}/again.runs.jsonl.gz"
        run(PY, "scripts/archive_runs.py", "write", f"{self.d}/pub.sqlite", again)
        with open(again, "rb") as a, open(f"{self.d}/archive/sphere.runs.jsonl.gz", "rb") as b:
            self.assertEqual(a.read(), b.read())

    def test_the_archives_runs_csv_is_the_databases_export_byte_for_byte(self):
        out = f"{self.d}/from-archive.csv"
        r = run(PY, "scripts/archive_runs.py", "runs-csv", f"{self.d}/archive", out)
        self.assertIn("9 runs ->", r.stdout)
        with open(out, "rb") as a, open(f"{self.d}/pub.csv", "rb") as b:
            self.assertEqual(a.read(), b.read())
        # never over a file
        again = run(PY, "scripts/archive_runs.py", "runs-csv", f"{self.d}/archive", f"{self.d}/pub.csv", check=False)
        self.assertEqual(again.returncode, 2)
        self.assertIn("pub.csv' exists", again.stderr)
        with open(out, "rb") as a, open(f"{self.d}/pub.csv", "rb") as b:
            self.assertEqual(a.read(), b.read())

    def test_a_runs_csv_row_from_losses_with_a_failed_episode_and_a_metric(self):
        # episode 1 failed (null), the smallest loss 1.0 first at episode 2, where the metric is 0.5
        obj = dict(archive.read(f"{self.d}/archive/sphere.runs.jsonl.gz")[0], episodes=5,
                   loss=[3.0, None, 1.0, 1.0, 2.0], used_grad="00000", metric=[0.3, None, 0.5, 0.6, 0.7])
        path = f"{self.d}/metric.runs.jsonl.gz"
        archive.write([obj], path)
        out = f"{self.d}/metric.csv"
        run(PY, "scripts/archive_runs.py", "runs-csv", path, out)
        with open(out, newline="") as f:
            row, = list(csv.DictReader(f))
        self.assertEqual((row["episodes"], row["best_loss"], row["best_episode"], row["metric_at_best"]),
                         ("5", "1.0", "2", "0.5"))
        self.assertEqual(row["results_versions"], obj["results_versions"])

    def test_a_rerun_that_differs_from_the_published_runs_is_refused(self):
        bad = f"{self.d}/bad.csv"
        with open(f"{self.d}/pub.csv", newline="") as f:
            rows = list(csv.reader(f))
        rows[1][6] = repr(float(rows[1][6]) * (1 + 2 ** -50))   # best_loss of one run, one ulp off
        with open(bad, "w", newline="") as f:
            csv.writer(f, lineterminator="\n").writerows(rows)
        p = run(PY, "scripts/archive_runs.py", "write", f"{self.d}/pub.sqlite", f"{self.d}/no.runs.jsonl.gz",
                "--against", bad, check=False)
        self.assertEqual(p.returncode, 2)
        self.assertIn("1 runs differ from the published ones, nothing written", p.stderr)
        self.assertFalse(os.path.exists(f"{self.d}/no.runs.jsonl.gz"))
        c = run(PY, "scripts/archive_runs.py", "check", f"{self.d}/archive", "--against", bad, check=False)
        self.assertEqual(c.returncode, 1)
        self.assertIn("published", c.stdout)

    def test_land_archives_a_reruns_finished_pieces_under_the_published_names(self):
        d = f"{self.d}/land"
        os.makedirs(f"{d}/study")
        os.makedirs(f"{d}/pieces")
        # the published study in two pieces: random's and cmaes's runs CSVs
        for opt in ("random", "cmaes"):
            run(HARNESS, "--env", "sphere-2", "--optimizer", opt, "--seeds", "3", "--budget", "25", "--quiet",
                "--db", f"{d}/pub-{opt}.sqlite")
            run(PY, "scripts/study_results.py", "export", f"{d}/pub-{opt}.sqlite", f"{d}/study/sphere-2__{opt}.csv")
        # the rerun's pieces: random's under its published name, cmaes's under another, gd's
        # (published nowhere), and a copy of random's with a run still running
        for opt, name in (("random", "sphere-2__random"), ("cmaes", "cmaes-rerun@0of1"), ("gd", "sphere-2__gd")):
            run(HARNESS, "--env", "sphere-2", "--optimizer", opt, "--seeds", "3", "--budget", "25", "--quiet",
                "--db", f"{d}/pieces/{name}.sqlite")
        shutil.copyfile(f"{d}/pieces/sphere-2__random.sqlite", f"{d}/pieces/zz-running.sqlite")
        con = sqlite3.connect(f"{d}/pieces/zz-running.sqlite")
        con.execute("UPDATE runs SET status = 'running' WHERE seed = 0")
        con.commit()
        con.close()
        p = run(PY, "scripts/archive_runs.py", "land", f"{d}/pieces", f"{d}/study")
        self.assertIn("pieces 2 landed, 0 archived already, 1 running, 1 publishing none", p.stdout)
        self.assertEqual(sorted(f for f in os.listdir(f"{d}/study") if f.endswith(archive.SUFFIX)),
                         ["sphere-2__cmaes.runs.jsonl.gz", "sphere-2__random.runs.jsonl.gz"])
        for opt in ("random", "cmaes"):
            with open(f"{d}/study/sphere-2__{opt}.csv", newline="") as f:
                want = {int(r["seed"]): float(r["best_loss"]) for r in csv.DictReader(f)}
            got = {r["seed"]: archive.final_best(r["loss"])[0]
                   for r in archive.read(f"{d}/study/sphere-2__{opt}.runs.jsonl.gz")}
            self.assertEqual({s: v.hex() for s, v in got.items()}, {s: v.hex() for s, v in want.items()}, opt)
        # again: nothing new, nothing rewritten
        before = {f: os.path.getmtime(f"{d}/study/{f}") for f in os.listdir(f"{d}/study")}
        p = run(PY, "scripts/archive_runs.py", "land", f"{d}/pieces", f"{d}/study")
        self.assertIn("pieces 0 landed, 2 archived already, 1 running, 1 publishing none", p.stdout)
        self.assertEqual(before, {f: os.path.getmtime(f"{d}/study/{f}") for f in os.listdir(f"{d}/study")})
        # a piece whose final best loss is one ulp off its published one is named and not archived
        os.makedirs(f"{d}/study2")
        with open(f"{d}/study/sphere-2__random.csv", newline="") as f:
            rows = list(csv.reader(f))
        rows[1][6] = repr(float(rows[1][6]) * (1 + 2 ** -50))
        with open(f"{d}/study2/sphere-2__random.csv", "w", newline="") as f:
            csv.writer(f, lineterminator="\n").writerows(rows)
        p = run(PY, "scripts/archive_runs.py", "land", f"{d}/pieces", f"{d}/study2", check=False)
        self.assertEqual(p.returncode, 1, p.stdout + p.stderr)
        self.assertIn("sphere-2__random.sqlite: 1 runs differ from the published ones, not archived", p.stdout)
        self.assertEqual(os.listdir(f"{d}/study2"), ["sphere-2__random.csv"])
        # bad input: exit 2, one line
        p = run(PY, "scripts/archive_runs.py", "land", f"{d}/no-such", f"{d}/study", check=False)
        self.assertEqual((p.returncode, p.stderr.count("\n")), (2, 1))
        self.assertIn("no-such", p.stderr)

    def test_the_report_ranks_yours_beside_the_archived_runs(self):
        out = f"{self.d}/report"
        run(HARNESS, "report", "--db", f"{self.d}/mine.sqlite", "--with", f"{self.d}/archive", "--out", out)
        with open(f"{out}/index.html", encoding="utf-8") as f:
            page = f.read()
        self.assertIn("9 archived runs in 1 files, 6 shown beside the database", page)
        self.assertIn("3 of the database&#x27;s runs have an archived run&#x27;s key and are counted once, the "
                      "database&#x27;s copy kept (3 repeat it bit for bit)", page)
        self.assertIn("the archive has no runs of branin (yours alone there)", page)
        with open(f"{out}/sources.csv", newline="") as f:
            src = {(r["env"], r["optimizer"]): (int(r["yours"]), int(r["archived"])) for r in csv.DictReader(f)}
        self.assertEqual(src[("sphere-2", "ext:rs")], (3, 0))
        self.assertEqual(src[("sphere-2", "cmaes")], (0, 3))
        self.assertEqual(src[("sphere-2", "random")], (3, 0))   # the database's copies
        with open(f"{out}/final_sphere-2.csv", newline="") as f:
            ranked = {r["optimizer"] for r in csv.DictReader(f)}
        self.assertEqual(ranked, {"cmaes", "gd", "random", "ext:rs"})

    def test_archived_runs_of_other_versions_are_left_out_and_said(self):
        folder = f"{self.d}/old-archive"
        os.mkdir(folder)
        runs = archive.read(f"{self.d}/archive/sphere.runs.jsonl.gz")
        for r in runs:
            if r["optimizer"] == "cmaes":
                r["results_versions"] = "env 1, optimizer 99, run 1"
        archive.write(runs, f"{folder}/old.runs.jsonl.gz")
        out = f"{self.d}/report-old"
        run(HARNESS, "report", "--db", f"{self.d}/mine.sqlite", "--with", folder, "--out", out)
        with open(f"{out}/stale_runs.csv", newline="") as f:
            stale = list(csv.DictReader(f))
        self.assertEqual([(r["optimizer"], r["done"]) for r in stale], [("cmaes", "3")])
        self.assertIn("optimizer cmaes version 99", stale[0]["reason"])
        with open(f"{out}/final_sphere-2.csv", newline="") as f:
            self.assertNotIn("cmaes", {r["optimizer"] for r in csv.DictReader(f)})
        e = run(HARNESS, "export", "--format", "ioh", "--with", folder, "--out", f"{self.d}/ioh-old")
        self.assertIn("left out 3 stale runs", e.stderr)

    def test_ioh_export_of_the_archive_with_and_without_a_database(self):
        a = run(HARNESS, "export", "--format", "ioh", "--with", f"{self.d}/archive", "--out", f"{self.d}/ioh-a")
        self.assertIn("wrote 9 runs", a.stderr)
        self.assertEqual(sorted(os.listdir(f"{self.d}/ioh-a")), ["cmaes", "gd", "random"])
        b = run(HARNESS, "export", "--format", "ioh", "--db", f"{self.d}/mine.sqlite", "--with",
                f"{self.d}/archive", "--out", f"{self.d}/ioh-b")
        self.assertIn("wrote 18 runs", b.stderr)
        self.assertIn("6 of them archived", b.stderr)
        self.assertIn("3 archived runs the database also holds counted once", b.stderr)
        self.assertEqual(sorted(os.listdir(f"{self.d}/ioh-b")), ["cmaes", "ext_rs", "gd", "random"])

    def test_a_damaged_archive_is_named(self):
        bad = f"{self.d}/bad-archive"
        os.mkdir(bad)
        with gzip.open(f"{bad}/x.runs.jsonl.gz", "wt") as f:
            f.write(json.dumps({"archive": 1, "env": "sphere-2"}) + "\n")
        p = run(HARNESS, "export", "--format", "ioh", "--with", bad, "--out", f"{self.d}/ioh-bad", check=False)
        self.assertEqual(p.returncode, 2)
        self.assertIn("x.runs.jsonl.gz' line 1", p.stderr)
        r = run(HARNESS, "report", "--db", f"{self.d}/mine.sqlite", "--with", bad, "--out", f"{self.d}/rep-bad",
                check=False)
        self.assertEqual(r.returncode, 2)
        self.assertIn("x.runs.jsonl.gz' line 1: no", r.stderr)


if __name__ == "__main__":
    unittest.main()
