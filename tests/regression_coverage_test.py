#!/usr/bin/env python3
"""scripts/regression_coverage.py on made-up inputs: a baseline that covers a small `harness list`
passes; one env without rows, an optimizer on one env only, and a missing ext: optimizer each fail
with exit 1 and a line naming them; the real `harness list` against the stored baseline passes."""
import os
import subprocess
import sys
import tempfile
import unittest

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SCRIPT = os.path.join(ROOT, "scripts", "regression_coverage.py")
HARNESS = sys.argv.pop(1) if len(sys.argv) > 1 else None

LIST = """env                    version   dim differentiable  rl  description
sphere-2                     1     2            yes  no  sphere
plb-pinch                    2    15            yes yes  plb

optimizer              version needs gradient needs rl  seed use  description
random                       1             no       no  at start  random
gd                           1            yes       no     never  gd
ext:NAME                     1         either       no   its own  yours
"""
HEADER = "env,optimizer,seed,budget,env_config_hash,opt_config_hash,env_version,optimizer_version,run_version,episode,loss\n"


def run(baseline_rows, listing=LIST):
    with tempfile.TemporaryDirectory() as d:
        path = os.path.join(d, "b.csv")
        with open(path, "w") as f:
            f.write(HEADER + "".join(f"{e},{o},0,3,a,b,1,1,1,0,1.5\n" for e, o in baseline_rows))
        p = subprocess.run([sys.executable, SCRIPT, path], input=listing, capture_output=True, text=True)
        return p.returncode, p.stdout


FULL = [(e, o) for e in ("sphere-2", "plb-pinch-h5") for o in ("random", "gd", "ext:random")]


class Coverage(unittest.TestCase):
    def test_a_covering_baseline_passes(self):
        code, out = run(FULL)
        self.assertEqual(code, 0, out)
        self.assertIn("coverage: 2 of 2 envs, 3 of 3 optimizers", out)

    def test_an_env_without_rows_fails(self):
        code, out = run([r for r in FULL if r[0] != "plb-pinch-h5"] + [("sphere-3", "random"), ("sphere-3", "gd"),
                                                                        ("sphere-3", "ext:random")])
        self.assertEqual(code, 1, out)
        self.assertIn("coverage: missing: env plb-pinch: no rows", out)

    def test_an_optimizer_on_one_env_fails(self):
        code, out = run([r for r in FULL if r != ("sphere-2", "gd")])
        self.assertEqual(code, 1, out)
        self.assertIn("coverage: missing: optimizer gd: rows on 1 envs, needs 2", out)

    def test_no_ext_optimizer_fails(self):
        code, out = run([r for r in FULL if r[1] != "ext:random"])
        self.assertEqual(code, 1, out)
        self.assertIn("coverage: missing: optimizer ext:: rows on 0 envs, needs 2", out)

    @unittest.skipUnless(HARNESS, "needs the harness binary")
    def test_the_stored_baseline_covers_this_harness(self):
        listing = subprocess.run([HARNESS, "list"], capture_output=True, text=True, check=True).stdout
        p = subprocess.run([sys.executable, SCRIPT, os.path.join(ROOT, "data", "baselines", "small-grid.csv")],
                           input=listing, capture_output=True, text=True)
        self.assertEqual(p.returncode, 0, p.stdout + p.stderr)


if __name__ == "__main__":
    unittest.main()
