"""A study's runs as one CSV file, a row per run, and back: what the project publishes from a grid
(data/study/runs.csv) and what the claims verdicts and results tables are regenerated from.

Columns (RUNS_CSV_COLUMNS): env, optimizer, seed, budget, status, episodes, best_loss (the run's
final best loss; empty when it has none), best_episode (the first episode that reached it),
metric_at_best (the env's second metric, evals.metric, at that episode; empty where the env has
none), wall_s, env_config_hash, opt_config_hash, harness_version, git_sha, seed_free_episodes (the
episodes before the optimizer's first draw from its RNG, runs.seed_free_episodes: equal to episodes
when no seed changes the run; empty where not recorded), results_versions (runs.results_versions,
"env E, optimizer O, run R": the code that made the run, docs/database.md; empty for runs made
before versions). Floats are written as
Python's repr, which reads back to the same bits, so verdicts and medians from the file are those
from the database. Every run is written, whatever its status (the claims table says which runs are
missing or incomplete); best_episode and metric_at_best only for the runs a report analyses
(data.load: one config variant per env, optimizer and budget).

A file without the last columns (written before they existed) is read with them empty: not
recorded (stats.seed_free counts none of its runs as one run; its runs name no results versions).

A Data read back from the file holds final values only: each panel's `best` is its runs' final
best loss as one column, so what needs whole curves (convergence plots, targets) is not for it.
"""
from __future__ import annotations

import csv
import math
import os

import numpy as np
import pandas as pd

from . import archive
from .data import Data, Panel, _choose_variants, slugify

RUNS_CSV_COLUMNS = ["env", "optimizer", "seed", "budget", "status", "episodes", "best_loss", "best_episode",
                    "metric_at_best", "wall_s", "env_config_hash", "opt_config_hash", "harness_version",
                    "git_sha", "seed_free_episodes", "results_versions"]
# absent from files written before they existed
OPTIONAL_COLUMNS = ["seed_free_episodes", "results_versions"]


class RunsCsvError(Exception):
    """The file cannot be read as a runs CSV (one-line message)."""


def _number(v) -> str:
    if v is None:
        return ""
    v = float(v)
    return "" if math.isnan(v) else repr(v)


def _count(v) -> str:
    """An integer count as text ('' when NULL)."""
    if v is None:
        return ""
    v = float(v)
    return "" if math.isnan(v) else str(int(v))


def write(data: Data, path: str) -> int:
    """Writes data's runs to `path` (a new file: an existing one is refused). Returns the rows."""
    if os.path.exists(path):
        raise RunsCsvError(f"'{path}' exists: remove it or name another file")
    at_best = {}
    for p in data.panels:
        final = p.best[:, -1] if p.best.size else np.zeros(0)
        for i, rid in enumerate(p.runs["run_id"].to_numpy()):
            episode = ""
            if p.best.shape[1] and np.isfinite(final[i]):
                episode = str(int(np.argmax(p.best[i] == final[i])))  # the first episode at the final best
            metric = p.metric_at_best[i] if p.metric_at_best.size else float("nan")
            at_best[int(rid)] = (episode, _number(metric))
    rows = []
    for r in data.runs.sort_values(["env", "optimizer", "budget", "seed", "run_id"]).itertuples(index=False):
        episode, metric = at_best.get(int(r.run_id), ("", ""))
        rows.append([r.env, r.optimizer, int(r.seed), int(r.budget), r.status, int(r.episodes),
                     _number(r.best_loss), episode, metric, _number(r.wall_s), r.env_config_hash,
                     r.opt_config_hash, r.harness_version, r.git_sha, _count(r.seed_free_episodes),
                     getattr(r, "results_versions", "") or ""])
    _write_rows(rows, path)
    return len(rows)


def write_archived(runs: list, path: str) -> int:
    """Writes the published archive's run objects (archive.read) to `path` as a runs CSV (a new
    file), each row what `write` gives the database the runs were archived from: the final best
    loss and its first episode rebuilt from the losses, the metric at that episode. Returns the rows."""
    if os.path.exists(path):
        raise RunsCsvError(f"'{path}' exists: remove it or name another file")
    rows = []
    for r in sorted(runs, key=lambda r: (r["env"], r["optimizer"], int(r["budget"]), int(r["seed"]))):
        final, episode = archive.final_best(r["loss"])
        metric = r.get("metric")
        at_best = metric[episode] if metric is not None and episode is not None else None
        episode = "" if episode is None else episode
        rows.append([r["env"], r["optimizer"], int(r["seed"]), int(r["budget"]), r["status"], int(r["episodes"]),
                     _number(final), episode, _number(at_best), _number(r.get("wall_s")), r["env_config_hash"],
                     r["opt_config_hash"], r["harness_version"], r.get("git_sha") or "",
                     _count(r.get("seed_free_episodes")), r.get("results_versions") or ""])
    _write_rows(rows, path)
    return len(rows)


def _write_rows(rows: list, path: str) -> None:
    """The header and rows to `path`, through a temporary file renamed over nothing."""
    tmp = path + ".tmp"
    with open(tmp, "w", newline="", encoding="utf-8") as f:
        w = csv.writer(f, lineterminator="\n")
        w.writerow(RUNS_CSV_COLUMNS)
        w.writerows(rows)
    os.replace(tmp, path)


RUN_KEY = ["env", "optimizer", "seed", "budget", "env_config_hash", "opt_config_hash"]


def _read(path: str) -> pd.DataFrame:
    try:
        runs = pd.read_csv(path, dtype={"env_config_hash": str, "opt_config_hash": str, "git_sha": str, "results_versions": str,
                                        "harness_version": str}, float_precision="round_trip",
                           keep_default_na=False, na_values=[""])
    except (OSError, pd.errors.ParserError, pd.errors.EmptyDataError) as e:
        raise RunsCsvError(f"cannot read '{path}': {e}") from None
    for c in OPTIONAL_COLUMNS:
        if c not in runs.columns:
            runs[c] = "" if c == "results_versions" else np.nan
    runs["results_versions"] = runs["results_versions"].fillna("").astype(str)
    absent = [c for c in RUNS_CSV_COLUMNS if c not in runs.columns]
    if absent:
        raise RunsCsvError(f"'{path}' lacks column(s) {', '.join(absent)}")
    return runs[RUNS_CSV_COLUMNS]


def load(*paths: str) -> Data:
    """The runs of one or more runs CSVs (a study's grids published apart, for example
    data/study/runs.csv and the fluid grid's pieces) as one Data of final values (see the module's
    docstring). A run (env, optimizer, seed, budget, config hashes) in two files is refused, naming
    both: the files are parts of one study, not versions of it."""
    if not paths:
        raise RunsCsvError("no runs CSV given")
    frames, origin = [], {}
    for path in paths:
        runs = _read(path)
        for key in runs[RUN_KEY].astype(str).itertuples(index=False, name=None):
            if key in origin:
                raise RunsCsvError(f"run {'/'.join(key[:4])} is in both '{origin[key]}' and '{path}'")
            origin[key] = path
        frames.append(runs)
    runs = pd.concat(frames, ignore_index=True) if len(frames) > 1 else frames[0]
    runs = runs.copy()
    runs.insert(0, "run_id", np.arange(1, len(runs) + 1))
    for c in ("best_loss", "wall_s", "metric_at_best", "seed_free_episodes"):
        runs[c] = pd.to_numeric(runs[c], errors="coerce").astype(float)
    selected, ignored = _choose_variants(runs[runs["status"] == "done"])
    panels = []
    budgets_per_env = selected.groupby("env")["budget"].nunique().to_dict()
    for (env, budget), g in selected.groupby(["env", "budget"], sort=True):
        g = g.sort_values(["optimizer", "seed"]).reset_index(drop=True)
        final = g["best_loss"].to_numpy(dtype=float)
        best = np.where(np.isnan(final), np.inf, final)[:, None]
        slug = slugify(env if budgets_per_env[env] == 1 else f"{env}_b{budget}")
        panels.append(Panel(env, int(budget), slug, g, best, np.full(len(g), np.nan),
                            sorted(g["optimizer"].unique()), g["metric_at_best"].to_numpy(dtype=float)))
    return Data(db_path=", ".join(paths), db_size=sum(os.path.getsize(p) for p in paths), meta={}, runs=runs,
                selected=selected, ignored=ignored, panels=panels, optimizers=sorted(runs["optimizer"].unique()))
