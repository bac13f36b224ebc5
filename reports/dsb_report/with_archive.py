"""A user's runs beside the published archive's (make_report.py --with DIR, `harness report
--with DIR`): the archived runs (archive.py) join the database's as runs of their own source, so
the overview, curves, significance tests and claims rank a new optimizer against the published
ones without rerunning them.

- Every run gets `source`: "yours" (the database) or "archived" (DIR's files).
- An archived run whose key (env, optimizer, seed, budget, config hashes, harness version and
  results versions) the database also holds is counted once: the database's copy is kept, and the
  note says how many such runs repeat the archived ones bit for bit (every episode's loss) and
  names those that do not (a reproducibility break worth a look).
- Archived runs of other results versions than the harness's are stale like any other
  (staleness.py): left out, and said, unless --include-stale.
- The note names the database's envs the archive has no runs of, and the archive's envs the
  database has no runs of.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from . import archive

KEY = ["env", "optimizer", "seed", "budget", "env_config_hash", "opt_config_hash", "harness_version",
       "results_versions"]


@dataclass
class ArchiveUse:
    folder: str
    files: int = 0
    runs: int = 0                    # archived runs read
    added: int = 0                   # of them, joined beside the database's runs
    repeated: int = 0                # database runs that repeat an archived run bit for bit
    differ: list = field(default_factory=list)      # keys (text) whose episodes differ
    only_yours: list = field(default_factory=list)  # envs of the database the archive lacks
    only_archived: list = field(default_factory=list)  # envs of the archive the database lacks

    def note(self) -> str:
        text = (f"Archive {self.folder}: {self.runs} archived runs in {self.files} files, {self.added} shown "
                f"beside the database's (marked archived)")
        if self.repeated or self.differ:
            text += (f"; {self.repeated + len(self.differ)} of the database's runs have an archived run's key and "
                     f"are counted once, the database's copy kept ({self.repeated} repeat it bit for bit")
            text += (f", {len(self.differ)} differ: " + "; ".join(self.differ[:10]) +
                     (f" and {len(self.differ) - 10} more" if len(self.differ) > 10 else "") + ")"
                     if self.differ else ")")
        if self.only_yours:
            text += "; the archive has no runs of " + ", ".join(self.only_yours) + " (yours alone there)"
        return text + "."


def _key_text(row) -> str:
    return f"{row['env']}/{row['optimizer']}/seed {row['seed']}/budget {row['budget']}"


def join(runs: pd.DataFrame, ev: pd.DataFrame, folder: str):
    """(runs, evals, ArchiveUse): the database's frames with DIR's archived runs added. runs of the
    database get source 'yours'; run_ids of archived runs follow the database's."""
    runs = runs.copy()
    runs["source"] = "yours"
    use = ArchiveUse(folder=folder)
    files = archive.files_under(folder)
    use.files = len(files)
    objs = [r for f in files for r in archive.read(f)]
    use.runs = len(objs)
    if not objs:
        return runs, ev, use
    first = int(runs["run_id"].max()) + 1 if len(runs) else 1
    arun, aev = archive.frames(objs, first)
    arun["source"] = "archived"
    # counted once: the database's copy of a key both hold
    mine = runs[runs["status"] == "done"]
    mine_key = {tuple(str(v) for v in r): rid for r, rid in
                zip(mine[KEY].itertuples(index=False, name=None), mine["run_id"])}
    drop = []
    for r in arun.itertuples(index=False):
        k = tuple(str(getattr(r, c)) for c in KEY)
        if k not in mine_key:
            continue
        drop.append(r.run_id)
        a = aev.loc[aev["run_id"] == r.run_id, "loss"].to_numpy(dtype=float)
        m = ev.loc[ev["run_id"] == mine_key[k], "loss"].to_numpy(dtype=float)
        same = a.shape == m.shape and np.array_equal(a.view(np.uint64), m.view(np.uint64))
        if same:
            use.repeated += 1
        else:
            use.differ.append(_key_text(r._asdict()))
    arun = arun[~arun["run_id"].isin(drop)]
    aev = aev[~aev["run_id"].isin(drop)]
    use.added = len(arun)
    have, archived_envs = set(runs["env"]), {o["env"] for o in objs}
    use.only_yours = sorted(have - archived_envs)
    use.only_archived = sorted(archived_envs - have)
    if "metric" not in ev.columns:
        ev = ev.assign(metric=np.nan)
    return (pd.concat([runs, arun], ignore_index=True),
            pd.concat([ev, aev[ev.columns]], ignore_index=True), use)


def sources(runs: pd.DataFrame) -> pd.DataFrame:
    """env, optimizer, yours, archived: the done runs of each source (the overview's table)."""
    done = runs[runs["status"] == "done"]
    if done.empty or "source" not in done.columns:
        return pd.DataFrame(columns=["env", "optimizer", "yours", "archived"])
    t = done.groupby(["env", "optimizer", "source"]).size().unstack(fill_value=0).reset_index()
    for c in ("yours", "archived"):
        if c not in t.columns:
            t[c] = 0
    return t[["env", "optimizer", "yours", "archived"]].sort_values(["env", "optimizer"]).reset_index(drop=True)


def label(panel, optimizer: str) -> str:
    """A legend's name of an optimizer in a panel: 'cmaes (n=5)', 'cmaes (n=5, archived)' or
    'cmaes (n=8, 5 archived)'."""
    rows = panel.rows(optimizer)
    n = rows.size
    if "source" not in panel.runs.columns:
        return f"{optimizer} (n={n})"
    k = int((panel.runs["source"].to_numpy()[rows] == "archived").sum())
    if k == 0:
        return f"{optimizer} (n={n})"
    return f"{optimizer} (n={n}, archived)" if k == n else f"{optimizer} (n={n}, {k} archived)"
