"""The published archive: every run of a study with its per-episode losses, so that anyone's new
runs can be compared with the published ones without rerunning them (docs/results.md, "Compare
your optimizer with the published runs").

An archive file is gzip-compressed JSON Lines, named NAME.runs.jsonl.gz, one object per run:

    {"archive": 1, "env": ..., "optimizer": ..., "seed": S, "budget": B,
     "env_config_hash": ..., "opt_config_hash": ..., "harness_version": ...,
     "results_versions": "env E, optimizer O, run R", "git_sha": ..., "status": "done",
     "episodes": N, "wall_s": W, "seed_free_episodes": K or null,
     "env_config": {...}, "opt_config": {...},
     "loss": [N numbers, null for a failed episode], "used_grad": "0110...",
     "metric": [N numbers or nulls] or null when the env records none}

The run key and results versions are those of the database it came from (docs/database.md); the
configs are the resolved ones the key's hashes name. Numbers are written as Python writes floats
(repr: the same bits read back), so the best-so-far curve, the final best loss and every table
rebuilt from an archive are those of the database. Only 'done' runs are archived (they are what a
study publishes). Objects are sorted by env, optimizer, budget, seed; a file's bytes depend only on
its runs (gzip without a name or time stamp).
"""
from __future__ import annotations

import glob
import gzip
import io
import json
import math
import os

import numpy as np
import pandas as pd

FORMAT = 1
SUFFIX = ".runs.jsonl.gz"
KEY = ["env", "optimizer", "seed", "budget", "env_config_hash", "opt_config_hash", "harness_version",
       "results_versions"]


class ArchiveError(Exception):
    """An archive file cannot be written or read (one-line message)."""


def _num(v):
    """A SQLite REAL as JSON: None for NULL or NaN (a failed episode), else the float."""
    if v is None:
        return None
    v = float(v)
    return None if math.isnan(v) else v


def runs_of_db(con) -> list:
    """Every 'done' run of an open harness database (sqlite3 connection) as archive objects."""
    cols = {r[1] for r in con.execute("PRAGMA table_info(runs)")}
    versions = "results_versions" if "results_versions" in cols else "''"
    seed_free = "seed_free_episodes" if "seed_free_episodes" in cols else "NULL"
    ev_cols = {r[1] for r in con.execute("PRAGMA table_info(evals)")}
    metric = "metric" if "metric" in ev_cols else "NULL"
    configs = dict(con.execute("SELECT hash, json FROM configs").fetchall())
    out = []
    for (run_id, env, opt, seed, budget, eh, oh, hv, rv, sha, status, episodes, wall, sf) in con.execute(
            f"SELECT run_id, env, optimizer, seed, budget, env_config_hash, opt_config_hash, "
            f"COALESCE(harness_version, ''), {versions}, COALESCE(git_sha, ''), status, episodes, wall_s, "
            f"{seed_free} FROM runs WHERE status = 'done' ORDER BY env, optimizer, budget, seed, run_id"):
        ev = con.execute(f"SELECT episode, loss, used_grad, {metric} FROM evals WHERE run_id = ? ORDER BY episode",
                         (run_id,)).fetchall()
        if [e[0] for e in ev] != list(range(len(ev))):
            raise ArchiveError(f"run {env}/{opt}/seed {seed}: its episodes are not 0..{len(ev) - 1}")
        metrics = [_num(e[3]) for e in ev]
        out.append({
            "archive": FORMAT, "env": env, "optimizer": opt, "seed": int(seed), "budget": int(budget),
            "env_config_hash": eh, "opt_config_hash": oh, "harness_version": hv, "results_versions": rv or "",
            "git_sha": sha, "status": status, "episodes": int(episodes), "wall_s": _num(wall),
            "seed_free_episodes": None if sf is None else int(sf),
            "env_config": json.loads(configs[eh]) if eh in configs else None,
            "opt_config": json.loads(configs[oh]) if oh in configs else None,
            "loss": [_num(e[1]) for e in ev],
            "used_grad": "".join("1" if e[2] else "0" for e in ev),
            "metric": metrics if any(m is not None for m in metrics) else None,
        })
    return out


def write(runs: list, path: str) -> int:
    """Writes archive objects to `path` (a new file, NAME.runs.jsonl.gz; an existing one is
    refused). Returns the number of runs."""
    if not path.endswith(SUFFIX):
        raise ArchiveError(f"'{path}': an archive file's name ends in {SUFFIX}")
    if os.path.exists(path):
        raise ArchiveError(f"'{path}' exists: remove it or name another file")
    folder = os.path.dirname(path) or "."
    if not os.path.isdir(folder):
        raise ArchiveError(f"'{path}': no folder '{folder}'")
    runs = sorted(runs, key=lambda r: (r["env"], r["optimizer"], r["budget"], r["seed"]))
    text = "".join(json.dumps(r, sort_keys=True, separators=(",", ":"), allow_nan=False) + "\n" for r in runs)
    buf = io.BytesIO()
    with gzip.GzipFile(filename="", mode="wb", fileobj=buf, mtime=0, compresslevel=9) as gz:
        gz.write(text.encode("utf-8"))
    tmp = path + ".tmp"
    with open(tmp, "wb") as f:
        f.write(buf.getvalue())
    os.replace(tmp, path)
    return len(runs)


def read(path: str) -> list:
    """The archive objects of one file (ArchiveError naming the file and line on damage)."""
    try:
        with gzip.open(path, "rt", encoding="utf-8") as f:
            lines = f.read().splitlines()
    except (OSError, EOFError, UnicodeDecodeError) as e:
        raise ArchiveError(f"cannot read archive '{path}': {e}") from None
    runs = []
    for n, line in enumerate(lines, 1):
        try:
            r = json.loads(line)
        except json.JSONDecodeError as e:
            raise ArchiveError(f"archive '{path}' line {n}: not JSON ({e.msg})") from None
        if not isinstance(r, dict) or r.get("archive") != FORMAT:
            raise ArchiveError(f"archive '{path}' line {n}: not a run of archive format {FORMAT}")
        missing = [k for k in KEY + ["status", "episodes", "loss", "used_grad"] if k not in r]
        if missing:
            raise ArchiveError(f"archive '{path}' line {n}: no {', '.join(missing)}")
        if len(r["loss"]) != r["episodes"] or len(r["used_grad"]) != r["episodes"]:
            raise ArchiveError(f"archive '{path}' line {n}: {len(r['loss'])} losses for {r['episodes']} episodes")
        runs.append(r)
    return runs


def files_under(folder: str) -> list:
    """The archive files of a folder and its subfolders, sorted."""
    if os.path.isfile(folder):
        return [folder]
    if not os.path.isdir(folder):
        raise ArchiveError(f"archive '{folder}': no such folder")
    return sorted(glob.glob(os.path.join(folder, "**", "*" + SUFFIX), recursive=True))


def best_so_far(losses) -> np.ndarray:
    """The best loss after each episode (NaN = a failed episode, never a best; +inf while none)."""
    a = np.array([np.nan if v is None else v for v in losses], dtype=float)
    a = np.where(np.isnan(a), np.inf, a)
    return np.minimum.accumulate(a) if a.size else a


def final_best(losses) -> tuple:
    """(the run's final best loss, the first episode that reached it); (NaN, None) when no episode
    gave a finite loss."""
    best = best_so_far(losses)
    finite = best[np.isfinite(best)]
    if not finite.size:
        return float("nan"), None
    return float(finite[-1]), int(np.argmax(best == finite[-1]))


def frames(runs: list, first_run_id: int = 1):
    """(runs, evals) DataFrames in the shape data.load reads from a database, for archive objects:
    run_ids from first_run_id on, best_loss rebuilt from the losses, status 'done'."""
    rows, ev = [], []
    for i, r in enumerate(runs):
        rid = first_run_id + i
        best = best_so_far(r["loss"])
        finite = best[np.isfinite(best)]
        rows.append({
            "run_id": rid, "env": r["env"], "optimizer": r["optimizer"], "seed": r["seed"], "budget": r["budget"],
            "env_config_hash": r["env_config_hash"], "opt_config_hash": r["opt_config_hash"],
            "status": r["status"], "episodes": r["episodes"],
            "failed_episodes": sum(v is None for v in r["loss"]),
            "best_loss": float(finite[-1]) if finite.size else np.nan,
            "wall_s": np.nan if r.get("wall_s") is None else float(r["wall_s"]),
            "error": None, "started_at": None, "finished_at": None,
            "harness_version": r["harness_version"], "git_sha": r.get("git_sha", ""), "host": "archive",
            "seed_free_episodes": np.nan if r.get("seed_free_episodes") is None else float(r["seed_free_episodes"]),
            "results_versions": r["results_versions"],
        })
        metric = r.get("metric")
        for k, v in enumerate(r["loss"]):
            ev.append((rid, k, np.nan if v is None else v, np.nan if not np.isfinite(best[k]) else best[k],
                       np.nan if metric is None or metric[k] is None else metric[k]))
    runs_df = pd.DataFrame(rows)
    ev_df = pd.DataFrame(ev, columns=["run_id", "episode", "loss", "best_loss", "metric"])
    return runs_df, ev_df
