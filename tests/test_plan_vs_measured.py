#!/usr/bin/env python3
"""scripts/plan_vs_measured.py on real piece databases (the harness's, on sphere-2) with a plan,
a calibration, a CPU log and runs' CPU seconds written here, so every figure it prints is known.

    python3 tests/test_plan_vs_measured.py SOURCE_DIR HARNESS
"""
import csv
import datetime
import json
import os
import shutil
import sqlite3
import subprocess
import sys
import tempfile
import unittest

SOURCE = sys.argv.pop(1) if len(sys.argv) > 2 else os.path.join(os.path.dirname(__file__), "..")
HARNESS = sys.argv.pop(1) if len(sys.argv) > 1 else os.path.join(SOURCE, "build", "bin", "harness")
SCRIPT = os.path.join(SOURCE, "scripts", "plan_vs_measured.py")
BUDGET = 30


def stretch_run(db, seconds, cpu_s=None):
    """The run's start and finish (unix), its finish moved `seconds` after its start (a sphere-2
    run takes a second; the pieces this script is for take an hour), and its gradient episodes.
    Its runs.cpu_s becomes `cpu_s` (None: NULL, as a harness before schema 6 left it)."""
    con = sqlite3.connect(db)
    try:
        start, = con.execute("SELECT started_at FROM runs").fetchone()
        start = int(datetime.datetime.strptime(start, "%Y-%m-%dT%H:%M:%SZ")
                    .replace(tzinfo=datetime.timezone.utc).timestamp())
        end = datetime.datetime.fromtimestamp(start + seconds, datetime.timezone.utc).strftime("%Y-%m-%dT%H:%M:%SZ")
        con.execute("UPDATE runs SET finished_at = ?, cpu_s = ?", (end, cpu_s))
        con.commit()
        grad, = con.execute("SELECT SUM(used_grad) FROM evals").fetchone()
    finally:
        con.close()
    return start, start + seconds, grad


class PlanVsMeasured(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.tmp = tempfile.TemporaryDirectory()
        cls.dir = cls.tmp.name
        cls.pieces = os.path.join(cls.dir, "pieces")
        os.mkdir(cls.pieces)
        cls.times = {}
        for opt in ("cmaes", "boleap", "random", "gd"):
            db = os.path.join(cls.pieces, f"sphere-2__{opt}.sqlite")
            r = subprocess.run([HARNESS, "--env", "sphere-2", "--optimizer", opt, "--seeds", "1", "--budget",
                                str(BUDGET), "--jobs", "1", "--quiet", "--db", db], capture_output=True, text=True)
            assert r.returncode == 0, r.stderr
            if opt == "gd":
                # the harness stores each run's CPU seconds (schema 6): what it wrote is a number
                con = sqlite3.connect(db)
                cls.gd_stored_cpu, = con.execute("SELECT cpu_s FROM runs").fetchone()
                con.close()
            # gd's piece measured by the database (90 s); the others as written before schema 6
            cls.times[opt] = stretch_run(db, 1000, 90.0 if opt == "gd" else None)
        # a sharing group: nlopt-lbfgs's seed 1 replays seed 0's episodes before its first random
        # draw (its restart), then simulates its own; both runs in one piece, measured by the database
        db = os.path.join(cls.pieces, "sphere-2__nlopt-lbfgs.sqlite")
        r = subprocess.run([HARNESS, "--env", "sphere-2", "--optimizer", "nlopt-lbfgs", "--seeds", "2", "--budget",
                            str(BUDGET), "--jobs", "1", "--quiet", "--db", db], capture_output=True, text=True)
        assert r.returncode == 0, r.stderr
        con = sqlite3.connect(db)
        con.execute("UPDATE runs SET cpu_s = 40.0")
        con.commit()
        cls.lbfgs_shared, = con.execute("SELECT shared_episodes FROM runs WHERE seed = 1").fetchone()
        cls.lbfgs_grad = dict(con.execute("SELECT r.seed, SUM(e.used_grad) FROM evals e JOIN runs r USING (run_id) "
                                          "GROUP BY r.seed").fetchall())
        con.close()
        # the plan (harness plan --runs-csv's columns), a calibration of 1 s forward, 3 s gradient
        cls.plan = os.path.join(cls.dir, "plan.csv")
        with open(cls.plan, "w", newline="") as f:
            w = csv.writer(f)
            w.writerow(["env", "optimizer", "seed", "budget", "planned_s", "source", "start_rank", "lead_seed"])
            for rank, (opt, s) in enumerate((("cmaes", 100.0), ("boleap", 200.0), ("random", 50.0), ("gd", 60.0))):
                w.writerow(["sphere-2", opt, 0, BUDGET, s, "model", rank, ""])
            w.writerow(["sphere-2", "nlopt-lbfgs", 0, BUDGET, 90.0, "model", 4, ""])
            w.writerow(["sphere-2", "nlopt-lbfgs", 1, BUDGET, 70.0, "model", 5, 0])
        cls.costs = os.path.join(cls.dir, "costs.json")
        with open(cls.costs, "w") as f:
            json.dump({"costs": {"sphere-2|abc|0.1.0+x|CPU": {"forward_s": 1.0, "gradient_s": 3.0}}}, f)
        # CPU samples: cmaes one process, 150 s; boleap two (stopped and resumed), 120 + 180 s; random
        # a process first seen 60 s after its run started (an unseen earlier one may have run)
        cls.cpu = os.path.join(cls.dir, "cpu.csv")
        c0, c1, _ = cls.times["cmaes"]
        b0, b1, _ = cls.times["boleap"]
        r0, r1, _ = cls.times["random"]
        with open(cls.cpu, "w") as f:
            f.write("unix_time,pid,piece,cpu_s,started_at_unix\n")
            f.write(f"{c0 + 5},11,sphere-2__cmaes,2,{c0}\n{c1},11,sphere-2__cmaes,150,{c0}\n")
            f.write(f"{b0 + 5},21,sphere-2__boleap,100,{b0}\n{b0 + 9},21,sphere-2__boleap,120,{b0}\n")
            f.write(f"{b1 - 3},22,sphere-2__boleap,180,{b0 + 500}\n")
            f.write(f"{r1},31,sphere-2__random,40,{r0 + 60}\n")

    @classmethod
    def tearDownClass(cls):
        cls.tmp.cleanup()

    def script(self, *extra, cpu=True):
        return subprocess.run([sys.executable, SCRIPT, "--plan", self.plan, *(["--cpu", self.cpu] if cpu else []),
                               "--costs", self.costs, "--pieces", self.pieces, *extra], capture_output=True, text=True)

    def test_rows(self):
        out = os.path.join(self.dir, "rows.csv")
        r = self.script("--share", "boleap=0.5", "--out", out, "--markdown")
        self.assertEqual(r.returncode, 0, r.stderr)
        with open(out, newline="") as f:
            rows = {row["optimizer"]: row for row in csv.DictReader(f)}
        self.assertEqual(rows["cmaes"]["measured"], "1")
        self.assertEqual(rows["cmaes"]["cpu_from"], "monitor")
        self.assertAlmostEqual(float(rows["cmaes"]["cpu_s"]), 150.0)
        self.assertAlmostEqual(float(rows["cmaes"]["ratio"]), 1.5)
        self.assertEqual(rows["cmaes"]["grad_episodes"], "0")
        # boleap: both processes counted; its plan at the run's own share of gradient episodes is
        # the plan's own time (200 - 30 x (0.5 x 3 + 0.5 x 1) = 140) plus its episodes at 3 s and 1 s
        grad = self.times["boleap"][2]
        self.assertGreater(grad, 0)
        self.assertLess(grad, BUDGET)
        self.assertEqual(rows["boleap"]["grad_episodes"], str(grad))
        self.assertAlmostEqual(float(rows["boleap"]["cpu_s"]), 300.0)
        self.assertAlmostEqual(float(rows["boleap"]["ratio"]), 1.5)
        own_share = 140.0 + 3.0 * grad + 1.0 * (BUDGET - grad)
        self.assertAlmostEqual(float(rows["boleap"]["planned_at_own_share_s"]), own_share, places=2)
        self.assertAlmostEqual(float(rows["boleap"]["ratio_at_own_share"]), round(300.0 / own_share, 3))
        # random: its first process began after its run: unmeasured, no figure
        self.assertEqual(rows["random"]["measured"], "0")
        self.assertEqual(rows["random"]["cpu_s"], "")
        # gd: its runs' cpu_s, no process of it in the log
        self.assertEqual(rows["gd"]["cpu_from"], "database")
        self.assertEqual(rows["gd"]["processes"], "0")
        self.assertAlmostEqual(float(rows["gd"]["cpu_s"]), 90.0)
        self.assertAlmostEqual(float(rows["gd"]["ratio"]), 1.5)
        # the family table: forward episodes counts cmaes (measured) and not random
        self.assertIn("| forward episodes (cmaes) | 1 (2) | 100 | 150 | 1.50 |", r.stdout)
        self.assertIn("| gp (episodes + GP time) (boleap) | 1 (1) | 200 | 300 | 1.50 |", r.stdout)
        # the gradient family: gd (60 s planned, 90 s CPU) and the L-BFGS group (160 s, 80 s)
        self.assertIn("| gradient episodes (gd, nlopt-lbfgs) | 2 (2) | 220 | 170 | 0.77 | 0.50-1.50 |", r.stdout)

    def test_a_sharing_groups_later_seed_counts_only_the_episodes_it_simulated(self):
        # every L-BFGS episode is a gradient one; seed 1 shares a prefix and then differs
        self.assertEqual(self.lbfgs_grad, {0: BUDGET, 1: BUDGET})
        self.assertGreater(self.lbfgs_shared, 0)
        self.assertLess(self.lbfgs_shared, BUDGET)
        out = os.path.join(self.dir, "lbfgs.csv")
        # no --share for nlopt-lbfgs: all its simulated episodes are gradient ones, not a mix
        r = self.script("--share", "boleap=0.5", "--out", out)
        self.assertEqual(r.returncode, 0, r.stderr)
        with open(out, newline="") as f:
            row = {row["optimizer"]: row for row in csv.DictReader(f)}["nlopt-lbfgs"]
        simulated = 2 * BUDGET - self.lbfgs_shared
        self.assertEqual((row["seeds"], row["status"], row["cpu_from"]), ("0 1", "done", "database"))
        self.assertEqual((row["episodes"], row["grad_episodes"]), (str(simulated), str(simulated)))
        self.assertAlmostEqual(float(row["planned_s"]), 160.0)
        self.assertAlmostEqual(float(row["cpu_s"]), 80.0)
        self.assertAlmostEqual(float(row["ratio"]), 0.5)
        self.assertAlmostEqual(float(row["planned_at_own_share_s"]), 160.0)

    def test_a_running_sharing_group_is_against_each_runs_plan_pro_rata(self):
        # the L-BFGS group while its seed 1 runs: seed 0 done (its whole 90 s), seed 1 halfway
        # through the episodes it simulates past its shared prefix (about half of its 70 s)
        pieces = os.path.join(self.dir, "running-pieces")
        os.mkdir(pieces)
        db = os.path.join(pieces, "sphere-2__nlopt-lbfgs.sqlite")
        shutil.copyfile(os.path.join(self.pieces, "sphere-2__nlopt-lbfgs.sqlite"), db)
        own = BUDGET - self.lbfgs_shared
        cut = self.lbfgs_shared + own // 2
        con = sqlite3.connect(db)
        run_id, = con.execute("SELECT run_id FROM runs WHERE seed = 1").fetchone()
        con.execute("DELETE FROM evals WHERE run_id = ? AND episode >= ?", (run_id, cut))
        con.execute("UPDATE runs SET status = 'running', episodes = ?, finished_at = NULL, cpu_s = 20.0 "
                    "WHERE run_id = ?", (cut, run_id))
        con.commit()
        con.close()
        out = os.path.join(self.dir, "running.csv")
        r = subprocess.run([sys.executable, SCRIPT, "--plan", self.plan, "--costs", self.costs, "--pieces", pieces,
                            "--out", out], capture_output=True, text=True)
        self.assertEqual(r.returncode, 0, r.stderr)
        with open(out, newline="") as f:
            row = next(csv.DictReader(f))
        self.assertEqual((row["status"], row["episodes"]), ("running", str(BUDGET + own // 2)))
        self.assertAlmostEqual(float(row["cpu_s"]), 60.0)
        # 60 s against 90 + 70 x (its own episodes so far / its own episodes), about 125 s (the lead's
        # budget alone as the whole, as before, had made it 60 / 160)
        self.assertAlmostEqual(float(row["ratio"]), round(60.0 / (90.0 + 70.0 * (own // 2) / own), 3))

    def test_the_harness_stores_a_runs_cpu_and_pieces_with_it_need_no_monitor(self):
        self.assertIsInstance(self.gd_stored_cpu, float)
        self.assertGreater(self.gd_stored_cpu, 0.0)
        out = os.path.join(self.dir, "no-monitor.csv")
        r = self.script("--share", "boleap=0.5", "--out", out, cpu=False)
        self.assertEqual(r.returncode, 0, r.stderr)
        with open(out, newline="") as f:
            rows = {row["optimizer"]: row for row in csv.DictReader(f)}
        self.assertEqual((rows["gd"]["measured"], rows["gd"]["cpu_from"], rows["gd"]["cpu_s"]), ("1", "database", "90.0"))
        for opt in ("cmaes", "boleap", "random"):
            self.assertEqual((rows[opt]["measured"], rows[opt]["cpu_from"], rows[opt]["cpu_s"]), ("0", "", ""), opt)

    def test_mixed_optimizer_needs_its_share(self):
        r = self.script()
        self.assertEqual(r.returncode, 2)
        self.assertIn("--share boleap=G", r.stderr)

    def test_bad_input_exits_2_and_writes_nothing(self):
        existing = os.path.join(self.dir, "existing.csv")
        with open(existing, "w") as f:
            f.write("mine\n")
        r = self.script("--share", "boleap=0.5", "--out", existing)
        self.assertEqual(r.returncode, 2)
        self.assertIn(existing, r.stderr)
        with open(existing) as f:
            self.assertEqual(f.read(), "mine\n")
        r = self.script("--share", "boleap=1.5")
        self.assertEqual(r.returncode, 2)
        self.assertIn("boleap=1.5", r.stderr)


if __name__ == "__main__":
    unittest.main()
