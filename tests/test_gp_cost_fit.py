#!/usr/bin/env python3
"""scripts/gp_cost_fit.py: its schedules are the C++ model's (optimizers/bo/gp_cost.cpp), and its fit
recovers constants from growths made with them.

    python3 tests/test_gp_cost_fit.py SOURCE_DIR
"""
import os
import sys
import tempfile
import unittest
import subprocess

SOURCE = sys.argv.pop(1) if len(sys.argv) > 1 else os.path.join(os.path.dirname(__file__), "..")
sys.path.insert(0, os.path.join(SOURCE, "scripts"))
import gp_cost_fit as g  # noqa: E402


class Schedules(unittest.TestCase):
    def test_fit_counts_are_the_cpp_models(self):
        # bo: the diagnostics' gp_fits of 1,000- and 200-episode runs (10-D: design 11, 39 fits to
        # n = 50, then every 10% of growth; 200-D: design 20), as test_bo checks bo_fits against runs
        self.assertEqual(len(g.bo_fits(10, 1000)), 70)
        self.assertEqual(len(g.bo_fits(10, 200)), 53)
        self.assertEqual(len(g.bo_fits(200, 1000)), 61)
        self.assertEqual(len(g.bo_fits(200, 200)), 44)
        # boleap: tests/test_plan_costs.cpp BoLeapsGpIsFittedOnItsDesignAndAfterEveryLeapThatLeavesBudget
        self.assertEqual(len(g.boleap_fits(400, 1000)), 10)
        self.assertEqual(len(g.boleap_fits(400, 200)), 2)
        self.assertEqual(len(g.boleap_fits(400, 10)), 1)

    def test_acquisition_sum_is_the_cpp_models(self):
        # tests/test_bo.cpp: a 13-episode run in 10-D proposes at n = 11 and 12, 812 evaluations each
        _, _, sa = g.sums("bo", 10, 13)
        self.assertEqual(sa, 812 * (11 * 21 + 12 * 22))
        self.assertEqual(g.sums("boleap", 10, 13)[2], 0.0)
        s3, s2d, _ = g.sums("bo", 10, 13)
        self.assertEqual(s3, 80.0 * (11**3 + 12**3 + 13**3))
        self.assertEqual(s2d, 80.0 * 10 * (11**2 + 12**2 + 13**2))


class Fit(unittest.TestCase):
    def test_recovers_the_constants_that_made_the_growths(self):
        a, b, c = 1.2e-10, 5e-10, 2.5e-10
        rows = []
        for opt, dim in (("bo", 10), ("bo", 200), ("boleap", 10), ("boleap", 200)):
            hi, lo = g.sums(opt, dim, 1000), g.sums(opt, dim, 200)
            row = dict(s3=hi[0] - lo[0], s2d=hi[1] - lo[1], sa=hi[2] - lo[2])
            row["growth_s"] = g.model(row, a, b, c)
            rows.append(row)
        for got, want in zip(g.fit_constants(rows), (a, b, c)):
            self.assertAlmostEqual(got / want, 1.0, places=5)

    def test_refuses_an_existing_output_and_a_missing_database(self):
        with tempfile.TemporaryDirectory() as tmp:
            out = os.path.join(tmp, "fit.csv")
            with open(out, "w") as f:
                f.write("mine\n")
            script = os.path.join(SOURCE, "scripts", "gp_cost_fit.py")
            r = subprocess.run([sys.executable, script, os.path.join(tmp, "none.sqlite"), out],
                               capture_output=True, text=True)
            self.assertEqual(r.returncode, 2)
            self.assertIn("none.sqlite", r.stderr)
            open(os.path.join(tmp, "db.sqlite"), "w").close()
            r = subprocess.run([sys.executable, script, os.path.join(tmp, "db.sqlite"), out],
                               capture_output=True, text=True)
            self.assertEqual(r.returncode, 2)
            self.assertIn("fit.csv", r.stderr)
            with open(out) as f:
                self.assertEqual(f.read(), "mine\n")


if __name__ == "__main__":
    unittest.main()
