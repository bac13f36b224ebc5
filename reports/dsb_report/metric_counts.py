"""How many seeds of each optimizer reach a metric claim's threshold (the cube lifted over the rim
for `fluid`): for each (env, threshold) of a claim of kind metric_most or metric_few, every
optimizer with a done run of the env counts the runs whose second metric at their best episode
(evals.metric, Panel.metric_at_best) is >= the threshold, out of its runs at the env's largest
budget. The claim's verdict looks at its own optimizers only; this table shows them all, so that a
reader sees who else lifts the cube. One place for the README's block (scripts/study_results.py)
and the report (claims_metric_counts.csv, index.html, summary.md).
"""
from __future__ import annotations

import numpy as np
import pandas as pd

from .claims import METRIC_KINDS

COLUMNS = ["env", "threshold", "optimizer", "reached", "runs", "with_metric", "seed_free"]


def thresholds(claims) -> list:
    """(env, threshold) of every metric claim, in the claims' order, each once."""
    seen = []
    for c in claims:
        if c.kind not in METRIC_KINDS:
            continue
        for env in c.envs:
            if (env, c.threshold) not in seen:
                seen.append((env, c.threshold))
    return seen


def table(claims, panels) -> pd.DataFrame:
    """One row per (env, threshold, optimizer with a done run): reached (runs whose metric at the
    best episode >= threshold), runs, with_metric (runs with a finite metric there), seed_free
    (its seeds are one run: stats.seed_free)."""
    from . import stats
    by_env = {p.env: p for p in panels}
    rows = []
    for env, threshold in thresholds(claims):
        p = by_env.get(env)
        if p is None:
            continue
        for o in p.optimizers:
            idx = p.rows(o)
            m = p.metric_at_best[idx] if p.metric_at_best.size else np.full(idx.size, np.nan)
            rows.append([env, threshold, o, int(np.sum(m >= threshold)), int(idx.size),
                         int(np.sum(np.isfinite(m))), stats.seed_free(p, o)])
    return pd.DataFrame(rows, columns=COLUMNS)


def cell(r) -> str:
    """'3 of 5', '0 of 5 (one run)' where its seeds are one run, or 'no metric' where none of the
    optimizer's runs has one."""
    if not r["with_metric"]:
        return "no metric"
    return f"{r['reached']} of {r['runs']}" + (" (one run)" if r.get("seed_free", False) else "")


def wide(t: pd.DataFrame):
    """The table one row per (env, threshold) and a column per optimizer: (headers, rows)."""
    opts = list(dict.fromkeys(t["optimizer"]))
    rows = []
    for (env, threshold), g in t.groupby(["env", "threshold"], sort=False):
        cells = {r["optimizer"]: cell(r) for _, r in g.iterrows()}
        rows.append([env, f"{threshold:g}"] + [cells.get(o, "—") for o in opts])
    return ["env", "threshold"] + opts, rows


def lines(claims, panels) -> list:
    """'- fluid, metric at the best episode >= 0.2: bo 0 of 5; boleap 4 of 5; ...' per (env,
    threshold); '- ENV: no done run' for an env without one."""
    t = table(claims, panels)
    out = []
    for env, threshold in thresholds(claims):
        g = t[(t["env"] == env) & (t["threshold"] == threshold)]
        if g.empty:
            out.append(f"- {env}: no done run")
            continue
        out.append(f"- {env}, metric at the best episode >= {threshold:g}: "
                   + "; ".join(f"{r['optimizer']} {cell(r)}" for _, r in g.iterrows()))
    return out
