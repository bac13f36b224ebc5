#!/usr/bin/python3
"""Test of reports/make_report.py on a small real harness database (standard library only).

usage: /usr/bin/python3 reports/test_make_report.py DB_PATH
   or: DSB_REPORT_DB=DB_PATH /usr/bin/python3 -m unittest reports/test_make_report.py
       (without a database it makes one with build/bin/harness, or $DSB_HARNESS, if it exists)

The database is never written: every case works on a copy in a temporary folder. The generator is
run with the same interpreter as this test (sys.executable). Prints 'N passed, M failed' last and
exits non-zero on any failure. DSB_REPORT_KEEP=1 keeps the temporary folders.
"""
import atexit
import csv
import math
import os
import re
import shutil
import sqlite3
import statistics
import subprocess
import sys
import tempfile
import unittest

HERE = os.path.dirname(os.path.abspath(__file__))
SCRIPT = os.path.join(HERE, "make_report.py")
_DB = {"path": None}


def db_path():
    """The database under test: argv, $DSB_REPORT_DB, or one made now with the harness."""
    if _DB["path"]:
        return _DB["path"]
    env = os.environ.get("DSB_REPORT_DB")
    if env:
        _DB["path"] = env
        return env
    harness = os.environ.get("DSB_HARNESS",
                             os.path.join(os.path.dirname(HERE), "build", "bin", "harness"))
    if not os.access(harness, os.X_OK):
        raise unittest.SkipTest("no database: pass DB_PATH or set DSB_REPORT_DB")
    tmp = tempfile.mkdtemp(prefix="dsb_report_db_")
    if not os.environ.get("DSB_REPORT_KEEP"):
        atexit.register(shutil.rmtree, tmp, True)
    out = os.path.join(tmp, "small.sqlite")
    subprocess.run([harness, "--env", "sphere-2,branin", "--optimizer", "random,cmaes,gd",
                    "--seeds", "3", "--budget", "20", "--db", out, "--quiet"], check=True)
    _DB["path"] = out
    return out


def copy_db(dst):
    """Consistent copy (WAL included) through SQLite's backup API; the source is opened read-only."""
    src = sqlite3.connect("file:" + os.path.abspath(db_path()) + "?mode=ro", uri=True)
    out = sqlite3.connect(dst)
    src.backup(out)
    src.close()
    out.close()
    return dst


def slug(text):
    return re.sub(r"[^A-Za-z0-9._-]", "_", text)


def run_report(db, out, *extra, python=(sys.executable,)):
    return subprocess.run([*python, SCRIPT, "--db", db, "--out", out, *extra],
                          capture_output=True, text=True, timeout=600)


def write_sphere_landscape(directory, n=15, checked=False):
    """sphere on dims 0, 1 of a 2-D box: loss x0^2 + x1^2, gradient 2 x, on an n x n grid.
    checked: with the columns of `harness landscape --check-step` (sphere-2_1_0.csv), where the
    points of the first row (a = 0) are marked as disagreeing."""
    path = os.path.join(directory, "sphere-2_1_0.csv" if checked else "sphere-2_0_1.csv")
    with open(path, "w", newline="") as f:
        w = csv.writer(f, lineterminator="\n")
        w.writerow(["i", "j", "xi", "xj", "loss", "grad_i", "grad_j"]
                   + (["fd_i", "fd_j", "rel_err", "agrees"] if checked else []))
        for a in range(n):
            for b in range(n):
                xi, xj = -1 + 2 * a / (n - 1), -1 + 2 * b / (n - 1)
                row = [0, 1, repr(xi), repr(xj), repr(xi * xi + xj * xj), repr(2 * xi), repr(2 * xj)]
                if checked:
                    row += [repr(2 * xi), repr(2 * xj), "0.5" if a == 0 else "0", 0 if a == 0 else 1]
                w.writerow(row)
    return path


def read_csv(path):
    with open(path, newline="", encoding="utf-8") as f:
        return list(csv.DictReader(f))


def cells(db):
    """(env, budget) -> optimizer -> list of best_loss of 'done' runs, straight from SQLite."""
    con = sqlite3.connect(db)
    out = {}
    for env, budget, opt, best in con.execute(
            "SELECT env, budget, optimizer, best_loss FROM runs WHERE status='done'"):
        out.setdefault((env, budget), {}).setdefault(opt, []).append(best)
    con.close()
    return out


def final_csv_name(env, budget, all_keys):
    several = sum(1 for e, _ in all_keys if e == env) > 1
    return f"final_{slug(f'{env}_b{budget}' if several else env)}.csv"


def html_rows(html):
    return re.findall(r"<tr[^>]*>(.*?)</tr>", html, flags=re.S)


def row_cells(row):
    return [re.sub(r"<[^>]+>", "", c).strip() for c in re.findall(r"<td[^>]*>(.*?)</td>", row, re.S)]


class ReportCase(unittest.TestCase):
    """Runs the generator once on a copy of the database (after `modify`, if any)."""
    modify = None

    @classmethod
    def setUpClass(cls):
        cls.tmp = tempfile.mkdtemp(prefix="dsb_report_test_")
        cls.db = copy_db(os.path.join(cls.tmp, "copy.sqlite"))
        if cls.modify:
            con = sqlite3.connect(cls.db)
            cls.modify(con)
            con.commit()
            con.close()
        cls.land = os.path.join(cls.tmp, "landscapes")
        os.makedirs(cls.land)
        write_sphere_landscape(cls.land)
        write_sphere_landscape(cls.land, checked=True)
        cls.out = os.path.join(cls.tmp, "report")
        cls.proc = run_report(cls.db, cls.out, "--landscapes", cls.land, "--build-type", "TestBuild")
        if cls.proc.returncode != 0:
            raise AssertionError(f"make_report exited {cls.proc.returncode}:\n{cls.proc.stderr}")
        with open(os.path.join(cls.out, "index.html"), encoding="utf-8") as f:
            cls.html = f.read()
        cls.cells = cells(cls.db)

    @classmethod
    def tearDownClass(cls):
        if not os.environ.get("DSB_REPORT_KEEP"):
            shutil.rmtree(cls.tmp, ignore_errors=True)

    def file(self, name):
        return os.path.join(self.out, name)

    def assert_nonempty(self, name):
        p = self.file(name)
        self.assertTrue(os.path.isfile(p), f"{name} missing")
        self.assertGreater(os.path.getsize(p), 0, f"{name} empty")

    def check_medians(self):
        keys = list(self.cells)
        for (env, budget), per_opt in self.cells.items():
            rows = {r["optimizer"]: r for r in read_csv(self.file(final_csv_name(env, budget, keys)))}
            for opt, vals in per_opt.items():
                vals = [math.inf if v is None else v for v in vals]
                want = statistics.median(vals)
                got = float(rows[opt]["median"])
                self.assertTrue(math.isclose(got, want, rel_tol=1e-12, abs_tol=1e-300),
                                f"{env}/{opt}: median {got} != {want} from sqlite")
                self.assertEqual(int(rows[opt]["n_seeds"]), len(vals), f"{env}/{opt}: n_seeds")


class TestReport(ReportCase):
    def test_checked_landscape_marks_and_counts_disagreeing_points(self):
        # sphere-2_1_0.csv: 15 of 225 points flagged as disagreeing (the first row)
        self.assert_nonempty("landscape_sphere-2_1_0.png")
        self.assertIn("gradient agrees with central differences at 210 of 225 points", self.html)
        # the unchecked slice says nothing about agreement
        self.assertEqual(self.html.count("gradient agrees with central differences at"), 1)

    def test_promised_files_exist(self):
        for name in ["index.html", "summary.md", "ranks.png", "ranks.csv", "ecdf.png", "ecdf.csv",
                     "significance.csv", "missing.csv", "landscape_sphere-2_0_1.png"]:
            self.assert_nonempty(name)
        keys = list(self.cells)
        for env, budget in keys:
            csv_name = final_csv_name(env, budget, keys)
            stem = csv_name[len("final_"):-len(".csv")]
            for name in (f"curves_{stem}.png", f"final_{stem}.png", csv_name):
                self.assert_nonempty(name)

    def test_html_references_every_png(self):
        pngs = [f for f in os.listdir(self.out) if f.endswith(".png")]
        self.assertGreater(len(pngs), 3)
        for p in pngs:
            self.assertIn(f'src="{p}"', self.html, f"{p} not shown in index.html")

    def test_html_self_contained(self):
        self.assertNotIn("<script", self.html.lower())
        for ref in re.findall(r'(?:src|href)="([^"]*)"', self.html):
            self.assertNotRegex(ref, r"^(/|[a-z]+:)", f"non-relative link {ref}")
            if not ref.startswith("#"):
                self.assertTrue(os.path.isfile(self.file(ref)), f"broken link {ref}")

    def test_final_medians_match_sqlite(self):
        self.check_medians()

    def test_significance_table(self):
        rows = read_csv(self.file("significance.csv"))
        for col in ("env", "optimizer", "p_raw", "p_holm", "indistinguishable_from_best"):
            self.assertIn(col, rows[0])
        envs = {e for e, _ in self.cells}
        self.assertEqual({r["env"] for r in rows}, envs)
        for env in envs:
            best = [r for r in rows if r["env"] == env and r["is_best"] == "True"]
            self.assertEqual(len(best), 1, f"{env}: exactly one best")
        for r in rows:
            if r["p_holm"]:
                self.assertGreaterEqual(float(r["p_holm"]), float(r["p_raw"]))
        self.assertIn("0.0079" if "5 seeds" in self.html else "smallest exact two-sided p", self.html)

    def test_missing_matches_grid(self):
        con = sqlite3.connect(self.db)
        runs = con.execute("SELECT env, optimizer, seed, budget, status FROM runs").fetchall()
        con.close()
        max_seed = max(r[2] for r in runs)
        budgets = {}
        for env, _, _, b, _ in runs:
            budgets.setdefault(env, set()).add(b)
        done = {(e, o, s, b) for e, o, s, b, st in runs if st == "done"}
        want = {(e, o, s, b) for e, o in {(r[0], r[1]) for r in runs} for b in budgets[e]
                for s in range(max_seed + 1)} - done
        got = {(r["env"], r["optimizer"], int(r["seed"]), int(r["budget"]))
               for r in read_csv(self.file("missing.csv"))}
        self.assertEqual(got, want)

    def test_provenance(self):
        for text in ("TestBuild", "schema_version", "harness version", "git sha", "host",
                     os.path.abspath(self.db), "report made"):
            self.assertIn(text, self.html)
        with open(self.file("summary.md"), encoding="utf-8") as f:
            md = f.read()
        for env, _ in self.cells:
            self.assertIn(env, md)

    def test_ranks_and_ecdf_tables(self):
        ranks = read_csv(self.file("ranks.csv"))
        opts = {o for per in self.cells.values() for o in per}
        self.assertEqual({r["optimizer"] for r in ranks}, opts)
        for r in ranks:
            self.assertGreaterEqual(float(r["mean_rank"]), 1.0)
        ecdf = read_csv(self.file("ecdf.csv"))
        for r in ecdf:
            self.assertTrue(0.0 <= float(r["fraction_solved"]) <= 1.0)


def _delete_and_fail(con):
    """Delete one done run (with its evals) and mark a run of another pair failed with 'boom'."""
    runs = con.execute("SELECT run_id, env, optimizer, seed, budget FROM runs WHERE status='done' "
                       "ORDER BY run_id").fetchall()
    victim = runs[0]
    other = next(r for r in runs if (r[1], r[2]) != (victim[1], victim[2]))
    con.execute("DELETE FROM evals WHERE run_id=?", (victim[0],))
    con.execute("DELETE FROM runs WHERE run_id=?", (victim[0],))
    con.execute("UPDATE runs SET status='failed', error='boom' WHERE run_id=?", (other[0],))
    TestDeletedAndFailed.deleted = victim[1:]
    TestDeletedAndFailed.failed = other[1:]


class TestDeletedAndFailed(ReportCase):
    modify = staticmethod(_delete_and_fail)

    def missing_row(self, key):
        for r in read_csv(self.file("missing.csv")):
            if (r["env"], r["optimizer"], int(r["seed"]), int(r["budget"])) == tuple(key):
                return r
        self.fail(f"{key} not in missing.csv")

    def html_row_with(self, *texts):
        for row in html_rows(self.html):
            c = row_cells(row)
            if all(str(t) in c for t in texts):
                return c
        self.fail(f"no table row in index.html with {texts}")

    def test_deleted_run_is_missing(self):
        self.assertEqual(self.missing_row(self.deleted)["reason"], "absent")
        self.html_row_with(*self.deleted, "absent")

    def test_failed_run_is_listed_with_error(self):
        r = self.missing_row(self.failed)
        self.assertEqual((r["reason"], r["error"]), ("failed", "boom"))
        self.html_row_with(*self.failed[:3], "boom")
        env, opt, _, budget = self.failed
        keys = list(self.cells)
        rows = {x["optimizer"]: x for x in read_csv(self.file(final_csv_name(env, budget, keys)))}
        self.assertEqual(int(rows[opt]["failed_runs"]), 1)

    def test_medians_exclude_failed_and_deleted(self):
        self.check_medians()


def _set_metric(con):
    """Give branin's episodes a second metric (as PlasticineLab's soft IoU would be); sphere-2 keeps none."""
    con.execute("UPDATE evals SET metric = 0.001 * episode + 0.01 * run_id "
                "WHERE run_id IN (SELECT run_id FROM runs WHERE env = 'branin')")


class TestMetric(ReportCase):
    modify = staticmethod(_set_metric)

    def test_metric_median_is_the_metric_at_each_runs_best_episode(self):
        con = sqlite3.connect(self.db)
        want = {}
        for run_id, opt in con.execute("SELECT run_id, optimizer FROM runs WHERE env = 'branin' AND status = 'done'"):
            ev = con.execute("SELECT loss, metric FROM evals WHERE run_id = ? AND loss IS NOT NULL "
                             "ORDER BY episode", (run_id,)).fetchall()
            best = min(l for l, _ in ev)
            want.setdefault(opt, []).append(next(m for l, m in ev if l == best))
        con.close()
        keys = list(self.cells)
        for env, budget in keys:
            rows = {r["optimizer"]: r for r in read_csv(self.file(final_csv_name(env, budget, keys)))}
            for opt, r in rows.items():
                if env == "branin":
                    self.assertTrue(math.isclose(float(r["metric_median"]), statistics.median(want[opt]),
                                                 rel_tol=1e-12), f"{opt}: {r['metric_median']}")
                else:
                    self.assertEqual(r["metric_median"], "", f"{env}/{opt} has no metric")
        with open(self.file("summary.md"), encoding="utf-8") as f:
            sections = f.read().split("### ")
        branin = [x for x in sections if x.startswith("branin")]
        sphere = [x for x in sections if x.startswith("sphere-2")]
        self.assertTrue(branin and "metric at best (median)" in branin[0])
        self.assertTrue(sphere and "metric at best" not in sphere[0])
        self.assertIn("metric at best (median)", self.html)


class TestBadInput(unittest.TestCase):
    def setUp(self):
        self.tmp = tempfile.mkdtemp(prefix="dsb_report_bad_")

    def tearDown(self):
        shutil.rmtree(self.tmp, ignore_errors=True)

    def assert_one_line_exit_2(self, proc):
        self.assertEqual(proc.returncode, 2, proc.stderr)
        lines = [x for x in proc.stderr.splitlines() if x.strip()]
        self.assertEqual(len(lines), 1, proc.stderr)
        return lines[0]

    def test_bad_db_path(self):
        bad = os.path.join(self.tmp, "no", "such.sqlite")
        line = self.assert_one_line_exit_2(run_report(bad, os.path.join(self.tmp, "out")))
        self.assertIn(bad, line)

    def test_not_a_database(self):
        bad = os.path.join(self.tmp, "text.sqlite")
        with open(bad, "w") as f:
            f.write("this is not a database\n" * 100)
        self.assert_one_line_exit_2(run_report(bad, os.path.join(self.tmp, "out")))

    def test_missing_modules_named(self):
        # -S -E: no site-packages, so pandas & co cannot be imported
        proc = run_report(db_path(), os.path.join(self.tmp, "out"),
                          python=(sys.executable, "-S", "-E"))
        if proc.returncode == 0:
            self.skipTest("the interpreter imports pandas even without site-packages")
        line = self.assert_one_line_exit_2(proc)
        self.assertIn("pandas", line)


def main(argv):
    if len(argv) > 1:
        if argv[1] in ("-h", "--help"):
            print(__doc__)
            return 0
        _DB["path"] = argv[1]
        if not os.path.isfile(argv[1]):
            print(f"test_make_report: no database '{argv[1]}'", file=sys.stderr)
            return 2
    suite = unittest.defaultTestLoader.loadTestsFromModule(sys.modules[__name__])
    result = unittest.TextTestRunner(verbosity=2).run(suite)
    failed = len(result.failures) + len(result.errors) + len(result.unexpectedSuccesses)
    skipped = len(result.skipped)
    passed = result.testsRun - failed - skipped
    print(f"{passed} passed, {failed} failed" + (f", {skipped} skipped" if skipped else ""))
    return 0 if failed == 0 and passed > 0 else 1


if __name__ == "__main__":
    sys.exit(main(sys.argv))
