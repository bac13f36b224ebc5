"""Read a harness database (read-only) into the frames and arrays the report needs.

Analysis unit: a *panel* = (env, budget). Within a panel each optimizer contributes its 'done'
runs, one per seed. If one (env, optimizer, budget) has runs under more than one config variant
(env_config_hash, opt_config_hash), the variant with the most 'done' runs is analysed (ties: the
one with the newest run) and the others are listed in the report, never mixed silently.

Runs made by other results versions than the harness's (stale, staleness.py) are left out before
anything else, or with include_stale analysed as optimizers of their own (OPT-stale-...).
"""
from __future__ import annotations

import os
import re
import sqlite3
from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from . import archive, read_only_db, staleness, with_archive

RUN_COLUMNS = ["run_id", "env", "optimizer", "seed", "budget", "env_config_hash",
               "opt_config_hash", "status", "episodes", "failed_episodes", "best_loss",
               "wall_s", "error", "started_at", "finished_at", "harness_version", "git_sha",
               "host"]
# read when the database has it (schema version 4 on; NULL or absent: not recorded): the episodes
# of a run before its optimizer's first draw from its RNG (stats.seed_free)
OPTIONAL_RUN_COLUMNS = ["seed_free_episodes"]
# read when the database has it (schema version 5 on; absent: '', made before results versions)
VERSIONS_COLUMN = "results_versions"


class DataError(Exception):
    """The database cannot be read as a harness database (one-line message)."""


@dataclass
class Panel:
    env: str
    budget: int
    slug: str                 # file-name part: env, or env_b<budget> when an env has several budgets
    runs: pd.DataFrame        # selected 'done' runs, sorted by optimizer, seed
    best: np.ndarray          # [n_runs, budget] best loss so far after episode k+1; +inf = none yet
    first_loss: np.ndarray    # [n_runs] loss of episode 0 (NaN if failed or absent)
    optimizers: list = field(default_factory=list)
    # [n_runs] the env's second metric (evals.metric, e.g. PlasticineLab's soft IoU) of the
    # episode that reached the run's final best loss (the first such episode); NaN where none
    metric_at_best: np.ndarray = field(default_factory=lambda: np.zeros(0))

    @property
    def has_metric(self) -> bool:
        return bool(np.any(np.isfinite(self.metric_at_best)))

    def rows(self, optimizer: str) -> np.ndarray:
        return np.flatnonzero(self.runs["optimizer"].to_numpy() == optimizer)

    def subset(self, keep: np.ndarray):
        """The panel of the runs where keep ([n_runs] bool) is True; None when none is."""
        if not keep.any():
            return None
        runs = self.runs[keep].reset_index(drop=True)
        return Panel(self.env, self.budget, self.slug, runs, self.best[keep], self.first_loss[keep],
                     sorted(runs["optimizer"].unique()), self.metric_at_best[keep])

    @property
    def fstar(self) -> float:
        finite = self.best[np.isfinite(self.best)]
        return float(finite.min()) if finite.size else float("nan")

    @property
    def f0(self) -> float:
        v = self.first_loss[np.isfinite(self.first_loss)]
        return float(np.median(v)) if v.size else float("nan")


@dataclass
class Data:
    db_path: str
    db_size: int
    meta: dict
    runs: pd.DataFrame        # every run, any status
    selected: pd.DataFrame    # 'done' runs analysed (one config variant per env, optimizer, budget)
    ignored: pd.DataFrame     # 'done' runs of other config variants
    panels: list
    optimizers: list          # sorted names of every optimizer in the database
    # the runs made by other results versions, and what was done with them (staleness.py)
    stale: staleness.Staleness = field(default_factory=lambda: staleness.Staleness(judged=False))
    # the published archive's runs joined to the database's (with_archive.py), None without --with
    archive: object = None


def slugify(text: str) -> str:
    return re.sub(r"[^A-Za-z0-9._-]", "_", text)


def connect_ro(path: str) -> sqlite3.Connection:
    """Opens a harness database to read it, leaving its folder as found (read_only_db: the
    harness's rules, immutable where a WAL database's -shm file cannot be made)."""
    if not os.path.isfile(path):
        raise DataError(f"cannot read database '{path}': no such file")
    try:
        con = read_only_db.connect(path)
        tables = {r[0] for r in con.execute("SELECT name FROM sqlite_master WHERE type='table'")}
    except sqlite3.Error as e:
        raise DataError(f"cannot read database '{path}': {e}") from None
    missing = {"runs", "evals", "meta"} - tables
    if missing:
        raise DataError(f"'{path}' is not a harness database (no table {', '.join(sorted(missing))})")
    return con


def _choose_variants(done: pd.DataFrame):
    """Split 'done' runs into the analysed config variant per (env, optimizer, budget) and the rest."""
    if done.empty:
        return done, done
    key = ["env", "optimizer", "budget"]
    var = ["env_config_hash", "opt_config_hash"]
    counts = (done.groupby(key + var).agg(n=("run_id", "size"), newest=("run_id", "max"))
              .reset_index().sort_values(key + ["n", "newest"], ascending=[True] * 3 + [False] * 2))
    chosen = counts.drop_duplicates(key)[key + var]
    merged = done.merge(chosen.assign(_keep=True), on=key + var, how="left")
    keep = merged["_keep"].eq(True).to_numpy()
    sel = done[keep]
    # one run per seed inside the variant (the UNIQUE key guarantees it; stay safe anyway)
    sel = sel.sort_values("run_id").drop_duplicates(key + ["seed"], keep="last")
    return sel.sort_values(["env", "budget", "optimizer", "seed"]).reset_index(drop=True), \
        done[~keep].reset_index(drop=True)


def _best_matrix(runs: pd.DataFrame, ev: pd.DataFrame, budget: int):
    n = len(runs)
    best = np.full((n, budget), np.nan)
    first = np.full(n, np.nan)
    if n and not ev.empty:
        row_of = pd.Series(np.arange(n), index=runs["run_id"].to_numpy())
        ev = ev[ev["run_id"].isin(row_of.index) & (ev["episode"] >= 0) & (ev["episode"] < budget)]
        r = row_of.loc[ev["run_id"].to_numpy()].to_numpy()
        e = ev["episode"].to_numpy()
        b = ev["best_loss"].to_numpy(dtype=float)
        best[r, e] = np.where(np.isnan(b), np.inf, b)       # NULL best = no finite loss yet
        m0 = e == 0
        first[r[m0]] = ev["loss"].to_numpy(dtype=float)[m0]
    # episodes without a row (a run that stopped early) keep the last best; none yet = +inf
    best = pd.DataFrame(best).ffill(axis=1).to_numpy()
    best[np.isnan(best)] = np.inf
    return best, first


def _metric_at_best(runs: pd.DataFrame, ev: pd.DataFrame, budget: int) -> np.ndarray:
    out = np.full(len(runs), np.nan)
    if "metric" not in ev.columns or ev.empty:
        return out
    for i, rid in enumerate(runs["run_id"].to_numpy()):
        e = ev[(ev["run_id"] == rid) & (ev["episode"] >= 0) & (ev["episode"] < budget)]
        loss = e["loss"].to_numpy(dtype=float)
        if not np.any(np.isfinite(loss)):
            continue
        k = int(np.nanargmin(loss))   # the first episode of the smallest loss
        out[i] = float(e["metric"].to_numpy(dtype=float)[k])
    return out


def load(path: str, registry=None, include_stale: bool = False, archive_dir=None) -> Data:
    """The database at path. registry: `harness list` of the harness whose results versions make a
    run current (None: staleness not judged, every run kept); include_stale: analyse stale runs as
    optimizers of their own instead of leaving them out; archive_dir: a folder of the published
    archive whose runs join the database's (with_archive.py)."""
    con = connect_ro(path)
    try:
        meta = dict(con.execute("SELECT key, value FROM meta").fetchall())
        cols = [r[1] for r in con.execute("PRAGMA table_info(runs)")]
        absent = [c for c in RUN_COLUMNS if c not in cols]
        if absent:
            raise DataError(f"'{path}': table runs lacks column(s) {', '.join(absent)}")
        optional = [c for c in OPTIONAL_RUN_COLUMNS + [VERSIONS_COLUMN] if c in cols]
        runs = pd.read_sql_query(f"SELECT {', '.join(RUN_COLUMNS + optional)} FROM runs", con)
        for c in OPTIONAL_RUN_COLUMNS:
            if c not in runs.columns:
                runs[c] = np.nan
        if VERSIONS_COLUMN not in runs.columns:
            runs[VERSIONS_COLUMN] = ""
        runs[VERSIONS_COLUMN] = runs[VERSIONS_COLUMN].fillna("").astype(str)
        ev_cols = [r[1] for r in con.execute("PRAGMA table_info(evals)")]
        metric = ", e.metric" if "metric" in ev_cols else ""  # schema version 2 on
        ev = pd.read_sql_query(
            f"SELECT e.run_id, e.episode, e.loss, e.best_loss{metric} FROM evals e "
            "JOIN runs r ON r.run_id = e.run_id WHERE r.status = 'done' "
            "ORDER BY e.run_id, e.episode", con)
    except sqlite3.Error as e:
        raise DataError(f"cannot read database '{path}': {e}") from None
    finally:
        con.close()
    for c in ("best_loss", "wall_s", "seed_free_episodes"):
        runs[c] = pd.to_numeric(runs[c], errors="coerce").astype(float)
    ev["loss"] = pd.to_numeric(ev["loss"], errors="coerce").astype(float)
    ev["best_loss"] = pd.to_numeric(ev["best_loss"], errors="coerce").astype(float)
    if "metric" in ev.columns:
        ev["metric"] = pd.to_numeric(ev["metric"], errors="coerce").astype(float)
    runs = runs.sort_values(["env", "optimizer", "seed", "budget", "run_id"]).reset_index(drop=True)
    # failed episodes of a done run: its stored episodes whose loss is NaN (evals.loss NULL), counted
    # from the episodes themselves rather than trusting runs.failed_episodes
    nan_eps = ev.loc[ev["loss"].isna(), "run_id"].value_counts()
    done = runs["status"] == "done"
    runs["failed_episodes"] = pd.to_numeric(runs["failed_episodes"], errors="coerce").fillna(0)
    runs.loc[done, "failed_episodes"] = runs.loc[done, "run_id"].map(nan_eps).fillna(0)
    runs["failed_episodes"] = runs["failed_episodes"].astype(int)
    use = None
    if archive_dir is not None:
        try:
            runs, ev, use = with_archive.join(runs, ev, archive_dir)
        except archive.ArchiveError as e:
            raise DataError(str(e)) from None
    runs, stale = staleness.judge(runs, registry, include_stale)
    runs = runs.sort_values(["env", "optimizer", "seed", "budget", "run_id"]).reset_index(drop=True)

    selected, ignored = _choose_variants(runs[runs["status"] == "done"])
    panels = []
    budgets_per_env = selected.groupby("env")["budget"].nunique().to_dict()
    for (env, budget), g in selected.groupby(["env", "budget"], sort=True):
        g = g.sort_values(["optimizer", "seed"]).reset_index(drop=True)
        gev = ev[ev["run_id"].isin(g["run_id"])]
        best, first = _best_matrix(g, gev, int(budget))
        slug = slugify(env if budgets_per_env[env] == 1 else f"{env}_b{budget}")
        panels.append(Panel(env, int(budget), slug, g, best, first,
                            sorted(g["optimizer"].unique()),
                            _metric_at_best(g, gev, int(budget))))
    return Data(db_path=path, db_size=os.path.getsize(path), meta=meta, runs=runs,
                selected=selected, ignored=ignored, panels=panels,
                optimizers=sorted(runs["optimizer"].unique()), stale=stale, archive=use)


def main_panels(data: Data, panels=None) -> list:
    """One panel per env for the across-env views: the one with the largest budget (of `panels`,
    default data.panels)."""
    out = {}
    for p in data.panels if panels is None else panels:
        if p.env not in out or p.budget > out[p.env].budget:
            out[p.env] = p
    return [out[e] for e in sorted(out)]


def current_view(data: Data):
    """(one panel per env, runs) of the current runs only: what the claims judge. Without stale
    runs shown these are main_panels(data) and data.runs."""
    if not data.stale.shown or not data.stale.count:
        return main_panels(data), data.runs
    panels = [q for q in (p.subset(~p.runs["stale"].to_numpy(dtype=bool)) for p in data.panels) if q is not None]
    return main_panels(data, panels), data.runs[~data.runs["stale"]].reset_index(drop=True)
