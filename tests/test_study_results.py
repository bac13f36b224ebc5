#!/usr/bin/python3
"""scripts/study_results.py on a small real database (ctest study_results): the runs CSV keeps
every run and its floats to the bit, and the claims verdicts and medians made from the CSV are
those made from the database.

    /usr/bin/python3 tests/test_study_results.py BUILD_DIR SOURCE_DIR
"""
import csv
import os
import shutil
import sqlite3
import statistics
import subprocess
import sys
import tempfile
import unittest

BUILD, SOURCE = sys.argv.pop(1), sys.argv.pop(1)
sys.path.insert(0, os.path.join(SOURCE, "reports"))
from dsb_report import claims as claims_mod, data as data_mod, runs_csv  # noqa: E402

SCRIPT = os.path.join(SOURCE, "scripts", "study_results.py")
HARNESS = os.path.join(BUILD, "bin", "harness")


def study(*args):
    return subprocess.run([sys.executable, SCRIPT, *args], capture_output=True, text=True)


class StudyResults(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.tmp = tempfile.mkdtemp()
        cls.db = os.path.join(cls.tmp, "grid.sqlite")
        subprocess.run([HARNESS, "--env", "cartpole1,sphere-2", "--optimizer", "random,cmaes,rand-descents,bo,gd",
                        "--seeds", "5", "--budget", "20", "--quiet", "--db", cls.db], check=True)
        con = sqlite3.connect(cls.db)
        # cartpole1's episodes get a metric (cmaes 0.9, the others 0.1), and one run is left
        # running, as an interrupted grid leaves it
        con.execute("UPDATE evals SET metric = CASE (SELECT optimizer FROM runs r WHERE r.run_id = evals.run_id) "
                    "WHEN 'cmaes' THEN 0.9 ELSE 0.1 END WHERE run_id IN (SELECT run_id FROM runs WHERE env = 'cartpole1')")
        con.execute("UPDATE runs SET status = 'running' WHERE env = 'sphere-2' AND optimizer = 'bo' AND seed = 2")
        con.commit()
        con.close()
        cls.claims = os.path.join(cls.tmp, "claims.csv")
        shutil.copy(os.path.join(SOURCE, "reports", "paper_claims.csv"), cls.claims)
        with open(cls.claims, "a", newline="", encoding="utf-8") as f:
            w = csv.writer(f, lineterminator="\n")
            w.writerow(["lifts", "cartpole1", "metric_most", "cmaes", "", "0.5", "cmaes lifts", "t", ""])
            w.writerow(["sphere", "sphere-2", "a_below_b", "cmaes", "random bo", "", "cmaes first", "t", ""])
        cls.csv = os.path.join(cls.tmp, "runs.csv")
        r = study("export", cls.db, cls.csv)
        assert r.returncode == 0, r.stderr

    @classmethod
    def tearDownClass(cls):
        shutil.rmtree(cls.tmp)

    def test_every_run_to_the_bit(self):
        con = sqlite3.connect(self.db)
        db = {(e, o, s): (st, b) for e, o, s, st, b in
              con.execute("SELECT env, optimizer, seed, status, best_loss FROM runs")}
        with open(self.csv, newline="") as f:
            rows = list(csv.DictReader(f))
        self.assertEqual(len(rows), len(db))
        self.assertEqual(len(rows), 2 * 5 * 5)
        for r in rows:
            status, best = db[(r["env"], r["optimizer"], int(r["seed"]))]
            self.assertEqual(r["status"], status)
            self.assertEqual(float(r["best_loss"]).hex(), best.hex())
        running = [r for r in rows if r["status"] == "running"]
        self.assertEqual([(r["env"], r["optimizer"], r["seed"]) for r in running], [("sphere-2", "bo", "2")])
        self.assertEqual(running[0]["best_episode"], "")  # not analysed
        # the episode of the final best and the metric there, for the analysed runs
        for r in rows:
            if r["status"] == "done":
                k = int(r["best_episode"])
                loss, = con.execute("SELECT e.loss FROM evals e JOIN runs x ON x.run_id = e.run_id WHERE x.env = ? "
                                    "AND x.optimizer = ? AND x.seed = ? AND e.episode = ?",
                                    (r["env"], r["optimizer"], int(r["seed"]), k)).fetchone()
                self.assertEqual(loss, float(r["best_loss"]))
        metrics = {r["optimizer"]: r["metric_at_best"] for r in rows if r["env"] == "cartpole1"}
        self.assertEqual((metrics["cmaes"], metrics["random"]), ("0.9", "0.1"))
        self.assertTrue(all(r["metric_at_best"] == "" for r in rows if r["env"] == "sphere-2"))

    def test_the_verdicts_from_the_csv_are_those_from_the_database(self):
        claims = claims_mod.load(self.claims)
        d = data_mod.load(self.db)
        c = runs_csv.load(self.csv)
        from_db, comps_db = claims_mod.evaluate(claims, data_mod.main_panels(d), d.runs)
        from_csv, comps_csv = claims_mod.evaluate(claims, data_mod.main_panels(c), c.runs)
        cols = ["id", "env", "budget", "verdict", "reason", "n", "p_holm", "p_claim", "a12", "runs_done", "settle"]
        self.assertEqual(from_db[cols].astype(str).values.tolist(), from_csv[cols].astype(str).values.tolist())
        self.assertEqual(comps_db.astype(str).values.tolist(), comps_csv.astype(str).values.tolist())
        verdicts = dict(zip(zip(from_csv["id"], from_csv["env"]), from_csv["verdict"]))
        self.assertEqual(verdicts[("lifts", "cartpole1")], "holds")
        # bo ends far below cmaes on sphere-2 (4 of its 5 runs done): cmaes is not first
        self.assertEqual(verdicts[("sphere", "sphere-2")], "does not hold")

    def test_tables(self):
        r = study("tables", self.csv, "--claims", self.claims)
        self.assertEqual(r.returncode, 0, r.stderr)
        # each median as SQLite's runs give it
        con = sqlite3.connect(self.db)
        med = statistics.median(b for b, in con.execute(
            "SELECT best_loss FROM runs WHERE env = 'cartpole1' AND optimizer = 'cmaes'"))
        line = next(x for x in r.stdout.splitlines() if x.startswith("| cartpole1 (20, 5) |"))
        header = next(x for x in r.stdout.splitlines() if x.startswith("| env (budget, seeds) |"))
        cells = dict(zip([h.strip() for h in header.split("|")[2:-1]], [c.strip() for c in line.split("|")[2:-1]]))
        self.assertEqual(cells["cmaes"], f"{med:.4g}")
        self.assertIn("| lifts | cartpole1 | holds | — | cmaes lifts |", r.stdout)
        # an unsettled row names the claims grid restricted to its env; one no run can settle, none
        fluid = next(x for x in r.stdout.splitlines() if x.startswith("| fluid-boleap-best | fluid |"))
        self.assertIn("| runs missing: 0 of ", fluid)
        self.assertIn("| `harness --claims --env fluid --seeds 5` |", fluid)
        tip = next(x for x in r.stdout.splitlines() if x.startswith("| cartpole3-tip-at-target |"))
        self.assertIn("| not testable from the database | none |", tip)
        self.assertIn("- cartpole1, metric at the best episode >= 0.5: bo 0 of 5; cmaes 5 of 5;", r.stdout)

    def test_tables_from_several_files_are_those_from_one(self):
        # the study's grids published apart (data/study/runs.csv and the fluid grid's pieces)
        with open(self.csv, newline="") as f:
            rows = list(csv.reader(f))
        parts = []
        for env in ("cartpole1", "sphere-2"):
            path = os.path.join(self.tmp, f"part-{env}.csv")
            with open(path, "w", newline="") as f:
                csv.writer(f, lineterminator="\n").writerows([rows[0]] + [r for r in rows[1:] if r[0] == env])
            parts.append(path)
        whole = study("tables", self.csv, "--claims", self.claims)
        split = study("tables", *parts, "--claims", self.claims)
        self.assertEqual(split.returncode, 0, split.stderr)
        self.assertEqual(split.stdout, whole.stdout)
        self.assertIn("| sphere | sphere-2 | does not hold |", split.stdout)
        # one run in two files: refused in one line naming the run and both files
        dup = os.path.join(self.tmp, "dup.csv")
        with open(dup, "w", newline="") as f:
            csv.writer(f, lineterminator="\n").writerows([rows[0], next(r for r in rows[1:] if r[0] == "sphere-2")])
        r = study("tables", *parts, dup, "--claims", self.claims)
        self.assertEqual(r.returncode, 2)
        self.assertEqual(r.stderr.count("\n"), 1)
        self.assertIn("part-sphere-2.csv", r.stderr)
        self.assertIn("dup.csv", r.stderr)
        self.assertIn("sphere-2/", r.stderr)

    def test_the_readme_block_is_the_published_data(self):
        # the README's results block is what the script makes of data/study/ now: a run landed
        # without regenerating it (or an edit by hand) fails here
        import glob
        with open(os.path.join(SOURCE, "README.md"), encoding="utf-8") as f:
            readme = f.read()
        begin, end = "<!-- study_results.py: begin -->\n", "<!-- study_results.py: end -->"
        block = readme[readme.index(begin) + len(begin):readme.index(end)]
        files = [os.path.join(SOURCE, "data", "study", "runs.csv")] + sorted(
            glob.glob(os.path.join(SOURCE, "data", "study", "fluid", "*.csv")))
        r = study("tables", *files, "--harness", HARNESS)
        self.assertEqual(r.returncode, 0, r.stderr)
        self.assertEqual(block, r.stdout, "README's block is stale: rerun scripts/study_results.py tables "
                         "data/study/runs.csv data/study/fluid/*.csv --harness build/bin/harness --update README.md")

    def test_update_replaces_its_block_only(self):
        readme = os.path.join(self.tmp, "README.md")
        with open(readme, "w") as f:
            f.write("# x\n\n<!-- study_results.py: begin -->\nOLD-TEXT\n<!-- study_results.py: end -->\n\nkept\n")
        r = study("tables", self.csv, "--claims", self.claims, "--update", readme)
        self.assertEqual(r.returncode, 0, r.stderr)
        with open(readme) as f:
            text = f.read()
        self.assertTrue(text.startswith("# x\n\n<!-- study_results.py: begin -->\nMedian final best loss"))
        self.assertTrue(text.endswith("<!-- study_results.py: end -->\n\nkept\n"))
        self.assertNotIn("OLD-TEXT", text)
        # no block: refused, the file as it was
        with open(readme, "w") as f:
            f.write("# no block\n")
        r = study("tables", self.csv, "--update", readme)
        self.assertEqual(r.returncode, 2)
        self.assertEqual(r.stderr.count("\n"), 1)
        with open(readme) as f:
            self.assertEqual(f.read(), "# no block\n")

    def test_export_never_writes_over_a_file(self):
        with open(self.csv, "rb") as f:
            before = f.read()
        r = study("export", self.db, self.csv)
        self.assertEqual(r.returncode, 2)
        self.assertIn("exists", r.stderr)
        with open(self.csv, "rb") as f:
            self.assertEqual(f.read(), before)
        r = study("tables", os.path.join(self.tmp, "absent.csv"))
        self.assertEqual(r.returncode, 2)
        self.assertIn("absent.csv", r.stderr)


if __name__ == "__main__":
    unittest.main()
