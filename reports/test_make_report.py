#!/usr/bin/python3
"""Test of reports/make_report.py on a small real harness database (standard library only).

usage: /usr/bin/python3 reports/test_make_report.py DB_PATH
   or: DSB_REPORT_DB=DB_PATH /usr/bin/python3 -m unittest reports/test_make_report.py
       (without a database it makes one with build/bin/harness, or $DSB_HARNESS, if it exists)

The harness ($DSB_HARNESS, else build/bin/harness) is also the generator's --harness: its `list`
tells the claims table which envs exist. The claims tests that need it are skipped without one.

The database is never written: every case works on a copy in a temporary folder. The generator is
run with the same interpreter as this test (sys.executable). Prints 'N passed, M failed' last and
exits non-zero on any failure. DSB_REPORT_KEEP=1 keeps the temporary folders.
"""
import atexit
import csv
import html
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


def harness_path():
    """$DSB_HARNESS, else build/bin/harness of this source tree; None when not executable."""
    harness = os.environ.get("DSB_HARNESS",
                             os.path.join(os.path.dirname(HERE), "build", "bin", "harness"))
    return harness if os.access(harness, os.X_OK) else None


def need_harness():
    harness = harness_path()
    if harness is None:
        raise unittest.SkipTest("no harness binary: set DSB_HARNESS")
    return harness


_REGISTRY = {}


def registry_of_harness():
    """`harness list` of the test's harness (dsb_report.registry), or None without one."""
    harness = harness_path()
    if harness is None:
        return None
    if harness not in _REGISTRY:
        if HERE not in sys.path:
            sys.path.insert(0, HERE)
        from dsb_report import registry
        _REGISTRY[harness] = registry.load(harness)
    return _REGISTRY[harness]


def versions_text(env, optimizer):
    """runs.results_versions of a run of env with optimizer made by the test's harness ('env E,
    optimizer O, run R', from its `harness list`); '' without a harness (the report then judges
    no run stale)."""
    reg = registry_of_harness()
    v = reg.current_versions(env, optimizer) if reg else None
    return "" if v is None else f"env {v[0]}, optimizer {v[1]}, run {v[2]}"


def db_path():
    """The database under test: argv, $DSB_REPORT_DB, or one made now with the harness."""
    if _DB["path"]:
        return _DB["path"]
    env = os.environ.get("DSB_REPORT_DB")
    if env:
        _DB["path"] = env
        return env
    harness = harness_path()
    if harness is None:
        raise unittest.SkipTest("no database: pass DB_PATH or set DSB_REPORT_DB")
    tmp = tempfile.mkdtemp(prefix="dsb_report_db_")
    if not os.environ.get("DSB_REPORT_KEEP"):
        atexit.register(shutil.rmtree, tmp, True)
    out = os.path.join(tmp, "small.sqlite")
    subprocess.run([harness, "--env", "sphere-2,branin", "--optimizer", "random,cmaes,gd",
                    "--seeds", "3", "--budget", "20", "--db", out, "--quiet"], check=True)
    _DB["path"] = out
    return out


def plan_runs_per_env(harness):
    """env -> the runs of `harness plan --all --seeds 1` on it: the optimizers --all runs there."""
    tmp = tempfile.mkdtemp(prefix="dsb_report_plan_")
    try:
        out = subprocess.run([harness, "plan", "--all", "--seeds", "1", "--budget", "1", "--db",
                              os.path.join(tmp, "none.sqlite")], capture_output=True, text=True,
                             check=True, timeout=120).stdout
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    lines = out.splitlines()
    start = next(k for k, x in enumerate(lines) if x.split()[:2] == ["env", "runs"])
    runs = {}
    for x in lines[start + 1:]:
        w = x.split()
        if not w or not w[1].isdigit():
            break
        runs[w[0]] = int(w[1])
    return runs


def copy_db(dst):
    """Consistent copy (WAL included) through SQLite's backup API; the source is opened read-only."""
    src = sqlite3.connect("file:" + os.path.abspath(db_path()) + "?mode=ro", uri=True)
    out = sqlite3.connect(dst)
    src.backup(out)
    src.close()
    out.close()
    return dst


def file_sha256(path):
    import hashlib
    with open(path, "rb") as f:
        return hashlib.sha256(f.read()).hexdigest()


def sidecar_files(folder):
    """The SQLite files (-wal, -shm, -journal) in folder, sorted."""
    return sorted(f for f in os.listdir(folder) if f.endswith(("-wal", "-shm", "-journal")))


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


def png_size(path):
    """(width, height) from a PNG's IHDR; fails on a file that is not a PNG."""
    import struct
    with open(path, "rb") as f:
        head = f.read(24)
    assert head[:8] == b"\x89PNG\r\n\x1a\n" and head[12:16] == b"IHDR", f"{path} is not a PNG"
    return struct.unpack(">II", head[16:24])


FIGURE = re.compile(r'<figure><img src="([^"]*)" alt="([^"]*)"><figcaption>(.*?)</figcaption></figure>', re.S)


def figures_in(page):
    """[(png, alt, caption)] of the <figure>s of an HTML fragment, in order, unescaped."""
    return [(html.unescape(p), html.unescape(a), html.unescape(c)) for p, a, c in FIGURE.findall(page)]


def env_section(page, stem):
    """The HTML of the env section id="env-<stem>", up to the next <h3> or <h2>."""
    return re.split(r"<h[23]", page.split(f'id="env-{stem}"', 1)[1], maxsplit=1)[0]


def chart_modules():
    """dsb_report's charts and plots modules (the registry of the report's charts)."""
    if HERE not in sys.path:
        sys.path.insert(0, HERE)
    from dsb_report import charts, plots
    return charts, plots


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
    """Runs the generator once on a copy of the database (after `modify`, if any), with `extra`
    arguments (a function of the temporary folder) if given."""
    modify = None
    extra = None

    @classmethod
    def setUpClass(cls):
        cls.tmp = tempfile.mkdtemp(prefix="dsb_report_test_")
        cls.db = copy_db(os.path.join(cls.tmp, "copy.sqlite"))
        if cls.modify:
            con = sqlite3.connect(cls.db)
            cls.modify(con)
            con.commit()
            con.close()
        cls.db_sha = file_sha256(cls.db)
        cls.land = os.path.join(cls.tmp, "landscapes")
        os.makedirs(cls.land)
        write_sphere_landscape(cls.land)
        write_sphere_landscape(cls.land, checked=True)
        cls.out = os.path.join(cls.tmp, "report")
        extra = tuple(cls.extra(cls.tmp)) if cls.extra else ()
        if harness_path():
            extra += ("--harness", harness_path())
        cls.proc = run_report(cls.db, cls.out, "--landscapes", cls.land, "--build-type", "TestBuild",
                              *extra)
        if cls.proc.returncode != 0:
            raise AssertionError(f"make_report exited {cls.proc.returncode}:\n{cls.proc.stderr}")
        # what the report left beside the database, before this test's own reads
        cls.sidecars_after_report = sidecar_files(cls.tmp)
        cls.sha_after_report = file_sha256(cls.db)
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
    def test_the_database_and_its_folder_are_left_as_found(self):
        self.assertEqual(self.sidecars_after_report, [])
        self.assertEqual(self.sha_after_report, self.db_sha)

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

    def test_every_declared_chart_is_drawn_and_placed_in_its_section(self):
        charts, plots = chart_modules()
        per_env = [c for c in plots.CHARTS if c.section == charts.PER_ENV]
        across = [c for c in plots.CHARTS if c.section == charts.ACROSS]
        self.assertEqual([c.name for c in per_env], ["curves", "final"])
        self.assertEqual([c.name for c in across], ["ranks", "ecdf"])
        keys = list(self.cells)
        for env, budget in keys:
            stem = final_csv_name(env, budget, keys)[len("final_"):-len(".csv")]
            shown = figures_in(env_section(self.html, stem))
            # the env's charts in declaration order, and nothing else (no renders here)
            self.assertEqual([f[0] for f in shown], [c.png.format(slug=stem) for c in per_env], env)
            for c, (png, alt, caption) in zip(per_env, shown):
                w, h = png_size(self.file(png))
                self.assertGreater(min(w, h), 200, f"{png}: {w} x {h} px")
                self.assertEqual(alt, c.alt.format(env=env))
                head, _, tail = c.caption.partition("{scale}")
                self.assertTrue(caption.startswith(head) and caption.endswith(tail), caption)
                self.assertRegex(caption[len(head):], r"^(Linear|Log) y axis")   # the env's scale sentence
        shown = figures_in(section(self.html, "across"))
        self.assertEqual(shown, [(c.png, c.alt, c.caption) for c in across])
        for c in across:
            self.assertGreater(min(png_size(self.file(c.png))), 200, c.png)
        # every <figure> of the page: the charts, and the two landscapes of --landscapes
        self.assertEqual(len(figures_in(self.html)), len(per_env) * len(keys) + len(across) + 2)
        self.assertEqual(self.html.count("<figure>"), len(figures_in(self.html)))

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
        # the test grid has 3 seeds: the smallest one-sided exact p is 1/C(6,3) = 0.05
        self.assertIn("smallest exact one-sided p-value is 1/C(6,3) = 0.05", self.html)
        # gd's seeds are one run on each env, as the database records (runs.seed_free_episodes =
        # episodes, every seed the same final loss); random's and cmaes's are not
        con = sqlite3.connect(self.db)
        recorded = {(e, o): (free, n, losses) for e, o, free, n, losses in con.execute(
            "SELECT env, optimizer, MIN(seed_free_episodes = episodes), COUNT(*), COUNT(DISTINCT best_loss) "
            "FROM runs WHERE status = 'done' GROUP BY env, optimizer")}
        con.close()
        for r in rows:
            free, n, losses = recorded[(r["env"], r["optimizer"])]
            self.assertEqual(r["seed_free"], "True" if r["optimizer"] == "gd" else "False", r)
            self.assertEqual(r["seed_free"] == "True", free == 1 and losses == 1 and n > 1, r)
        for env in envs:
            final = {x["optimizer"]: x for x in read_csv(self.file(f"final_{slug(env)}.csv"))}
            self.assertEqual((final["gd"]["ci95_low"], final["gd"]["std"]), ("", ""))   # one run: no CI
            self.assertNotEqual(final["random"]["ci95_low"], "")
        self.assertIn("Here: gd on branin, gd on sphere-2.", self.html)

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

    def test_claims_without_the_papers_runs_say_runs_missing(self):
        rows = read_csv(self.file("claims.csv"))
        with open(os.path.join(HERE, "paper_claims.csv"), newline="", encoding="utf-8") as f:
            paper = list(csv.DictReader(f))
        self.assertEqual(len(rows), sum(len(r["env"].split()) for r in paper))
        top = self.html.index('id="claims"')
        self.assertLess(top, self.html.index('id="provenance"'))
        self.assertIn("The paper&#x27;s claims", self.html)
        if {r["env"] for r in rows} & {e for e, _ in self.cells}:
            return                      # a database with the paper's envs: verdicts of its own
        all_runs = plan_runs_per_env(need_harness())
        kinds = {r["id"]: r for r in paper}
        for r in rows:
            c = kinds[r["id"]]
            if c["kind"] == "not_testable":
                self.assertEqual((r["verdict"], r["settle"]), ("not testable from the database", ""))
                continue
            # 5 seeds of each optimizer named; a_best: of every optimizer `harness --all` runs there
            n = 5 * (all_runs[r["env"]] if c["kind"] == "a_best" else len(set((c["a"] + " " + c["b"]).split())))
            self.assertEqual(r["verdict"], f"runs missing: 0 of {n} done", r["id"])
            self.assertEqual(r["settle"], f"harness --claims --env {r['env']} --seeds 5")
            self.assertTrue(r["reason"].startswith(f"No run of {r['env']} in the database; the claim "
                                                   f"needs {n} runs ("), r["reason"])

    def test_gradient_quality_from_the_default_file(self):
        default = os.path.join(os.path.dirname(HERE), "data", "gradient_quality.csv")
        sec = section(self.html, "gradient-quality")
        if not os.path.isfile(default):
            self.assertIn("No gradient survey", sec)
            return
        with open(default, newline="", encoding="utf-8") as f:
            envs = [r["env"] for r in csv.DictReader(f)]
        rows = [c for c in map(row_cells, html_rows(sec)) if c]
        self.assertEqual([r[0].split(" (as ")[0] for r in rows], envs)

    def test_the_harness_runs_are_current(self):
        # the versions the harness stored (harness/core/results_versions.cpp) are the ones its `harness
        # list` gives (dsb_report.staleness): no run left out, no stale file, no note
        need_harness()
        con = sqlite3.connect(self.db)
        stored = con.execute("SELECT DISTINCT env, optimizer, results_versions FROM runs").fetchall()
        con.close()
        self.assertEqual(len(stored), 6)
        for env, opt, text in stored:
            self.assertEqual(text, versions_text(env, opt))
            self.assertRegex(text, r"^env [1-9][0-9]*, optimizer [1-9][0-9]*, run [1-9][0-9]*$")
        self.assertFalse(os.path.exists(self.file("stale_runs.csv")))
        self.assertNotIn("stale", self.html.split('<h2 id="contents">')[0])
        self.assertNotIn('id="stale"', self.html)

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


# Final best losses per (env, optimizer), one per seed, for the claims tests (paper_claims.csv).
CLAIM_CELLS = {
    ("plb-torus", "boleap"): [1, 2, 3, 4, 5, 6],        # clearly below cmaes: holds
    ("plb-torus", "cmaes"): [11, 12, 13, 14, 15, 16],
    ("plb-assembly", "boleap"): [11, 12, 13, 14, 15, 16],  # clearly above cmaes: does not hold
    ("plb-assembly", "cmaes"): [1, 2, 3, 4, 5, 6],
    ("plb-pinch", "boleap"): [1, 3, 5, 7, 9, 11],        # interleaved: no difference, holds
    ("plb-pinch", "cmaes"): [2, 4, 6, 8, 10, 12],
    ("plb-table", "boleap"): [1, 2, 3],                  # 3 seeds: not enough data
    ("plb-table", "cmaes"): [11, 12, 13],
    ("cartpole1", "cmaes"): [1, 3, 5, 7, 9, 11],         # 2 comparisons for Holm
    ("cartpole1", "rand-descents"): [2, 4, 6, 8, 10, 13],
    ("cartpole1", "bo"): [20, 21, 22, 23, 24, 25],
    ("fluid", "boleap"): [1, 2, 3, 4, 5, 6],             # best, but no lift metric stored
    ("fluid", "cmaes"): [11, 12, 13, 14, None, 16],      # None: a run without a finite loss
    ("branin", "boleap"): [1, 3, 5, 7, 9],               # interleaved with cmaes: p >= alpha, and
    ("branin", "cmaes"): [2, 4, 6, 8, 10],               # random's 2 seeds cannot change that
    ("branin", "random"): [20, 21],
    ("sphere-2", "boleap"): [1, 2, 3, 4, 5],             # clearly below cmaes, random short: open
    ("sphere-2", "cmaes"): [11, 12, 13, 14, 15],
    ("sphere-2", "random"): [20, 21],
}
# 5 seeds of 8 optimizers for a claim of 4 x 4 one-sided comparisons ("many"): Holm's smallest
# reachable p is 16 / C(10, 5) = 0.063 >= 0.05, so it needs 6 seeds (16 / C(12, 6) = 0.017)
MANY_A, MANY_B = ["gd", "rand-descents", "boleap", "nlopt-lbfgs"], ["cmaes", "random", "bo", "nlopt-bobyqa"]
CLAIM_CELLS.update({("hartmann6", o): [k + 10 * j for k in range(5)]
                    for j, o in enumerate(MANY_A + MANY_B)})


def _synthetic_runs(con, cells=CLAIM_CELLS):
    """Replace every run by 'done' runs of budget 2 with the given final best losses (episode 0
    one higher, episode 1 the final loss), keeping the copied database's schema and config rows."""
    env_h, opt_h, ver = con.execute(
        "SELECT env_config_hash, opt_config_hash, harness_version FROM runs LIMIT 1").fetchone()
    for table in ("replay", "evals", "runs"):
        con.execute(f"DELETE FROM {table}")
    for (env, opt), losses in cells.items():
        for seed, best in enumerate(losses):
            cur = con.execute(
                "INSERT INTO runs(env, optimizer, seed, budget, env_config_hash, opt_config_hash, "
                "rng_seed, status, episodes, best_loss, wall_s, harness_version, git_sha, host, "
                "results_versions) VALUES (?, ?, ?, 2, ?, ?, '0', 'done', 2, ?, 0.1, ?, 'test', 'test', ?)",
                (env, opt, seed, env_h, opt_h, best, ver, versions_text(env, opt)))
            first = None if best is None else best + 1
            for ep, (loss, b) in enumerate([(first, first), (best, best)]):
                con.execute("INSERT INTO evals(run_id, episode, loss, best_loss, used_grad, wall_s, "
                            "failed) VALUES (?, ?, ?, ?, 0, 0.05, ?)",
                            (cur.lastrowid, ep, loss, b, int(loss is None)))


def _paper_and_metric_claims(tmp):
    """--claims: reports/paper_claims.csv plus three claims on the share of seeds reaching a
    metric (plb-torus: boleap's runs at 0.9, cmaes's at 0.1, see _synthetic_with_metric)."""
    path = os.path.join(tmp, "claims.csv")
    shutil.copy(os.path.join(HERE, "paper_claims.csv"), path)
    with open(path, "a", newline="", encoding="utf-8") as f:
        w = csv.writer(f, lineterminator="\n")
        w.writerow(["lifts", "plb-torus", "metric_most", "boleap", "", "0.5", "lifts", "t", ""])
        w.writerow(["drops", "plb-torus", "metric_few", "cmaes", "", "0.5", "drops", "t", ""])
        w.writerow(["wrong", "plb-torus", "metric_most", "cmaes", "", "0.5", "wrong", "t", ""])
        w.writerow(["many", "hartmann6", "a_below_b", " ".join(MANY_A), " ".join(MANY_B), "",
                    "many", "t", ""])
        w.writerow(["early-fail", "branin", "a_below_b", "boleap", "cmaes random", "", "early", "t", ""])
        w.writerow(["early-open", "sphere-2", "a_below_b", "boleap", "cmaes random", "", "open", "t", ""])
    return ("--claims", path)


def _synthetic_with_metric(con):
    """The claims runs, with plb-torus's boleap episodes at metric 0.9 and cmaes's at 0.1."""
    _synthetic_runs(con)
    con.execute("UPDATE evals SET metric = CASE (SELECT optimizer FROM runs r WHERE r.run_id = "
                "evals.run_id) WHEN 'boleap' THEN 0.9 ELSE 0.1 END WHERE run_id IN "
                "(SELECT run_id FROM runs WHERE env = 'plb-torus')")


class TestPaperClaims(ReportCase):
    """The paper's claims (reports/paper_claims.csv, plus three metric claims) on a synthetic
    database: each verdict."""
    modify = staticmethod(_synthetic_with_metric)
    extra = staticmethod(_paper_and_metric_claims)

    def claim(self, cid, env):
        rows = [r for r in read_csv(self.file("claims.csv")) if (r["id"], r["env"]) == (cid, env)]
        self.assertEqual(len(rows), 1, f"{cid} on {env}")
        return rows[0]

    def comparisons(self, cid, env):
        return {(r["a"], r["b"]): r for r in read_csv(self.file("claims_comparisons.csv"))
                if (r["id"], r["env"]) == (cid, env)}

    def test_clear_difference_holds(self):
        r = self.claim("plb-boleap-beats-cmaes", "plb-torus")
        self.assertEqual(r["verdict"], "holds", r["reason"])
        c = self.comparisons("plb-boleap-beats-cmaes", "plb-torus")[("boleap", "cmaes")]
        # perfectly separated, 6 vs 6, one-sided exact: 1 / C(12, 6); one comparison: Holm = raw
        self.assertAlmostEqual(float(c["p_raw"]), 1 / math.comb(12, 6), delta=1e-12)
        self.assertAlmostEqual(float(c["p_holm"]), float(c["p_raw"]), delta=1e-15)
        self.assertEqual(float(c["a12"]), 1.0)
        self.assertEqual(r["n"], "boleap 6; cmaes 6")
        self.assertEqual(self.claim("fluid-boleap-best", "fluid")["verdict"], "holds")
        # a settled row names no command (the page: "—")
        self.assertEqual((r["settle"], r["runs_done"], r["runs_needed"]), ("", "", ""))
        row = next(c for c in map(row_cells, html_rows(section(self.html, "claims")))
                   if c[:2] == ["plb-boleap-beats-cmaes", "plb-torus (2)"])
        self.assertEqual((row[2], row[5]), ("holds", "—"))

    def test_reversed_difference_does_not_hold(self):
        r = self.claim("plb-boleap-beats-cmaes", "plb-assembly")
        self.assertEqual(r["verdict"], "does not hold", r["reason"])
        self.assertEqual(float(r["a12_claim"]), 0.0)
        # a 'no difference' claim fails where the two clearly differ (two-sided 2/C(12,6))
        self.assertEqual(self.claim("cartpole1-cmaes-like-gradient", "cartpole1")["verdict"],
                         "does not hold")

    def test_no_difference_holds(self):
        r = self.claim("plb-boleap-like-cmaes", "plb-pinch")
        self.assertEqual(r["verdict"], "holds", r["reason"])
        self.assertGreaterEqual(float(r["p_claim"]), 0.05)

    def test_three_seeds_are_not_enough(self):
        # not enough data for the test, and 2 of the claims grid's 5 seeds a side absent
        r = self.claim("plb-boleap-like-cmaes", "plb-table")
        self.assertEqual(r["verdict"], "runs missing: 6 of 10 done", r["reason"])
        self.assertEqual(int(r["min_n"]), 4)   # two-sided, one comparison: 2/C(8,4) = 0.029
        self.assertIn("6 of 10 runs done (boleap, cmaes x seeds 0-4, budget 2). Absent: boleap, "
                      "cmaes seeds 3-4.", r["reason"])
        self.assertIn("needs >= 4 seeds", r["reason"])
        self.assertEqual(r["settle"], "harness --claims --env plb-table --seeds 5")

    def test_more_comparisons_need_more_seeds(self):
        # 16 comparisons: 5 seeds of each optimizer cannot reach alpha; the claim asks for 6
        r = self.claim("many", "hartmann6")
        self.assertEqual((r["comparisons"], r["min_n"]), ("16", "6"))
        self.assertEqual(r["verdict"], "runs missing: 40 of 48 done", r["reason"])
        self.assertIn(f"Absent: {', '.join(MANY_A + MANY_B)} seed 5.", r["reason"])
        self.assertEqual(r["settle"], "harness --claims --env hartmann6 --seeds 6")

    def test_a_failing_comparison_settles_before_the_short_ones(self):
        # boleap vs cmaes interleaved (p >= alpha before Holm) and boleap vs random's 2 seeds short
        # (2 x 1/C(7, 2) = 0.095): no run of random can make "boleap below both" hold
        r = self.claim("early-fail", "branin")
        self.assertEqual(r["verdict"], "does not hold", r["reason"])
        self.assertTrue(r["reason"].startswith("boleap vs cmaes: p 0.") and
                        r["reason"].endswith("before Holm; 1 comparison(s) short of seeds cannot change that"),
                        r["reason"])
        self.assertEqual(r["settle"], "")
        # the same short comparison beside a significant one: Holm multiplies cmaes's 1/C(10, 5) =
        # 0.004 by 2 and random's exact 1/C(7, 2) = 0.048 by 1, so both are significant and the
        # claim holds, though the bound 2 x 1/21 = 0.095 called random's 2 seeds short (the tests
        # settle a claim before any count of seeds does)
        r = self.claim("early-open", "sphere-2")
        self.assertEqual((r["verdict"], r["reason"]), ("holds", "all 2 Holm-corrected p < 0.05"))
        comps = {c["b"]: c for c in read_csv(self.file("claims_comparisons.csv")) if c["id"] == "early-open"}
        self.assertAlmostEqual(float(comps["random"]["p_raw"]), 1 / 21, places=12)
        self.assertAlmostEqual(float(comps["random"]["p_holm"]), 1 / 21, places=12)
        self.assertAlmostEqual(float(comps["cmaes"]["p_holm"]), 2 / 252, places=12)
        self.assertEqual(r["settle"], "")

    def test_env_or_optimizer_missing(self):
        need_harness()        # runs missing vs env missing: `harness list` says plb-triplemove exists
        r = self.claim("plb-boleap-beats-cmaes", "plb-triplemove")
        self.assertEqual((r["verdict"], r["reason"]), (
            "runs missing: 0 of 10 done", "No run of plb-triplemove in the database; the claim needs "
            "10 runs (boleap, cmaes x seeds 0-4)."))
        self.assertEqual(r["settle"], "harness --claims --env plb-triplemove --seeds 5")
        # boleap's seeds 0-4 of its 6 done, the three gradient optimizers absent
        r = self.claim("plb-boleap-beats-gradient", "plb-torus")
        self.assertEqual(r["verdict"], "runs missing: 5 of 20 done")
        self.assertIn("Absent: gd, rand-descents, nlopt-lbfgs seeds 0-4.", r["reason"])
        # a_best on an RL env: every optimizer of --all (12 there) x 5 seeds; cmaes, rand-descents
        # and bo have 5 of their 6 seeds counted
        r = self.claim("cartpole1-boleap-best", "cartpole1")
        self.assertEqual(plan_runs_per_env(need_harness())["cartpole1"], 12)
        self.assertEqual(r["verdict"], "runs missing: 15 of 60 done", r["reason"])

    def test_holm_over_a_two_comparison_claim(self):
        c = self.comparisons("cartpole1-cmaes-like-gradient", "cartpole1")
        self.assertEqual(set(c), {("cmaes", "rand-descents"), ("cmaes", "bo")})
        lo, hi = sorted(c.values(), key=lambda r: float(r["p_raw"]))
        self.assertEqual(lo["b"], "bo")
        self.assertAlmostEqual(float(lo["p_raw"]), 2 / math.comb(12, 6), delta=1e-12)
        # Holm: the smallest p times 2, the next times 1 but never below the one before
        self.assertAlmostEqual(float(lo["p_holm"]), 2 * float(lo["p_raw"]), delta=1e-12)
        self.assertAlmostEqual(float(hi["p_holm"]),
                               min(1.0, max(float(hi["p_raw"]), 2 * float(lo["p_raw"]))),
                               delta=1e-12)
        self.assertGreater(float(hi["p_raw"]), 0.05)

    def test_lifting_is_not_testable_without_a_metric(self):
        r = self.claim("fluid-boleap-lifts", "fluid")
        self.assertEqual(r["verdict"], "not testable from the database")
        self.assertIn("no per-episode metric", r["reason"])

    def test_metric_rate_verdicts(self):
        got = {i: self.claim(i, "plb-torus")["verdict"] for i in ("lifts", "drops", "wrong")}
        self.assertEqual(got, {"lifts": "holds", "drops": "holds", "wrong": "does not hold"})

    def test_seeds_reaching_each_metric_threshold_per_optimizer(self):
        # every optimizer with a done run of the env, counted as SQLite counts them
        con = sqlite3.connect(self.db)
        want = {}
        for env, thr in (("plb-torus", 0.5), ("fluid", 0.2)):
            for opt, runs, reached, with_metric in con.execute(
                    "SELECT r.optimizer, COUNT(*), SUM(e.metric >= ?), COUNT(e.metric) FROM runs r JOIN evals e "
                    "ON e.run_id = r.run_id AND e.episode = 1 WHERE r.env = ? AND r.status = 'done' "
                    "GROUP BY r.optimizer", (thr, env)):
                want[(env, opt)] = (str(reached or 0), str(runs), str(with_metric))
        got = {(r["env"], r["optimizer"]): (r["reached"], r["runs"], r["with_metric"])
               for r in read_csv(self.file("claims_metric_counts.csv"))}
        self.assertEqual(got, want)
        self.assertEqual(got[("plb-torus", "boleap")], ("6", "6", "6"))
        self.assertEqual(got[("plb-torus", "cmaes")], ("0", "6", "6"))
        self.assertEqual(got[("fluid", "boleap")][2], "0")  # no metric stored
        rows = {c[0]: c for c in (row_cells(x) for x in html_rows(section(self.html, "claims-detail")))
                if len(c) == 4}
        self.assertEqual(rows["plb-torus"], ["plb-torus", "0.5", "6 of 6", "0 of 6"])
        self.assertEqual(rows["fluid"], ["fluid", "0.2", "no metric", "no metric"])
        with open(self.file("summary.md"), encoding="utf-8") as f:
            self.assertIn("| plb-torus | 0.5 | 6 of 6 | 0 of 6 |", f.read())

    def test_table_near_the_top_of_the_page(self):
        rows = [row_cells(x) for x in html_rows(section(self.html, "claims-detail"))]
        verdicts = {c[7] for c in rows if len(c) == 10}
        self.assertTrue({"holds", "does not hold", "runs missing: 6 of 10 done",
                         "not testable from the database"} <= verdicts, verdicts)
        self.assertLess(self.html.index('id="claims"'), self.html.index('id="provenance"'))


def _killed_and_failed(con):
    """On the harness's database: branin's cmaes seed 1 as a harness killed after 7 of its 20
    episodes leaves it (status running, episodes 7-19 not stored) and random seed 2 failed."""
    rid = con.execute("SELECT run_id FROM runs WHERE env = 'branin' AND optimizer = 'cmaes' AND "
                      "seed = 1").fetchone()[0]
    con.execute("UPDATE runs SET status = 'running', episodes = 7, finished_at = NULL WHERE "
                "run_id = ?", (rid,))
    con.execute("DELETE FROM evals WHERE run_id = ? AND episode >= 7", (rid,))
    con.execute("UPDATE runs SET status = 'failed', error = 'boom' WHERE env = 'branin' AND "
                "optimizer = 'random' AND seed = 2")


def _claims_file(path, rows):
    """A claims table at `path`: paper_claims.csv's header, then `rows` (id, env, kind, a, b,
    threshold; statement "s", source "t" and no note)."""
    with open(path, "w", newline="", encoding="utf-8") as f:
        w = csv.writer(f, lineterminator="\n")
        w.writerow(["id", "env", "kind", "a", "b", "threshold", "statement", "source", "note"])
        w.writerows(row + ["s", "t", ""] for row in rows)
    return path


def _state_claims(tmp):
    """One claim per state the claims table tells apart, on the harness database's envs."""
    return ("--claims", _claims_file(os.path.join(tmp, "state_claims.csv"), [
        ["gone", "cartpole2", "a_below_b", "cmaes", "random", ""],
        ["short", "sphere-2", "a_below_b", "cmaes", "random", ""],
        ["broken", "branin", "a_below_b", "cmaes", "random", ""],
        ["best", "sphere-2", "a_best", "gd", "", ""],
        ["variant", "sphere-3", "a_below_b", "cmaes", "random", ""]]))


class TestClaimStates(ReportCase):
    """What an unsettled claim lacks, on the harness's database (sphere-2, branin x random, cmaes,
    gd x 3 seeds, budget 20) with one of branin's runs killed part-way and one failed: env missing
    (no such env in `harness list`), runs missing, runs incomplete; each with its command."""
    modify = staticmethod(_killed_and_failed)
    extra = staticmethod(_state_claims)

    @classmethod
    def setUpClass(cls):
        need_harness()
        super().setUpClass()

    def claim(self, cid):
        return next(r for r in read_csv(self.file("claims.csv")) if r["id"] == cid)

    def test_env_missing(self):
        r = self.claim("gone")
        self.assertEqual((r["verdict"], r["settle"], r["runs_done"]), ("env missing", "", ""))
        self.assertTrue(r["reason"].startswith("the harness has no env cartpole2 (`harness list` of "),
                        r["reason"])
        # sphere-3 is a dimension of the sphere family that `harness list` shows as sphere-10
        self.assertEqual(self.claim("variant")["verdict"], "runs missing: 0 of 10 done")

    def test_runs_missing(self):
        r = self.claim("short")
        self.assertEqual(r["verdict"], "runs missing: 6 of 10 done")
        self.assertEqual((r["runs_done"], r["runs_needed"]), ("6", "10"))
        self.assertTrue(r["reason"].startswith(
            "6 of 10 runs done (cmaes, random x seeds 0-4, budget 20). Absent: cmaes, random seeds "
            "3-4."), r["reason"])
        self.assertEqual(r["settle"], "harness --claims --env sphere-2 --seeds 5")

    def test_runs_incomplete(self):
        r = self.claim("broken")
        self.assertEqual(r["verdict"], "runs incomplete: 4 of 10 done")
        self.assertTrue(r["reason"].startswith(
            "4 of 10 runs done (cmaes, random x seeds 0-4, budget 20). Running: cmaes seed 1. "
            "Failed: random seed 2. Absent: cmaes, random seeds 3-4."), r["reason"])
        self.assertEqual(r["settle"], "harness --claims --env branin --seeds 5")

    def test_a_best_needs_every_optimizer_of_all(self):
        # sphere-2 is not an RL env: the 10 optimizers of --all there, 3 of them with 3 seeds done.
        # gd's seeds are one run (recorded seed-free), so its 2 comparisons are sign tests of the
        # others' seeds against its one value: Holm's smallest p 2 x 2^-n reaches 0.05 from n = 6
        # (2/64), not 4 as two Mann-Whitney samples would (2/70): the claim asks for 6 seeds
        self.assertEqual(plan_runs_per_env(need_harness())["sphere-10"], 10)
        r = self.claim("best")
        self.assertEqual(r["verdict"], "runs missing: 9 of 60 done")
        self.assertEqual(r["min_n"], "6")
        self.assertIn("gd 3 seeds = 1 run; cmaes 3; random 3", r["n"])
        self.assertIn("Absent: gd, random, cmaes seeds 3-5; rand-descents, bo, boleap, nlopt-lbfgs, "
                      "nlopt-bobyqa, nlopt-direct-l, nlopt-crs2 seeds 0-5.", r["reason"])
        comps = [c for c in read_csv(self.file("claims_comparisons.csv")) if c["id"] == "best"]
        self.assertEqual(sorted((c["b"], c["test"], c["n_a"], c["n_b"]) for c in comps),
                         [("cmaes", "sign", "1", "3"), ("random", "sign", "1", "3")])

    def test_page_and_summary_name_the_commands(self):
        top = {c[0]: c for c in map(row_cells, html_rows(section(self.html, "claims"))) if c}
        self.assertEqual(top["gone"][2:], ["env missing", "—", "—", "none"])
        self.assertEqual(top["broken"][2], "runs incomplete: 4 of 10 done")
        self.assertEqual(top["broken"][5], "harness --claims --env branin --seeds 5")
        self.assertIn("env missing 1, runs incomplete 1, runs missing 3:",
                      html.unescape(section(self.html, "claims")))
        with open(self.file("summary.md"), encoding="utf-8") as f:
            md = f.read()
        self.assertIn("| runs missing: 6 of 10 done |", md)
        self.assertIn("| harness --claims --env sphere-2 --seeds 5 |", md)


def _older_binary(con):
    """The harness's database as older binaries leave it: random's runs without results versions
    (a schema-4 file's, migrated: ''), branin's random seed 2 failed, and sphere-2's cmaes seeds 0
    and 1 of another optimizer version (this binary's + 1); sphere-2's cmaes seed 2 and every gd
    run stay current."""
    e, o, r = registry_of_harness().current_versions("sphere-2", "cmaes")
    con.execute("UPDATE runs SET results_versions = '' WHERE optimizer = 'random'")
    con.execute("UPDATE runs SET status = 'failed', error = 'old' WHERE optimizer = 'random' AND "
                "env = 'branin' AND seed = 2")
    con.execute("UPDATE runs SET results_versions = ? WHERE env = 'sphere-2' AND optimizer = 'cmaes' "
                "AND seed < 2", (f"env {e}, optimizer {o + 1}, run {r}",))


def _stale_claims(tmp, *more):
    """A claim on sphere-2's cmaes and random: the runs it counts are the current ones only."""
    return ("--claims", _claims_file(os.path.join(tmp, "stale_claims.csv"), [
        ["cm-rand", "sphere-2", "a_below_b", "cmaes", "random", ""],
        ["gd-cm", "branin", "a_below_b", "gd", "cmaes", ""]])) + more


def finals_of(case, env):
    return {r["optimizer"]: r for r in read_csv(case.file(f"final_{slug(env)}.csv"))}


def best_losses(db, where, args=()):
    con = sqlite3.connect(db)
    out = [b for (b,) in con.execute(f"SELECT best_loss FROM runs WHERE status = 'done' AND {where}", args)]
    con.close()
    return out


class StaleCase(ReportCase):
    modify = staticmethod(_older_binary)

    @classmethod
    def setUpClass(cls):
        need_harness()
        super().setUpClass()
        e, o, r = registry_of_harness().current_versions("sphere-2", "cmaes")
        cls.cmaes_now, cls.cmaes_label = o, f"cmaes-stale-e{e}o{o + 1}r{r}"
        cls.unversioned = "made before results versions (a database of schema 4 or older)"

    def notes(self):
        return [html.unescape(n) for n in re.findall(r'<p class="note">(.*?)</p>', self.html)]

    def groups(self, shown):
        suffix = (lambda lab: f" (shown as {lab})") if shown else (lambda lab: "")
        return (f"branin / random: 2 done, 1 unfinished: {self.unversioned}{suffix('random-stale-unversioned')}; "
                f"sphere-2 / cmaes: 2 done, 0 unfinished: optimizer cmaes version {self.cmaes_now + 1}, "
                f"this binary's {self.cmaes_now}{suffix(self.cmaes_label)}; "
                f"sphere-2 / random: 3 done, 0 unfinished: {self.unversioned}{suffix('random-stale-unversioned')}.")

    def check_stale_file(self, shown):
        rows = [(r["env"], r["optimizer"], r["results_versions"], r["done"], r["unfinished"], r["shown_as"])
                for r in read_csv(self.file("stale_runs.csv"))]
        e, o, r = registry_of_harness().current_versions("sphere-2", "cmaes")
        self.assertEqual(rows, [
            ("branin", "random", "", "2", "1", "random-stale-unversioned" if shown else ""),
            ("sphere-2", "cmaes", f"env {e}, optimizer {o + 1}, run {r}", "2", "0", self.cmaes_label if shown else ""),
            ("sphere-2", "random", "", "3", "0", "random-stale-unversioned" if shown else "")])
        self.assertIn("Stale runs (8)", self.html)

    def check_claims_judge_current_runs(self):
        # sphere-2: cmaes seed 2 is the one current run of the 10 (cmaes, random x seeds 0-4)
        v = {r["id"]: r for r in read_csv(self.file("claims.csv"))}
        self.assertEqual(v["cm-rand"]["verdict"], "runs missing: 1 of 10 done")
        self.assertTrue(v["cm-rand"]["reason"].startswith(
            "1 of 10 runs done (cmaes, random x seeds 0-4, budget 20). Absent: cmaes seeds 0-1, 3-4; "
            "random seeds 0-4."), v["cm-rand"]["reason"])
        # branin's gd and cmaes are current: 3 seeds each, as the database has them
        self.assertEqual(v["gd-cm"]["n"].split("; ")[1], "cmaes 3")
        comps = read_csv(self.file("claims_comparisons.csv"))
        self.assertFalse([c for c in comps if "stale" in c["a"] + c["b"]])


class TestStaleLeftOut(StaleCase):
    """Runs of other results versions are left out of every table, figure, test and claim, and
    the overview says how many and why, as `harness export` counts them."""
    extra = staticmethod(_stale_claims)

    def test_overview_says_how_many_and_why(self):
        note = next(n for n in self.notes() if "stale" in n)
        self.assertEqual(note, (
            f"Left out: 8 stale run(s) (7 done, 1 unfinished), made by other results versions than this "
            f"harness's (`harness list` of {harness_path()}); --include-stale shows them, marked: "
            + self.groups(False)))
        with open(self.file("summary.md"), encoding="utf-8") as f:
            self.assertIn("> " + note, f.read())
        self.check_stale_file(False)

    def test_the_harness_counts_the_same_stale_runs(self):
        ex = subprocess.run([need_harness(), "export", "--db", self.db, "--out", os.path.join(self.tmp, "t.csv")],
                            capture_output=True, text=True, timeout=120)
        self.assertEqual(ex.returncode, 0, ex.stderr)
        self.assertIn("left out 7 stale done runs", ex.stderr)
        self.assertIn(f"sphere-2 / cmaes: 2 (optimizer cmaes version {self.cmaes_now + 1}, this binary's "
                      f"{self.cmaes_now})", ex.stderr)
        self.assertIn(f"sphere-2 / random: 3 ({self.unversioned})", ex.stderr)

    def test_tables_hold_current_runs_only(self):
        sphere, branin = finals_of(self, "sphere-2"), finals_of(self, "branin")
        self.assertEqual(sorted(sphere), ["cmaes", "gd"])
        self.assertEqual(sorted(branin), ["cmaes", "gd"])
        # sphere-2's cmaes: seed 2 alone, its median its own best loss
        (seed2,) = best_losses(self.db, "env = 'sphere-2' AND optimizer = 'cmaes' AND seed = 2")
        self.assertEqual((sphere["cmaes"]["n_seeds"], float(sphere["cmaes"]["median"])), ("1", seed2))
        self.assertEqual(branin["cmaes"]["n_seeds"], "3")
        self.assertEqual(float(branin["cmaes"]["median"]),
                         statistics.median(best_losses(self.db, "env = 'branin' AND optimizer = 'cmaes'")))
        self.assertEqual({r["optimizer"] for r in read_csv(self.file("significance.csv"))}, {"cmaes", "gd"})
        self.assertEqual({r["optimizer"] for r in read_csv(self.file("ranks.csv"))}, {"cmaes", "gd"})
        head = re.findall(r"<th>(.*?)</th>", html_rows(section(self.html, "overview"))[0])
        self.assertEqual(head, ["env (budget)", "cmaes", "gd"])
        self.assertNotIn("random", section(self.html, "failed"))     # the stale failed run too
        # a stale run is not done: sphere-2's cmaes seeds 0-1 are missing, to be run anew
        missing = {(r["env"], r["optimizer"], r["seed"], r["reason"]) for r in read_csv(self.file("missing.csv"))}
        self.assertEqual(missing, {("sphere-2", "cmaes", "0", "absent"), ("sphere-2", "cmaes", "1", "absent")})

    def test_claims_judge_current_runs_only(self):
        self.check_claims_judge_current_runs()


class TestStaleIncluded(StaleCase):
    """--include-stale: every stale (optimizer, versions) is an optimizer of its own, marked,
    never pooled with the current runs of its optimizer; the claims still judge current runs."""
    extra = staticmethod(lambda tmp: _stale_claims(tmp, "--include-stale"))

    def test_overview_says_they_are_shown(self):
        note = next(n for n in self.notes() if "stale" in n)
        self.assertEqual(note, (
            f"Shown: 8 stale run(s) (7 done, 1 unfinished), made by other results versions than this "
            f"harness's (`harness list` of {harness_path()}); each is its own optimizer, OPT-stale-eEoOrR "
            f"or OPT-stale-unversioned, never pooled with current runs, and the claims judge current runs "
            f"only: " + self.groups(True)))
        self.check_stale_file(True)

    def test_stale_runs_are_samples_of_their_own(self):
        sphere, branin = finals_of(self, "sphere-2"), finals_of(self, "branin")
        self.assertEqual(sorted(sphere), ["cmaes", self.cmaes_label, "gd", "random-stale-unversioned"])
        (seed2,) = best_losses(self.db, "env = 'sphere-2' AND optimizer = 'cmaes' AND seed = 2")
        self.assertEqual((sphere["cmaes"]["n_seeds"], float(sphere["cmaes"]["median"])), ("1", seed2))
        old = best_losses(self.db, "env = 'sphere-2' AND optimizer = 'cmaes' AND seed < 2")
        self.assertEqual(sphere[self.cmaes_label]["n_seeds"], "2")
        self.assertAlmostEqual(float(sphere[self.cmaes_label]["median"]), statistics.median(old), delta=1e-15)
        self.assertEqual(float(sphere[self.cmaes_label]["min"]), min(old))
        # branin's random: 2 done seeds, the failed third counted as its failed run
        self.assertEqual((branin["random-stale-unversioned"]["n_seeds"],
                          branin["random-stale-unversioned"]["failed_runs"]), ("2", "1"))
        sig = {(r["env"], r["optimizer"]) for r in read_csv(self.file("significance.csv"))}
        self.assertIn(("sphere-2", self.cmaes_label), sig)
        head = re.findall(r"<th>(.*?)</th>", html_rows(section(self.html, "overview"))[0])
        self.assertEqual(head, ["env (budget)", "cmaes", self.cmaes_label, "gd", "random-stale-unversioned"])
        self.assertIn("random-stale-unversioned", section(self.html, "failed"))
        # the figures' legends name them as the tables do: the labels the curves are drawn under
        from dsb_report import data
        d = data.load(self.db, registry_of_harness(), include_stale=True)
        pn = next(p for p in d.panels if p.env == "sphere-2")
        self.assertEqual(pn.optimizers, ["cmaes", self.cmaes_label, "gd", "random-stale-unversioned"])
        self.assertEqual(pn.rows(self.cmaes_label).size, 2)

    def test_claims_judge_current_runs_only(self):
        self.check_claims_judge_current_runs()
        # and a stale run is no run to make again under its label
        self.assertFalse([r for r in read_csv(self.file("missing.csv")) if "stale" in r["optimizer"]])


def _schema_4(con):
    """The database as a schema-4 harness left it: runs without the results_versions column (the
    table rebuilt without it), meta.schema_version 4."""
    cols = [r[1] for r in con.execute("PRAGMA table_info(runs)") if r[1] != "results_versions"]
    con.execute(f"CREATE TABLE runs4 AS SELECT {', '.join(cols)} FROM runs")
    con.execute("DROP TABLE runs")
    con.execute("ALTER TABLE runs4 RENAME TO runs")
    con.execute("UPDATE meta SET value = '4' WHERE key = 'schema_version'")


class TestStaleSchema4(ReportCase):
    """A database of schema 4 (no runs.results_versions) is read without being changed; its runs
    were made before results versions, so all are stale for this harness."""
    modify = staticmethod(_schema_4)

    @classmethod
    def setUpClass(cls):
        need_harness()
        super().setUpClass()

    def test_every_run_is_left_out_and_the_file_is_unchanged(self):
        con = sqlite3.connect(self.db)
        self.assertNotIn("results_versions", [r[1] for r in con.execute("PRAGMA table_info(runs)")])
        n = con.execute("SELECT count(*) FROM runs").fetchone()[0]
        con.close()
        self.assertEqual(n, 18)
        notes = [html.unescape(x) for x in re.findall(r'<p class="note">(.*?)</p>', self.html)]
        self.assertTrue(notes[0].startswith("Left out: 18 stale run(s) (18 done, 0 unfinished)"), notes[0])
        self.assertIn("No run of this harness's results versions is done: there is nothing to compare yet.", notes)
        self.assertEqual({r["reason"] for r in read_csv(self.file("stale_runs.csv"))},
                         {"made before results versions (a database of schema 4 or older)"})
        self.assertEqual(sum(int(r["done"]) for r in read_csv(self.file("stale_runs.csv"))), 18)
        self.assertEqual(file_sha256(self.db), self.db_sha)

    def test_include_stale_shows_them_all(self):
        out = os.path.join(self.tmp, "report_all")
        proc = run_report(self.db, out, "--harness", need_harness(), "--include-stale")
        self.assertEqual(proc.returncode, 0, proc.stderr)
        for env in ("sphere-2", "branin"):
            rows = {r["optimizer"]: r for r in read_csv(os.path.join(out, f"final_{env}.csv"))}
            self.assertEqual(sorted(rows), ["cmaes-stale-unversioned", "gd-stale-unversioned",
                                            "random-stale-unversioned"])
            self.assertEqual({r["n_seeds"] for r in rows.values()}, {"3"})
            self.assertEqual(float(rows["random-stale-unversioned"]["median"]),
                             statistics.median(best_losses(self.db, "env = ? AND optimizer = 'random'", (env,))))
        self.assertEqual(file_sha256(self.db), self.db_sha)


class TestStaleNotJudged(unittest.TestCase):
    """Without a harness to ask, no run can be judged stale: all are kept, and the overview says so."""

    def test_all_runs_kept(self):
        need_harness()
        tmp = tempfile.mkdtemp(prefix="dsb_report_nojudge_")
        try:
            db = copy_db(os.path.join(tmp, "copy.sqlite"))
            con = sqlite3.connect(db)
            _older_binary(con)
            con.commit()
            con.close()
            # the generator alone, beside no build/bin/harness, without $DSB_HARNESS
            shutil.copytree(HERE, os.path.join(tmp, "reports"),
                            ignore=shutil.ignore_patterns("__pycache__", "test_*.py"))
            env = {k: v for k, v in os.environ.items() if k != "DSB_HARNESS"}
            out = os.path.join(tmp, "report")
            proc = subprocess.run([sys.executable, os.path.join(tmp, "reports", "make_report.py"), "--db", db,
                                   "--out", out], capture_output=True, text=True, timeout=600, env=env)
            self.assertEqual(proc.returncode, 0, proc.stderr)
            with open(os.path.join(out, "index.html"), encoding="utf-8") as f:
                page = f.read()
            notes = [html.unescape(x) for x in re.findall(r'<p class="note">(.*?)</p>', page)]
            self.assertEqual(notes[0], (
                "Staleness could not be judged: no harness to ask for its results versions (make_report.py "
                "--harness BIN, $DSB_HARNESS or build/bin/harness), so all 18 run(s) are kept, whatever "
                "versions of the code made them (docs/database.md, \"Results versions\")."))
            rows = {r["optimizer"]: r for r in read_csv(os.path.join(out, "final_sphere-2.csv"))}
            self.assertEqual({o: r["n_seeds"] for o, r in rows.items()}, {"cmaes": "3", "gd": "3", "random": "3"})
            self.assertFalse(os.path.exists(os.path.join(out, "stale_runs.csv")))
        finally:
            shutil.rmtree(tmp, ignore_errors=True)


class TestStaleReasons(unittest.TestCase):
    """dsb_report.staleness reads stored versions and says why a run is stale in the harness's
    words (harness/core/results_versions.cpp, stale_reason)."""

    def test_reasons(self):
        reg = registry_of_harness() if harness_path() else None
        if reg is None:
            self.skipTest("no harness binary: set DSB_HARNESS")
        from dsb_report import staleness
        e, o, r = reg.current_versions("plb-pinch-h5", "boleap")
        now = f"env {e}, optimizer {o}, run {r}"
        self.assertEqual(staleness.parse(now), (e, o, r))
        for bad in ("", f"env 0{e}, optimizer {o}, run {r}", f"env {e}, optimizer {o}", "env 0, optimizer 0, run 0"):
            self.assertEqual(staleness.parse(bad), (0, 0, 0), bad)
        self.assertEqual(staleness.reason(reg, "plb-pinch-h5", "boleap", now), "")
        self.assertEqual(staleness.reason(reg, "plb-pinch", "boleap", now), "")       # a variant: its env's
        self.assertEqual(staleness.reason(reg, "plb-pinch", "boleap", "garbage"), staleness.UNVERSIONED)
        self.assertEqual(staleness.reason(reg, "plb-pinch", "boleap", f"env {e + 1}, optimizer {o}, run {r + 2}"),
                         f"env plb-pinch version {e + 1}, this binary's {e}; run code version {r + 2}, "
                         f"this binary's {r}")
        self.assertEqual(staleness.reason(reg, "no-such-env", "boleap", now),
                         f"env no-such-env version {e}, this binary's none (unknown here)")
        # an external optimizer has the ext: adapter's version
        es, x = reg.current_versions("sphere-2", "cmaes")[0], reg.versions["optimizer"]["ext:NAME"]
        self.assertEqual(staleness.reason(reg, "sphere-2", "ext:mine", f"env {es}, optimizer {x}, run {r}"), "")
        self.assertEqual(staleness.reason(reg, "sphere-2", "ext:mine", f"env {es}, optimizer {x + 1}, run {r}"),
                         f"optimizer ext:mine version {x + 1}, this binary's {x}")
        self.assertEqual(staleness.label("cmaes", "env 1, optimizer 2, run 3"), "cmaes-stale-e1o2r3")
        self.assertEqual(staleness.label("cmaes", ""), "cmaes-stale-unversioned")


class TestRegistry(unittest.TestCase):
    """dsb_report.registry reads `harness list`: which envs exist, which optimizers --all runs."""

    @classmethod
    def setUpClass(cls):
        sys.path.insert(0, HERE)
        from dsb_report import registry
        cls.reg = registry.load(need_harness())

    def test_optimizers_of_all_per_env_equal_the_plan(self):
        plan = plan_runs_per_env(need_harness())
        self.assertEqual(set(plan), set(self.reg.envs))
        self.assertEqual({e: len(self.reg.optimizers_for(e)) for e in plan}, plan)
        self.assertIn("ppo", self.reg.optimizers_for("cartpole1"))
        self.assertNotIn("ppo", self.reg.optimizers_for("branin"))
        self.assertFalse(any(":" in o for o in self.reg.optimizers))   # ext:NAME is no optimizer

    def test_variants_exist_and_unknown_names_do_not(self):
        for name in ("sphere-3", "fluid-h5", "plb-table-h10", "cartpole1"):
            self.assertTrue(self.reg.has_env(name), name)
        for name in ("pinball-2x2", "cartpole2", "sphere", "fluid-x5"):
            self.assertFalse(self.reg.has_env(name), name)

    def test_without_a_registry_a_best_counts_at_least(self):
        from dsb_report import claims
        c = claims.Claim(id="x", envs=["cartpole1"], kind="a_best", a=["boleap"], b=[],
                         threshold=math.nan, statement="", source="", note="")
        v, _ = claims.evaluate([c], [], None, None)
        self.assertEqual(v.loc[0, "verdict"], "runs missing: 0 of at least 5 done")
        self.assertIn("Whether the harness has env cartpole1 is unknown", v.loc[0, "reason"])
        v, _ = claims.evaluate([c], [], None, self.reg)
        self.assertEqual(v.loc[0, "verdict"], "runs missing: 0 of 60 done")


# The overview, failures, regret and 'too few seeds' on a synthetic database: per (env, optimizer)
# the final best losses over seeds (see _overview_runs for the episodes).
FS_BRANIN = 0.3978873577297384
FS_STYB2 = -39.16616570377142 * 2
OVERVIEW_CELLS = {
    ("branin", "cmaes"): [FS_BRANIN + 0.001 * k for k in range(1, 7)],          # the winner
    ("branin", "gd"): [FS_BRANIN + 0.001 * k + 0.0005 for k in range(1, 7)],    # interleaved: a tie
    ("branin", "nlopt-bobyqa"): [FS_BRANIN + 0.1 * k for k in range(1, 7)],
    ("branin", "nlopt-direct-l"): [FS_BRANIN + 0.2 * k for k in range(1, 7)],
    ("branin", "nlopt-lbfgs"): [FS_BRANIN + 0.3 * k for k in range(1, 7)],
    ("branin", "rand-descents"): [FS_BRANIN + 0.4 * k for k in range(1, 7)],
    ("branin", "random"): [FS_BRANIN + k for k in range(1, 7)],                 # the worst
    ("styblinski-2", "cmaes"): [FS_STYB2 + 0.1 * k for k in range(1, 4)],      # 3 seeds only
    ("styblinski-2", "random"): [FS_STYB2 + k for k in range(1, 4)],
    ("sphere-2", "cmaes"): [2.0 + k for k in range(6)],
    ("sphere-2", "gd"): [0.5] * 6,                 # gd and nlopt-lbfgs: the very same curves
    ("sphere-2", "nlopt-lbfgs"): [0.5] * 6,
    ("bounce", "cmaes"): [1.0, 2.0, 3.0, 4.0],     # no known optimum
    ("bounce", "random"): [2.5, 3.5, 4.5, 5.5],
}
OVERVIEW_BUDGET = 40
# (env, optimizer, seed) -> episodes stored with a NaN loss (NULL); runs.failed_episodes stays 0
OVERVIEW_NAN = {("branin", "cmaes", 0): [0, 5], ("branin", "cmaes", 1): [3],
                ("bounce", "random", 2): [7, 8, 9]}
TAB10 = ["#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd", "#8c564b", "#e377c2", "#7f7f7f",
         "#bcbd22", "#17becf"]


def _overview_runs(con):
    """Every run replaced by the OVERVIEW_CELLS runs (_curve_runs), the OVERVIEW_NAN episodes NaN;
    plus one failed run of (branin, random) with two NaN episodes stored."""
    insert = _curve_runs(con, OVERVIEW_CELLS, OVERVIEW_NAN)
    insert("branin", "random", 6, 1.0, "failed")
    insert("hartmann6", "cmaes", 0, 1.0, "failed")     # an env whose only run failed


def _curve_runs(con, cells, nan_episodes):
    """Every run replaced by done runs of `cells` ((env, optimizer) -> final best losses, one per
    seed): OVERVIEW_BUDGET episodes whose loss falls as final + 10 / (episode + 1) - 10 / budget
    to the cell's final best loss at the last episode (the same curve for every seed with the same
    final loss), the episodes of nan_episodes ((env, optimizer, seed) -> episodes) NaN. Returns
    insert(env, optimizer, seed, final, status) for more runs."""
    env_h, opt_h, ver = con.execute(
        "SELECT env_config_hash, opt_config_hash, harness_version FROM runs LIMIT 1").fetchone()
    for table in ("replay", "evals", "runs"):
        con.execute(f"DELETE FROM {table}")
    b = OVERVIEW_BUDGET

    def insert(env, opt, seed, final, status):
        cur = con.execute(
            "INSERT INTO runs(env, optimizer, seed, budget, env_config_hash, opt_config_hash, "
            "rng_seed, status, episodes, best_loss, wall_s, harness_version, git_sha, host, error, "
            "results_versions) VALUES (?, ?, ?, ?, ?, ?, '0', ?, ?, ?, 0.1, ?, 'test', 'test', ?, ?)",
            (env, opt, seed, b, env_h, opt_h, status, b, final, ver,
             "blew up" if status == "failed" else None, versions_text(env, opt)))
        nan = nan_episodes.get((env, opt, seed), [0, 1] if status == "failed" else [])
        best = None
        for ep in range(b):
            loss = None if ep in nan else final + 10.0 / (ep + 1) - 10.0 / b
            if loss is not None:
                best = loss if best is None else min(best, loss)
            con.execute("INSERT INTO evals(run_id, episode, loss, best_loss, used_grad, wall_s, "
                        "failed) VALUES (?, ?, ?, ?, 0, 0.01, ?)",
                        (cur.lastrowid, ep, loss, best, int(loss is None)))

    for (env, opt), finals in cells.items():
        for seed, final in enumerate(finals):
            insert(env, opt, seed, final, "done")
    return insert


# Medians 1e-11 to 1.8 on cartpole1 (as its 1,000-episode grid has them): a log colour scale;
# bounce's 1 to 99 stays linear (ratio 99 <= 100)
LOG_CELLS = {("cartpole1", "nlopt-lbfgs"): [1e-11] * 5, ("cartpole1", "gd"): [1e-3] * 5,
             ("cartpole1", "cmaes"): [1e-2] * 5, ("cartpole1", "random"): [1.8] * 5,
             ("bounce", "cmaes"): [1.0] * 5, ("bounce", "gd"): [10.0] * 5,
             ("bounce", "random"): [99.0] * 5}


def hex_rgb(text):
    return tuple(int(text[i:i + 2], 16) for i in (1, 3, 5))


class TestOverviewLogScale(ReportCase):
    """Where an env's medians span orders of magnitude, the overview's colours follow their logs."""
    modify = staticmethod(lambda con: _curve_runs(con, LOG_CELLS, {}))

    def cells_of(self, env):
        sec = section(self.html, "overview")
        head = re.findall(r"<th>(.*?)</th>", html_rows(sec)[0])[1:]
        row = next(r for r in html_rows(sec)[1:] if f">{env}</a>" in r)
        tds = re.findall(r"<td([^>]*)>(.*?)</td>", row, re.S)
        out = {}
        for o, (attrs, text) in zip(head, tds[1:]):
            bg = re.search(r"background:(#[0-9a-f]{6})", attrs)
            out[o] = (re.sub(r"<[^>]+>", "", text), bg.group(1) if bg else None)
        return re.sub(r"<[^>]+>", "", tds[0][1]), out

    def test_log_scale_tells_1e_minus_11_from_1e_minus_3(self):
        name, cells = self.cells_of("cartpole1")
        self.assertEqual(name, "cartpole1 (40)log colour scale")
        span = math.log(1.8) - math.log(1e-11)
        self.assertEqual(cells["nlopt-lbfgs"][0], "0.00★ best")
        self.assertEqual(cells["gd"][0], f"{(math.log(1e-3) - math.log(1e-11)) / span:.2f}")  # 0.71
        self.assertEqual(cells["cmaes"][0], f"{(math.log(1e-2) - math.log(1e-11)) / span:.2f}")
        self.assertEqual(cells["random"][0], "1.00")
        green, gd = hex_rgb(cells["nlopt-lbfgs"][1]), hex_rgb(cells["gd"][1])
        self.assertEqual(cells["nlopt-lbfgs"][1], "#aadeaa")
        # on a linear scale gd's (1e-3 - 1e-11) / 1.8 = 0.0006 would be the winner's green to
        # the digit; on the log scale it is a pale red, 80 apart in red
        self.assertGreater(max(abs(p - q) for p, q in zip(green, gd)), 60, (green, gd))
        with open(self.file("summary.md"), encoding="utf-8") as f:
            self.assertIn("| cartpole1 (40, log colour scale) |", f.read())

    def test_two_decades_or_less_stay_linear(self):
        name, cells = self.cells_of("bounce")
        self.assertEqual(name, "bounce (40)")
        self.assertEqual(cells["gd"][0], f"{(10.0 - 1.0) / (99.0 - 1.0):.2f}")   # 0.09
        sys.path.insert(0, HERE)
        from dsb_report import tables
        self.assertFalse(tables.uses_log([1.0, 100.0]))
        self.assertTrue(tables.uses_log([1.0, 100.5, math.inf]))
        self.assertFalse(tables.uses_log([-1.0, 1e6]))     # a log scale needs positive medians


def png_rgba(path):
    """(width, height, rows) of an 8-bit RGB or RGBA, non-interlaced PNG; rows[y] is a list of
    (r, g, b) tuples. Standard library only (zlib and the five PNG filters)."""
    import struct
    import zlib
    with open(path, "rb") as f:
        data = f.read()
    assert data[:8] == b"\x89PNG\r\n\x1a\n", f"{path} is not a PNG"
    pos, idat, w = 8, b"", 0
    while pos < len(data):
        n, kind = struct.unpack(">I4s", data[pos:pos + 8])
        body = data[pos + 8:pos + 8 + n]
        if kind == b"IHDR":
            w, h, depth, ctype, _, _, interlace = struct.unpack(">IIBBBBB", body)
            assert depth == 8 and ctype in (2, 6) and interlace == 0, (depth, ctype, interlace)
            ch = 3 if ctype == 2 else 4
        elif kind == b"IDAT":
            idat += body
        pos += 12 + n
    raw = zlib.decompress(idat)
    stride = w * ch
    prev = bytearray(stride)
    rows = []
    for y in range(h):
        ftype = raw[y * (stride + 1)]
        line = bytearray(raw[y * (stride + 1) + 1:(y + 1) * (stride + 1)])
        for i in range(stride):
            a = line[i - ch] if i >= ch else 0
            c = prev[i - ch] if i >= ch else 0
            bb = prev[i]
            if ftype == 1:
                line[i] = (line[i] + a) & 255
            elif ftype == 2:
                line[i] = (line[i] + bb) & 255
            elif ftype == 3:
                line[i] = (line[i] + (a + bb) // 2) & 255
            elif ftype == 4:
                pa, pb, pc = abs(bb - c), abs(a - c), abs(a + bb - 2 * c)
                line[i] = (line[i] + (a if pa <= pb and pa <= pc else bb if pb <= pc else c)) & 255
        rows.append([tuple(line[x * ch:x * ch + 3]) for x in range(w)])
        prev = line
    return w, h, rows


def count_color(rows, hexcolor, x_max=None, tol=3):
    want = tuple(int(hexcolor[i:i + 2], 16) for i in (1, 3, 5))
    n = 0
    for row in rows:
        for px in row[:x_max]:
            if all(abs(p - q) <= tol for p, q in zip(px, want)):
                n += 1
    return n


class TestOverview(ReportCase):
    """The page opens with the answer: the overview of normalised medians (winner, ties, too few
    seeds), the failed episodes and runs, regret for known optima, curves that stay visible."""
    modify = staticmethod(_overview_runs)

    def overview_rows(self):
        sec = section(self.html, "overview")
        head = re.findall(r"<th>(.*?)</th>", html_rows(sec)[0])
        out = {}
        for row in html_rows(sec)[1:]:
            c = row_cells(row)
            out[c[0].split(" (")[0]] = dict(zip(head[1:], c[1:]))
        return sec, out

    def test_winner_ties_and_scores(self):
        sec, rows = self.overview_rows()
        b = rows["branin"]
        self.assertEqual(b["cmaes"], "0.00★ best")
        self.assertEqual(b["gd"], f"{0.0005 / (3.5 - 0.0035):.2f}≈ best")
        self.assertEqual(b["random"], "1.00")
        # (median - best) / (worst - best) with medians 0.35 (bobyqa), 0.0035 and 3.5
        self.assertEqual(b["nlopt-bobyqa"], f"{(0.35 - 0.0035) / (3.5 - 0.0035):.2f}")
        self.assertEqual(rows["sphere-2"]["random"], "—")
        self.assertIn('class="cell win"', sec)
        self.assertEqual(sec.count('class="cell win"'), 4)   # one winner per env

    def test_too_few_seeds_instead_of_a_tie(self):
        _, rows = self.overview_rows()
        self.assertEqual(rows["styblinski-2"]["random"], "1.00too few seeds")
        # 4 seeds a side, one comparison: 2/C(8,4) = 0.029 < 0.05, so a tie is a tie there
        self.assertEqual(rows["bounce"]["random"], "1.00≈ best")
        sig = {(r["env"], r["optimizer"]): r for r in read_csv(self.file("significance.csv"))}
        self.assertEqual(sig[("styblinski-2", "random")]["too_few_seeds"], "True")
        self.assertEqual(sig[("styblinski-2", "random")]["mark"], "too few seeds")
        self.assertEqual(sig[("branin", "gd")]["too_few_seeds"], "False")
        self.assertEqual(sig[("branin", "gd")]["mark"], "≈ best")
        panel = self.html.split('id="env-styblinski-2"')[1].split("<h3")[0].split("<table>")[1]
        self.assertNotIn("≈ best", panel)
        self.assertIn("<td>random</td>", panel)
        self.assertIn("<td>too few seeds</td>", panel)

    def test_failed_episodes_and_runs_equal_the_database(self):
        con = sqlite3.connect(self.db)
        nan = dict(((e, o), n) for e, o, n in con.execute(
            "SELECT r.env, r.optimizer, COUNT(*) FROM evals v JOIN runs r ON r.run_id = v.run_id "
            "WHERE v.loss IS NULL AND r.status = 'done' GROUP BY r.env, r.optimizer"))
        failed = dict(((e, o), n) for e, o, n in con.execute(
            "SELECT env, optimizer, COUNT(*) FROM runs WHERE status = 'failed' GROUP BY env, optimizer"))
        con.close()
        self.assertEqual(nan, {("branin", "cmaes"): 3, ("bounce", "random"): 3})
        self.assertEqual(failed, {("branin", "random"): 1, ("hartmann6", "cmaes"): 1})
        sec = section(self.html, "failures")
        head = re.findall(r"<th>(.*?)</th>", html_rows(sec)[0])
        seen = 0
        for row in html_rows(sec)[1:]:
            c = row_cells(row)
            env = c[0].split(" (")[0]
            for opt, cell in zip(head[1:], c[1:]):
                if (env, opt) not in OVERVIEW_CELLS and (env, opt) not in failed:
                    self.assertEqual(cell, "—")
                    continue
                self.assertEqual(cell, f"{nan.get((env, opt), 0)} / {failed.get((env, opt), 0)}",
                                 f"{env}/{opt}")
                seen += 1
        self.assertEqual(seen, len(OVERVIEW_CELLS) + 1)   # + hartmann6's failed run: "0 / 1"
        self.assertIn("In all: 6 failed episode(s), 2 failed run(s).", sec)
        final = {r["optimizer"]: r for r in read_csv(self.file("final_branin.csv"))}
        self.assertEqual((final["cmaes"]["failed_episodes"], final["random"]["failed_runs"]), ("3", "1"))

    def test_the_answer_comes_first_and_provenance_last(self):
        order = [self.html.index(f'<h2 id="{a}">') for a in
                 ("claims", "overview", "failures", "contents", "claims-detail", "across", "envs",
                  "significance", "provenance")]
        self.assertEqual(order, sorted(order))
        self.assertEqual(re.findall(r"<h2[^>]*>", self.html)[0], '<h2 id="claims">')
        # the compact verdicts at the top: claim, env, verdict, p, A12; one row per claim and env
        top = [c for c in map(row_cells, html_rows(section(self.html, "claims"))) if c]
        self.assertEqual(len(top), len(read_csv(self.file("claims.csv"))))
        # claim, env, verdict, p, A12, command; none of the paper's envs has a run here
        for c in top:
            self.assertEqual(len(c), 6)
            if c[2] != "not testable from the database":
                self.assertRegex(c[2], r"^runs missing: 0 of (at least )?[0-9]+ done$")
                self.assertEqual(c[5], f"harness --claims --env {c[1]} --seeds 5")
        with open(self.file("summary.md"), encoding="utf-8") as f:
            heads = [x for x in f.read().splitlines() if x.startswith("## ")]
        self.assertEqual(heads[:3], ["## The paper's claims",
                                     "## Overview: final results per env and optimizer",
                                     "## Failed episodes and failed runs"])
        self.assertEqual(heads[-1], "## Provenance")

    def test_regret_against_the_known_optimum(self):
        con = sqlite3.connect(self.db)
        for env, fs in (("branin", FS_BRANIN), ("styblinski-2", FS_STYB2)):
            rows = {r["optimizer"]: r for r in read_csv(self.file(f"final_{env}.csv"))}
            for opt, r in rows.items():
                vals = [v for (v,) in con.execute(
                    "SELECT best_loss FROM runs WHERE env = ? AND optimizer = ? AND status = 'done'",
                    (env, opt))]
                self.assertEqual(float(r["f_star"]), fs)
                self.assertAlmostEqual(float(r["regret_median"]), statistics.median(vals) - fs,
                                       delta=1e-12)
            sec = html.unescape(self.html.split(f'id="env-{env}"')[1].split("<h3")[0])
            self.assertIn(f"regret f − f*: the loss minus the env's known optimum f* = {fs:.10g}", sec)
            self.assertEqual(sec.count("Log y axis of the regret"), 2)   # curves and bars
        con.close()
        bounce = read_csv(self.file("final_bounce.csv"))
        self.assertEqual({r["f_star"] for r in bounce}, {""})
        self.assertNotIn("known optimum", self.html.split('id="env-bounce"')[1].split("<h3")[0])

    def test_a_curve_under_another_stays_visible(self):
        # gd and nlopt-lbfgs have the very same curves on sphere-2; lbfgs is drawn last, on top.
        opts = sorted({o for _, o in OVERVIEW_CELLS})
        w, h, rows = png_rgba(self.file("curves_sphere-2.png"))
        plot_area = int(w * 0.6)   # left of the legend (outside the axes, on the right)
        for o in ("gd", "nlopt-lbfgs"):
            n = count_color(rows, TAB10[opts.index(o)], plot_area)
            self.assertGreater(n, 60, f"{o}: {n} pixels of its colour in the plot area")

    def test_mean_labels_do_not_overlap_tick_labels(self):
        sys.path.insert(0, HERE)
        from dsb_report import data, plots, stats, style
        d = data.load(self.db)
        pn = next(p for p in d.panels if p.env == "branin")
        t = stats.final_table(pn, d.runs)
        style.setup()
        boxes = plots.finals(pn, t, style.palette(d.optimizers), style.yscale_for(pn.best, FS_BRANIN),
                             os.path.join(self.tmp, "bars.png"))
        self.assertEqual((len(boxes["means"]), len(boxes["ticks"])), (7, 7))

        def overlap(a, b):
            return a[0] < b[2] and b[0] < a[2] and a[1] < b[3] and b[1] < a[3]
        for m in boxes["means"]:
            for tk in boxes["ticks"]:
                self.assertFalse(overlap(m, tk), f"mean label {m} overlaps tick label {tk}")
            # and above the tick labels' top
            self.assertGreater(m[1], max(tk[3] for tk in boxes["ticks"]))


GRADIENT_QUALITY_COLUMNS = [
    "env", "surveyed", "dim", "points", "seed", "amplitude", "step", "tolerance", "large_step",
    "agreeing", "agree_fraction", "exactly_zero", "zero_fraction", "norm_min", "norm_median",
    "norm_max", "small_step_opposed", "large_step_directed", "large_step_opposed",
    "large_step_opposed_fraction", "large_step_flat", "large_step_ratio_median", "non_finite",
    "value_mismatches"]
# (env, surveyed, dim, points, agreeing, exactly_zero, norms, directed, opposed, ratio median)
GRADIENT_QUALITY_ROWS = [
    ("sphere-10", "sphere-10", 10, 100, 100, 0, (1.5, 7.25, 12.0), 100, 0, 1.0),
    ("pinball-4x4", "pinball-4x4", 16, 100, 28, 61, (0.0, 0.0, 3.5), 39, 10, 0.125),
    ("fluid", "fluid-h5", 10, 3, 1, 0, (0.01, 0.02, 0.04), 3, 2, -0.5),
]


def write_gradient_quality(path, drop=None):
    """A small CSV in the format of scripts/gradient-quality.sh; `drop` leaves a column out."""
    cols = [c for c in GRADIENT_QUALITY_COLUMNS if c != drop]
    with open(path, "w", newline="") as f:
        w = csv.DictWriter(f, cols, lineterminator="\n", extrasaction="ignore")
        w.writeheader()
        for env, surveyed, dim, n, agree, zero, (lo, med, hi), directed, opposed, ratio in \
                GRADIENT_QUALITY_ROWS:
            w.writerow(dict(env=env, surveyed=surveyed, dim=dim, points=n, seed=0, amplitude=0.5,
                            step=1e-06, tolerance=0.0001, large_step=0.05, agreeing=agree,
                            agree_fraction=f"{agree / n:.4f}", exactly_zero=zero,
                            zero_fraction=f"{zero / n:.4f}", norm_min=lo, norm_median=med,
                            norm_max=hi, small_step_opposed=0, large_step_directed=directed,
                            large_step_opposed=opposed,
                            large_step_opposed_fraction=f"{opposed / directed:.4f}",
                            large_step_flat=0, large_step_ratio_median=ratio, non_finite=0,
                            value_mismatches=0))
    return path


def section(html, anchor):
    """The HTML from <h2 id=anchor> to the next <h2>."""
    start = html.index(f'<h2 id="{anchor}">')
    end = html.find("<h2", start + 1)
    return html[start:end if end >= 0 else len(html)]


class TestGradientQuality(ReportCase):
    """--gradient-quality FILE: the section's table shows the file's rows."""
    extra = staticmethod(lambda tmp: ("--gradient-quality",
                                      write_gradient_quality(os.path.join(tmp, "gq.csv"))))

    def test_rows_of_the_file(self):
        rows = [c for c in map(row_cells, html_rows(section(self.html, "gradient-quality"))) if c]
        self.assertEqual(len(rows), 3)
        self.assertEqual(rows[0], ["sphere-10", "10", "100", "100.0%", "0.0%", "1.5", "7.25", "12",
                                   "0.0% of 100", "1"])
        self.assertEqual(rows[1], ["pinball-4x4", "16", "100", "28.0%", "61.0%", "0", "0", "3.5",
                                   "25.6% of 39", "0.125"])
        self.assertEqual(rows[2][0], "fluid (as fluid-h5)")
        self.assertEqual((rows[2][3], rows[2][8], rows[2][9]), ("33.3%", "66.7% of 3", "-0.5"))
        sec = section(self.html, "gradient-quality")
        self.assertIn("large step H = 0.05", sec)
        self.assertIn('<tr class="best"><td>sphere-10', sec)
        self.assertIn('<tr class="bad"><td>pinball-4x4', sec)
        self.assertIn('href="#gradient-quality"', self.html)

    def test_copy_and_summary(self):
        with open(self.file("gradient_quality.csv"), encoding="utf-8") as f:
            copied = f.read()
        with open(os.path.join(self.tmp, "gq.csv"), encoding="utf-8") as f:
            self.assertEqual(copied, f.read())
        with open(self.file("summary.md"), encoding="utf-8") as f:
            md = f.read()
        self.assertIn("## Gradient quality", md)
        self.assertIn("| fluid (as fluid-h5) | 10 | 3 | 33.3% |", md)


def write_renders(tmp):
    """A --renders folder: a picture for sphere-2 (any PNG will do) and one of an env without runs."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.image
    d = os.path.join(tmp, "renders")
    os.makedirs(d)
    for env in ("sphere-2", "nosuchenv"):
        matplotlib.image.imsave(os.path.join(d, f"render_{env}.png"), [[0.0, 1.0], [1.0, 0.0]])
    return ("--renders", d)


class TestRenders(ReportCase):
    """--renders DIR: render_<env>.png of the envs in the database are copied and shown in their
    section with the best run (smallest best_loss, ties to the smallest run_id) in the caption."""
    extra = staticmethod(write_renders)

    def test_copied_and_captioned(self):
        with open(os.path.join(self.tmp, "renders", "render_sphere-2.png"), "rb") as f:
            src = f.read()
        with open(self.file("render_sphere-2.png"), "rb") as f:
            self.assertEqual(f.read(), src)
        self.assertFalse(os.path.exists(self.file("render_nosuchenv.png")))
        con = sqlite3.connect(self.db)
        opt, seed, best = con.execute(
            "SELECT optimizer, seed, best_loss FROM runs WHERE env='sphere-2' AND status='done' AND "
            "best_loss IS NOT NULL ORDER BY best_loss, run_id LIMIT 1").fetchone()
        con.close()
        self.assertIn('src="render_sphere-2.png"', self.html)
        self.assertIn(f"sphere-2: best run ({opt}, seed {seed}, loss {best:.4g}) at 4 time points", self.html)
        # inside sphere-2's own section
        start = self.html.index('id="env-sphere-2"')
        self.assertGreater(self.html.index('src="render_sphere-2.png"'), start)
        self.assertEqual(self.html.count("<img src=\"render_"), 1)


class TestWinnerComparison(unittest.TestCase):
    """The overview's 'worse than the winner?' test: one-sided, so ten optimizers at the default
    5 seeds can be told apart after Holm (two-sided could not)."""

    def test_five_seeds_separate_nine_comparisons_one_sided_only(self):
        sys.path.insert(0, HERE)
        from dsb_report import stats
        # 9 comparisons x 1/C(10,5) = 0.036 < 0.05; two-sided 9 x 2/252 = 0.071
        self.assertFalse(stats.too_few_seeds(9, 5, 5, sides=1))
        self.assertTrue(stats.too_few_seeds(9, 5, 5, sides=2))
        self.assertFalse(stats.too_few_seeds(12, 5, 5, sides=1))  # 12/252 = 0.048
        self.assertTrue(stats.too_few_seeds(13, 5, 5, sides=1))   # 13/252 = 0.052
        import numpy as np
        best, worse = np.array([1.0, 2, 3, 4, 5]), np.array([6.0, 7, 8, 9, 10])
        self.assertAlmostEqual(stats.mwu_p(worse, best, "greater"), 1 / 252, places=12)
        self.assertAlmostEqual(stats.mwu_p(best, worse, "greater"), 1.0, places=12)
        adj = stats.holm([stats.mwu_p(worse, best, "greater")] * 9)
        self.assertLess(max(adj), 0.05)


class TestOneRunAgainstSeeds(unittest.TestCase):
    """An optimizer whose seeds are one run is one value: the other side's seeds are tested against
    it by the exact sign test, whose p-values are binomial tails worked out by hand."""

    def test_sign_test_exact_p(self):
        sys.path.insert(0, HERE)
        from dsb_report import stats
        import numpy as np
        c = 0.2024   # fluid's gd: its five seeds are one run
        five_below = np.array([0.003, 0.0031, 0.0029, 0.0035, 0.2])
        # all 5 of 5 below: P(Bin(5, 1/2) >= 5) = 1/32, where five copies of c as a Mann-Whitney
        # sample would give 0.0037 (U = 0; the five copies tie, so scipy's normal approximation
        # with the tie-corrected variance 25/12 (11 - 120/90) and continuity correction)
        self.assertEqual(stats.sign_test_p(five_below, c, "less"), 1 / 32)
        z = (0.5 - 12.5) / math.sqrt(25 / 12 * (11 - 120 / 90))
        self.assertAlmostEqual(stats.mwu_p(five_below, np.full(5, c), "less"),
                               0.5 * math.erfc(-z / math.sqrt(2)), places=12)
        # 4 of 5 below: P(Bin(5, 1/2) >= 4) = (5 + 1) / 32 = 0.1875; the other direction 31/32
        four_below = np.array([0.003, 0.0031, 0.0029, 0.0035, 0.216])
        self.assertEqual(stats.sign_test_p(four_below, c, "less"), 6 / 32)
        self.assertEqual(stats.sign_test_p(four_below, c, "greater"), 31 / 32)
        # two-sided: twice the smaller tail, 12/32
        self.assertEqual(stats.sign_test_p(four_below, c, "two-sided"), 12 / 32)
        # a value equal to c drops out: 4 below of 4 left, 1/16
        self.assertEqual(stats.sign_test_p(np.array([0.1, 0.1, 0.1, 0.1, c]), c, "less"), 1 / 16)
        self.assertEqual(stats.sign_test_p(np.full(3, c), c, "less"), 1.0)
        # compare_p: the constant on either side, the alternative mirrored; two constants by order
        self.assertEqual(stats.compare_p(np.array([c]), True, five_below, False, "greater"), 1 / 32)
        self.assertEqual(stats.compare_p(five_below, False, np.array([c]), True, "less"), 1 / 32)
        self.assertEqual(stats.compare_p(np.array([0.1]), True, np.array([c]), True, "less"), 0.0)
        self.assertEqual(stats.compare_p(np.array([0.1]), True, np.array([c]), True, "greater"), 1.0)
        # the seeds a claim needs against one run: 5 for one one-sided comparison (1/32 < 0.05 <
        # 1/16), 6 for two after Holm (2/64), 8 for eleven (11/256); 4 for two samples (1/70)
        self.assertEqual([stats.min_seeds(m, 1, against_one_run=True) for m in (1, 2, 11)], [5, 6, 8])
        self.assertEqual(stats.min_seeds(1, 1), 4)
        self.assertTrue(stats.too_few_seeds(1, 4, 1, sides=1, constant2=True))    # 1/16
        self.assertFalse(stats.too_few_seeds(1, 5, 1, sides=1, constant2=True))   # 1/32
        self.assertEqual(stats.holm([1 / 32, 6 / 32]), [2 / 32, 6 / 32])


class TestChartDeclarations(unittest.TestCase):
    """charts.check refuses a wrong declaration, naming the chart and what is wrong; charts.writes
    knows a chart's files (what make_report.py may remove) and nothing else."""

    def chart(self, name="bars", section=None, png="bars_{slug}.png"):
        charts, _ = chart_modules()
        return charts.Chart(name=name, section=section or charts.PER_ENV, png=png,
                            draw=lambda view, path: None, alt="bars {env}", caption="Bars.")

    def assert_refused(self, declared, *words):
        charts, _ = chart_modules()
        with self.assertRaises(ValueError) as e:
            charts.check(declared)
        for w in words:
            self.assertIn(w, str(e.exception))

    def test_the_report_charts_pass(self):
        charts, plots = chart_modules()
        charts.check(plots.CHARTS)
        self.assertEqual(len({c.name for c in plots.CHARTS}), len(plots.CHARTS))

    def test_a_name_declared_twice(self):
        self.assert_refused((self.chart(), self.chart(png="other_{slug}.png")), "'bars'", "twice")

    def test_an_unknown_section(self):
        self.assert_refused((self.chart(section="sidebar"),), "'bars'", "'sidebar'")

    def test_a_per_env_file_without_slug(self):
        self.assert_refused((self.chart(png="bars.png"),), "'bars'", "'bars.png'", "{slug}")

    def test_a_file_naming_another_field(self):
        self.assert_refused((self.chart(png="bars_{slug}_{env}.png"),), "'bars'", "{env}")

    def test_writes(self):
        charts, plots = chart_modules()
        for name in ("curves_sphere-2.png", "final_branin_b20.png", "ranks.png", "ecdf.png"):
            self.assertTrue(charts.writes(plots.CHARTS, name), name)
        for name in ("curves_.png", "final_branin.csv", "ranks.csv", "xcurves_a.png", "curves_a.pngx",
                     "notes.png"):
            self.assertFalse(charts.writes(plots.CHARTS, name), name)


class TestDeclaredChart(unittest.TestCase):
    """A chart is its function and its declaration: two more declared in plots.CHARTS (one per env,
    one across envs) are drawn and placed in their sections with their alt texts and captions,
    with no other change to the report's code."""

    @classmethod
    def setUpClass(cls):
        charts, plots = chart_modules()
        from dsb_report import build, data, style
        cls.tmp = tempfile.mkdtemp(prefix="dsb_report_chart_")
        db = copy_db(os.path.join(cls.tmp, "copy.sqlite"))
        cls.out = os.path.join(cls.tmp, "report")
        os.makedirs(cls.out)
        cls.calls = []   # (chart name, view, path) of every call of the two drawing functions

        def seeds_bars(view, path):   # the seeds of each optimizer on the env [optimizers]
            cls.calls.append(("seeds", view, path))
            fig, ax = style.plt.subplots(figsize=(4, 3))
            ax.bar(range(len(view.table)), view.table["n_seeds"])
            style.save(fig, path)

        def env_count(view, path):
            cls.calls.append(("envs", view, path))
            fig, ax = style.plt.subplots(figsize=(4, 3))
            ax.set_title(f"{view.n_envs} envs")
            style.save(fig, path)

        cls.extra = (charts.Chart("seeds", charts.PER_ENV, "seeds_{slug}.png", seeds_bars, "seeds {env}",
                                  "Seeds per optimizer on {env}. {scale}"),
                     charts.Chart("envs", charts.ACROSS, "envs.png", env_count, "env count",
                                  "How many envs were ranked."))
        saved = plots.CHARTS
        plots.CHARTS = saved + cls.extra
        try:
            cls.written = build.build(data.load(db), cls.out, None, "TestBuild", "2026-12-05T00:00:00Z")
        finally:
            plots.CHARTS = saved
        with open(os.path.join(cls.out, "index.html"), encoding="utf-8") as f:
            cls.html = f.read()
        cls.cells = cells(db)

    @classmethod
    def tearDownClass(cls):
        if not os.environ.get("DSB_REPORT_KEEP"):
            shutil.rmtree(cls.tmp, ignore_errors=True)

    def test_per_env_chart_in_every_env_section(self):
        keys = list(self.cells)
        self.assertEqual(len(keys), 2)
        for env, budget in keys:
            stem = final_csv_name(env, budget, keys)[len("final_"):-len(".csv")]
            png = f"seeds_{stem}.png"
            self.assertIn(png, self.written)
            # drawn once, into that file, from this env's panel and final table (seeds as in SQLite)
            views = [v for name, v, path in self.calls if name == "seeds" and path == os.path.join(self.out, png)]
            self.assertEqual(len(views), 1, png)
            self.assertEqual((views[0].panel.env, views[0].panel.budget), (env, budget))
            self.assertEqual(int(views[0].table["n_seeds"].sum()),
                             sum(len(v) for v in self.cells[(env, budget)].values()))
            w, h = png_size(os.path.join(self.out, png))
            self.assertTrue(300 < w <= 440 and 200 < h <= 330, (w, h))   # 4 x 3 in at 110 dpi, trimmed
            shown = figures_in(env_section(self.html, stem))
            self.assertEqual([f[0] for f in shown], [f"curves_{stem}.png", f"final_{stem}.png", png])
            self.assertEqual(shown[2][1], f"seeds {env}")
            self.assertTrue(shown[2][2].startswith(f"Seeds per optimizer on {env}. "), shown[2][2])
            self.assertRegex(shown[2][2], r"\. (Linear|Log) y axis")

    def test_across_chart_after_the_others_and_their_tables(self):
        sec = section(self.html, "across")
        self.assertEqual(figures_in(sec)[-1], ("envs.png", "env count", "How many envs were ranked."))
        self.assertEqual([f[0] for f in figures_in(sec)], ["ranks.png", "ecdf.png", "envs.png"])
        # the tables of ranks and of the data profile's targets stay under their charts
        at = [sec.index(x) for x in ('src="ranks.png"', "Mean rank at each episode count", 'src="ecdf.png"',
                                      "Targets per env", 'src="envs.png"')]
        self.assertEqual(at, sorted(at))
        self.assertEqual([(v.n_envs, path) for name, v, path in self.calls if name == "envs"],
                         [(2, os.path.join(self.out, "envs.png"))])
        w, h = png_size(os.path.join(self.out, "envs.png"))
        self.assertTrue(300 < w <= 440 and 200 < h <= 330, (w, h))
        self.assertIn('<a href="envs.png">', self.html)   # and in the list of files


class TestOldChartFiles(unittest.TestCase):
    """A report into a folder of an older one removes the older charts of envs no longer in the
    database (their names known from plots.CHARTS) and keeps a file that is not the report's."""

    def test_removed_and_kept(self):
        tmp = tempfile.mkdtemp(prefix="dsb_report_old_")
        self.addCleanup(shutil.rmtree, tmp, True)
        out = os.path.join(tmp, "report")
        os.makedirs(out)
        old = ["curves_gone.png", "final_gone.png", "final_gone.csv"]
        for name in old + ["notes.png"]:
            with open(os.path.join(out, name), "w") as f:
                f.write("old\n")
        proc = run_report(db_path(), out)
        self.assertEqual(proc.returncode, 0, proc.stderr)
        left = set(os.listdir(out))
        self.assertFalse(left & set(old), sorted(left & set(old)))
        self.assertIn("notes.png", left)
        self.assertIn("curves_sphere-2.png", left)


class TestReadOnlyDb(unittest.TestCase):
    """dsb_report.read_only_db: a read leaves the folder as found (the harness's rules)."""

    def setUp(self):
        if HERE not in sys.path:
            sys.path.insert(0, HERE)
        from dsb_report import read_only_db
        self.ro = read_only_db
        self.tmp = tempfile.mkdtemp(prefix="dsb_read_only_db_")
        self.addCleanup(shutil.rmtree, self.tmp, True)
        # a WAL database with a '?' and a '#' in its name, closed: nothing beside it
        self.db = os.path.join(self.tmp, "a?b#c.sqlite")
        con = sqlite3.connect(self.db)
        con.execute("PRAGMA journal_mode = WAL")
        con.execute("CREATE TABLE t (x)")
        con.execute("INSERT INTO t VALUES (1), (2)")
        con.commit()
        con.close()
        self.assertEqual(sidecar_files(self.tmp), [])
        self.sha = file_sha256(self.db)

    def test_a_database_nobody_has_open_is_read_and_left_without_files_beside_it(self):
        con = self.ro.connect(self.db)
        self.assertEqual(con.execute("SELECT sum(x) FROM t").fetchone(), (3,))
        with self.assertRaisesRegex(sqlite3.OperationalError, "readonly"):
            con.execute("INSERT INTO t VALUES (3)")
        con.close()
        self.assertEqual(sidecar_files(self.tmp), [])
        self.assertEqual(file_sha256(self.db), self.sha)
        # SQLite's plain read-only connection, which the scripts used until 2026-12-06, leaves two
        con = sqlite3.connect(self.ro.uri(self.db, "mode=ro"), uri=True)
        con.execute("SELECT sum(x) FROM t").fetchone()
        con.close()
        self.assertEqual(sidecar_files(self.tmp), ["a?b#c.sqlite-shm", "a?b#c.sqlite-wal"])

    def test_a_database_another_connection_holds_keeps_its_files(self):
        writer = sqlite3.connect(self.db)
        writer.execute("INSERT INTO t VALUES (5)")
        writer.commit()  # a frame in the -wal that only the -shm indexes
        held = sidecar_files(self.tmp)
        self.assertEqual(held, ["a?b#c.sqlite-shm", "a?b#c.sqlite-wal"])
        con = self.ro.connect(self.db)
        self.assertEqual(con.execute("SELECT sum(x) FROM t").fetchone(), (8,))
        with self.assertRaisesRegex(sqlite3.OperationalError, "readonly"):
            con.execute("INSERT INTO t VALUES (3)")
        con.close()
        self.assertEqual(sidecar_files(self.tmp), held)
        writer.close()
        self.assertEqual(sidecar_files(self.tmp), [])

    def test_a_database_the_user_may_not_write_in_a_folder_they_may(self):
        # SQLite opens such a file read-only whatever the mode says, and the folder lets it make the
        # -wal and -shm it then cannot remove; root may write anything, so the read runs as nobody
        os.chmod(self.tmp, 0o777)
        os.chmod(self.db, 0o444)
        as_user = ["setpriv", "--reuid=65534", "--regid=65534", "--clear-groups"] if os.geteuid() == 0 else []
        read = ("import sys; sys.path.insert(0, sys.argv[1]); from dsb_report import read_only_db; "
                "con = read_only_db.connect(sys.argv[2]); print(con.execute('SELECT sum(x) FROM t').fetchone()[0]); "
                "con.close()")
        out = subprocess.run(as_user + [sys.executable, "-c", read, HERE, self.db],
                             capture_output=True, text=True, check=True).stdout
        self.assertEqual(out.strip(), "3")
        self.assertEqual(sidecar_files(self.tmp), [])
        self.assertEqual(file_sha256(self.db), self.sha)


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

    def test_bad_claims_file(self):
        bad = os.path.join(self.tmp, "claims.csv")
        with open(bad, "w") as f:
            f.write("id,env,kind,a,b,statement,source\nx,cartpole1,a_beats_b,boleap,cmaes,s,t\n")
        line = self.assert_one_line_exit_2(run_report(db_path(), os.path.join(self.tmp, "out"),
                                                      "--claims", bad))
        self.assertIn("a_beats_b", line)

    def test_bad_gradient_quality_file(self):
        bad = write_gradient_quality(os.path.join(self.tmp, "gq.csv"), drop="large_step_opposed")
        line = self.assert_one_line_exit_2(run_report(db_path(), os.path.join(self.tmp, "out"),
                                                      "--gradient-quality", bad))
        self.assertIn("large_step_opposed", line)
        absent = os.path.join(self.tmp, "no_such.csv")
        line = self.assert_one_line_exit_2(run_report(db_path(), os.path.join(self.tmp, "out"),
                                                      "--gradient-quality", absent))
        self.assertIn(absent, line)

    def test_bad_harness(self):
        bad = os.path.join(self.tmp, "no_such_harness")
        line = self.assert_one_line_exit_2(run_report(db_path(), os.path.join(self.tmp, "out"),
                                                      "--harness", bad))
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
