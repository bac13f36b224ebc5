"""The expected grid and what is not done in it.

Expected grid = every (env, optimizer) pair with at least one run in the database (any status)
x seed indices 0..max seed present in the database x every budget present for that env.
Gradient optimizers never run on non-differentiable envs, so pairs are taken from the database
rather than from a full product of names.
"""
from __future__ import annotations

import pandas as pd

MISSING_COLUMNS = ["env", "optimizer", "seed", "budget", "reason", "error"]


def missing_runs(runs: pd.DataFrame) -> pd.DataFrame:
    """Every expected (env, optimizer, seed, budget) without a 'done' run, with the reason:
    'failed' or 'running' when such a run exists (error text of the newest one), else 'absent'."""
    if runs.empty:
        return pd.DataFrame(columns=MISSING_COLUMNS)
    max_seed = int(runs["seed"].max())
    seeds = range(0, max_seed + 1)
    budgets = runs.groupby("env")["budget"].unique().to_dict()
    pairs = runs[["env", "optimizer"]].drop_duplicates().itertuples(index=False)
    done = set(runs.loc[runs["status"] == "done", ["env", "optimizer", "seed", "budget"]]
               .itertuples(index=False, name=None))
    latest = (runs.sort_values("run_id").drop_duplicates(["env", "optimizer", "seed", "budget"],
                                                        keep="last")
              .set_index(["env", "optimizer", "seed", "budget"]))
    rows = []
    for env, opt in pairs:
        for budget in sorted(int(b) for b in budgets[env]):
            for seed in seeds:
                key = (env, opt, seed, budget)
                if key in done:
                    continue
                reason, error = "absent", ""
                if key in latest.index:
                    r = latest.loc[key]
                    reason = str(r["status"])
                    error = "" if pd.isna(r["error"]) else str(r["error"])
                rows.append((env, opt, seed, budget, reason, error))
    out = pd.DataFrame(rows, columns=MISSING_COLUMNS)
    return out.sort_values(["env", "optimizer", "budget", "seed"]).reset_index(drop=True)


def runs_with_status(runs: pd.DataFrame, status: str) -> pd.DataFrame:
    cols = ["env", "optimizer", "seed", "budget", "run_id", "error", "started_at", "finished_at",
            "host"]
    return runs.loc[runs["status"] == status, cols].reset_index(drop=True)
