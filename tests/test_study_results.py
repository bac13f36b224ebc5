#!/usr/bin/python3
"""scripts/study_results.py on a small real database (ctest study_results): the runs CSV keeps
every run and its floats to the bit, and the claims verdicts and medians made from the CSV are
those made from the database.

    /usr/bin/python3 tests/test_study_results.py BUILD_DIR SOURCE_DIR
"""
import csv
import math
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


def write_claims(path, mode, rows):
    """Claims rows in paper_claims.csv's columns, appended to `path` ("a") or as a new file ("w")."""
    with open(path, mode, newline="", encoding="utf-8") as f:
        csv.writer(f, lineterminator="\n").writerows(rows)


class TempDirCase(unittest.TestCase):
    """A test class with a fresh folder cls.tmp, made by setUpClass (a subclass's calls it first)
    and removed after its last test."""

    @classmethod
    def setUpClass(cls):
        cls.tmp = tempfile.mkdtemp()

    @classmethod
    def tearDownClass(cls):
        shutil.rmtree(cls.tmp)


def exported(tmp, db):
    """The runs CSV of `db`, written by `study_results.py export` into `tmp`."""
    out = os.path.join(tmp, "runs.csv")
    r = study("export", db, out)
    assert r.returncode == 0, r.stderr
    return out


class StudyResults(TempDirCase):
    @classmethod
    def setUpClass(cls):
        super().setUpClass()
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
        write_claims(cls.claims, "a", [
            ["lifts", "cartpole1", "metric_most", "cmaes", "", "0.5", "cmaes lifts", "t", ""],
            ["sphere", "sphere-2", "a_below_b", "cmaes", "random bo", "", "cmaes first", "t", ""]])
        cls.csv = exported(cls.tmp, cls.db)

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

    def test_the_results_block_is_the_published_data(self):
        # docs/results.md's results block is what the script makes of data/study/ now: a run landed
        # without regenerating it (or an edit by hand) fails here
        import glob
        with open(os.path.join(SOURCE, "docs", "results.md"), encoding="utf-8") as f:
            readme = f.read()
        begin, end = "<!-- study_results.py: begin -->\n", "<!-- study_results.py: end -->"
        block = readme[readme.index(begin) + len(begin):readme.index(end)]
        files = [os.path.join(SOURCE, "data", "study", "runs.csv")] + sorted(
            glob.glob(os.path.join(SOURCE, "data", "study", "*", "*.csv")))
        r = study("tables", *files, "--harness", HARNESS)
        self.assertEqual(r.returncode, 0, r.stderr)
        self.assertEqual(block, r.stdout, "docs/results.md's block is stale: rerun scripts/study_results.py tables "
                         "data/study/runs.csv data/study/*/*.csv --harness build/bin/harness --update docs/results.md")

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


# One-sided Mann-Whitney p of 5 tied copies of one value against 5 higher values, as scipy gives
# it with ties (normal approximation, tie-corrected variance, continuity correction 0.5): U = 0,
# mean 12.5, variance 25/12 x (11 - (5^3 - 5) / (10 x 9)), z = (0.5 - 12.5) / sd; p = Phi(z)
_SD = math.sqrt(25 / 12 * (11 - (5 ** 3 - 5) / (10 * 9)))
MANY_TIES_P = 0.5 * math.erfc(-((0.5 - 12.5) / _SD) / math.sqrt(2))   # 0.00375


class SeedsThatAreOneRun(TempDirCase):
    """An (env, optimizer) whose seeds are one run counts as one sample: on a real database of
    sphere-2 x gd, nlopt-direct-l (never draw in 200 episodes: one run), nlopt-lbfgs, nlopt-bobyqa
    (every seed ends at 0.0, reached before their first draw, but their runs differ after it: a tie,
    not one run) and random, 5 seeds x 200 episodes."""

    @classmethod
    def setUpClass(cls):
        super().setUpClass()
        cls.db = os.path.join(cls.tmp, "one-run.sqlite")
        subprocess.run([HARNESS, "--env", "sphere-2", "--optimizer", "gd,nlopt-direct-l,nlopt-lbfgs,nlopt-bobyqa,random",
                        "--seeds", "5", "--budget", "200", "--quiet", "--db", cls.db], check=True)
        cls.claims = os.path.join(cls.tmp, "claims.csv")
        write_claims(cls.claims, "w", [
            ["id", "env", "kind", "a", "b", "threshold", "statement", "source", "note"],
            ["gd-first", "sphere-2", "a_below_b", "gd", "random", "", "s", "t", ""],
            ["both-first", "sphere-2", "a_below_b", "gd nlopt-direct-l", "random", "", "s", "t", ""],
            ["order", "sphere-2", "a_below_b", "gd", "nlopt-direct-l", "", "s", "t", ""],
            ["tie", "sphere-2", "not_significant", "nlopt-lbfgs", "nlopt-bobyqa", "", "s", "t", ""]])
        cls.csv = exported(cls.tmp, cls.db)

    def one_run(self, data):
        from dsb_report import stats
        p, = data_mod.main_panels(data)
        return {o for o in p.optimizers if stats.seed_free(p, o)}

    def test_detected_from_the_recorded_prefix_not_from_ties(self):
        con = sqlite3.connect(self.db)
        rows = con.execute("SELECT optimizer, seed_free_episodes, episodes, best_loss FROM runs").fetchall()
        free = {o: set() for o, *_ in rows}
        for o, f, n, _ in rows:
            free[o].add(f == n)
        self.assertEqual({o for o, v in free.items() if v == {True}}, {"gd", "nlopt-direct-l"})
        # lbfgs and bobyqa: every seed at 0.0, their prefixes 3 and 35 of 200 episodes
        for o, f, n, b in rows:
            if o in ("nlopt-lbfgs", "nlopt-bobyqa"):
                self.assertEqual(b, 0.0)
                self.assertLess(f, n)
        self.assertEqual(self.one_run(data_mod.load(self.db)), {"gd", "nlopt-direct-l"})
        self.assertEqual(self.one_run(runs_csv.load(self.csv)), {"gd", "nlopt-direct-l"})
        with open(self.csv, newline="") as f:
            got = {(r["optimizer"], r["seed"]): r["seed_free_episodes"] for r in csv.DictReader(f)}
        con_rows = con.execute("SELECT optimizer, seed, seed_free_episodes FROM runs").fetchall()
        self.assertEqual(got, {(o, str(s)): str(f) for o, s, f in con_rows})

    def test_a_sample_against_one_run_is_a_sign_test(self):
        from dsb_report import stats
        for data in (data_mod.load(self.db), runs_csv.load(self.csv)):
            verdicts, comps = claims_mod.evaluate(claims_mod.load(self.claims), data_mod.main_panels(data), data.runs)
            v = verdicts.set_index("id")
            c = {(r["id"], r["a"], r["b"]): r for _, r in comps.iterrows()}
            # gd's one run (9.3e-11) below random's 5 seeds (0.019-0.44): all 5 of 5 on the tested
            # side, P(Bin(5, 1/2) >= 5) = 1/32 exactly; five copies of gd as a Mann-Whitney sample
            # would have claimed 0.0037 (U = 0 with gd's five tied: MANY_TIES_P)
            g = c[("gd-first", "gd", "random")]
            self.assertEqual((g["test"], g["n_a"], g["n_b"], g["p_raw"], g["p_holm"]), ("sign", 1, 5, 1 / 32, 1 / 32))
            self.assertEqual(v.loc["gd-first", "verdict"], "holds")
            p, = data_mod.main_panels(data)
            self.assertAlmostEqual(stats.mwu_p(stats.final_values(p, "gd"), stats.final_values(p, "random"), "less"),
                                   MANY_TIES_P, places=12)
            # two sign tests, Holm: 2 x 1/32 = 0.0625 >= 0.05 whatever the data: needs 6 seeds (2/64),
            # so the claim asks for a sixth seed of each of its three optimizers (gd's and DIRECT-L's
            # replay their first seed's run)
            for a in ("gd", "nlopt-direct-l"):
                self.assertEqual(c[("both-first", a, "random")]["p_raw"], 1 / 32)
                self.assertEqual(c[("both-first", a, "random")]["p_holm"], 2 / 32)
            self.assertEqual((v.loc["both-first", "verdict"], v.loc["both-first", "min_n"]),
                             ("runs missing: 15 of 18 done", 6))
            self.assertIn("Gd 5 seeds = 1 run vs random 5: with 2 comparison(s) the smallest reachable Holm p is "
                          "0.0625 >= 0.05; needs >= 6 seeds per optimizer.", v.loc["both-first", "reason"])
            self.assertIn("exact sign test for gd vs random, nlopt-direct-l vs random", v.loc["both-first", "test"])
            # two single runs: gd's 9.3e-11 below DIRECT-L's 4.1e-8 is certain, p 0
            o = c[("order", "gd", "nlopt-direct-l")]
            self.assertEqual((o["test"], o["p_raw"]), ("order", 0.0))
            self.assertEqual(v.loc["order", "verdict"], "holds")
            # a tie is not one run: lbfgs's and bobyqa's five 0.0 stay five samples each
            t = c[("tie", "nlopt-lbfgs", "nlopt-bobyqa")]
            self.assertEqual((t["test"], t["n_a"], t["n_b"], t["p_raw"]), ("mann-whitney", 5, 5, 1.0))

    def test_tables_name_the_cells_and_a_csv_without_the_record_counts_seeds(self):
        r = study("tables", self.csv, "--claims", self.claims)
        self.assertEqual(r.returncode, 0, r.stderr)
        self.assertIn("Seeds that are one run (every run recorded seed-free over all its episodes, so each counts "
                      "once in the tests: the other side's seeds against its value by the exact sign test): "
                      "sphere-2: gd, nlopt-direct-l.", r.stdout)
        self.assertIn("| gd-first | sphere-2 | holds |", r.stdout)
        # a runs CSV written before the column (and before results_versions, the last one): nothing
        # recorded, so no seeds are one run (equal losses alone never make them so) and gd's five
        # seeds are five samples again
        old = os.path.join(self.tmp, "old.csv")
        with open(self.csv, newline="") as f, open(old, "w", newline="") as g:
            w = csv.writer(g, lineterminator="\n")
            for row in csv.reader(f):
                w.writerow(row[:-2])
        with open(old) as f:
            self.assertNotIn("seed_free_episodes", f.readline())
        data = runs_csv.load(old)
        self.assertEqual(self.one_run(data), set())
        _, comps = claims_mod.evaluate(claims_mod.load(self.claims), data_mod.main_panels(data), data.runs)
        g = comps[(comps["id"] == "gd-first")].iloc[0]
        self.assertEqual((g["test"], g["n_a"]), ("mann-whitney", 5))
        self.assertAlmostEqual(g["p_raw"], MANY_TIES_P, places=12)
        # record-seed-free fills the column back from a rerun's database: the export byte for byte,
        # but for results_versions, which it does not add (the old file names no versions)
        back = os.path.join(self.tmp, "back.csv")
        r = study("record-seed-free", old, self.db, back)
        self.assertEqual(r.returncode, 0, r.stderr)
        self.assertIn("25 of 25 runs recorded", r.stdout)
        with open(self.csv, newline="") as g:
            expected = "".join(",".join(row[:-1]) + "\n" for row in csv.reader(g))
        with open(back, newline="") as f:
            self.assertEqual(f.read(), expected)
        # a run whose loss is not the database's is not the same run: refused, nothing written
        with open(old, newline="") as f:
            rows = list(csv.reader(f))
        rows[1][6] = repr(float(rows[1][6]) * (1 + 2 ** -50))
        changed = os.path.join(self.tmp, "changed.csv")
        with open(changed, "w", newline="") as f:
            csv.writer(f, lineterminator="\n").writerows(rows)
        bad = os.path.join(self.tmp, "bad.csv")
        r = study("record-seed-free", changed, self.db, bad)
        self.assertEqual(r.returncode, 2)
        self.assertEqual(r.stderr.count("\n"), 1)
        self.assertIn(f"run sphere-2/{rows[1][1]}/{rows[1][2]}/200: best loss", r.stderr)
        self.assertFalse(os.path.exists(bad))
        r = study("record-seed-free", old, self.db, back)   # never over a file
        self.assertEqual(r.returncode, 2)
        self.assertIn("exists", r.stderr)


if __name__ == "__main__":
    unittest.main()
