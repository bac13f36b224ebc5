"""CSV and Markdown output, and the number format shared with the HTML page."""
from __future__ import annotations

import math

import numpy as np
import pandas as pd

FINAL_COLUMNS = ["env", "budget", "optimizer", "n_seeds", "seed_free", "failed_runs", "running_runs",
                 "failed_episodes", "median", "q25", "q75", "mean", "std", "ci95_low", "ci95_high",
                 "min", "max", "median_wall_s", "is_best", "p_raw", "p_holm",
                 "indistinguishable_from_best", "too_few_seeds", "metric_median", "f_star",
                 "regret_median"]
SIGNIFICANCE_COLUMNS = ["env", "optimizer", "p_raw", "p_holm", "indistinguishable_from_best",
                        "too_few_seeds"]
TOO_FEW = "too few seeds"


def fmt(v, digits: int = 6) -> str:
    """Human number: NaN -> '—', inf -> '∞', else `digits` significant digits."""
    if v is None or (isinstance(v, float) and math.isnan(v)):
        return "—"
    if isinstance(v, bool):
        return "yes" if v else "no"
    if isinstance(v, float):
        if math.isinf(v):
            return "∞" if v > 0 else "−∞"
        return f"{v:.{digits}g}"
    return str(v)


def write_csv(df: pd.DataFrame, path: str, columns: list | None = None):
    (df[columns] if columns else df).to_csv(path, index=False, lineterminator="\n")


def mark(row) -> str:
    """Significance mark of a final-table row."""
    if row["n_seeds"] == 0:
        return "no done runs"
    if row["is_best"]:
        return "best"
    if bool(row.get("too_few_seeds", False)):
        return TOO_FEW
    if row["indistinguishable_from_best"]:
        return "≈ best"
    if isinstance(row["p_holm"], float) and math.isnan(row["p_holm"]):
        return "n/a"
    return "worse"


def md_table(headers: list, rows: list) -> str:
    esc = [[str(c).replace("|", "\\|").replace("\n", " ") for c in r] for r in rows]
    out = ["| " + " | ".join(headers) + " |", "|" + "---|" * len(headers)]
    out += ["| " + " | ".join(r) + " |" for r in esc]
    return "\n".join(out)


def final_md_rows(table: pd.DataFrame) -> tuple:
    """Rows of a final table; a last column with the env's second metric (median over seeds at
    each run's best episode, e.g. PlasticineLab's soft IoU) when any run recorded one. n reads
    '5 (one run)' for an optimizer whose seeds are one run (stats.seed_free: one sample, no CI)."""
    headers = ["optimizer", "n", "failed runs", "median", "q25", "q75", "mean", "std",
               "95% CI (t)", "p (Holm)", "vs best"]
    metric = "metric_median" in table.columns and bool(table["metric_median"].notna().any())
    if metric:
        headers.append("metric at best (median)")
    rows = []
    for _, r in table.iterrows():
        ci = "—" if math.isnan(r["ci95_low"]) else f"[{fmt(r['ci95_low'])}, {fmt(r['ci95_high'])}]"
        n = f"{r['n_seeds']} (one run)" if bool(r.get("seed_free", False)) else str(r["n_seeds"])
        rows.append([r["optimizer"], n, str(r["failed_runs"]), fmt(r["median"]),
                     fmt(r["q25"]), fmt(r["q75"]), fmt(r["mean"]), fmt(r["std"]), ci,
                     fmt(r["p_holm"], 3), mark(r)] + ([fmt(r["metric_median"], 4)] if metric else []))
    return headers, rows


def rank_md_rows(mean_ranks: pd.DataFrame) -> tuple:
    if mean_ranks.empty:
        return ["optimizer"], []
    wide = mean_ranks.pivot(index="optimizer", columns="episodes", values="mean_rank")
    n = mean_ranks.groupby("optimizer")["n_envs"].max()
    headers = ["optimizer", "envs"] + [f"@{c}" for c in wide.columns]
    rows = [[o, str(int(n[o]))] + [fmt(v, 3) for v in wide.loc[o]] for o in wide.index]
    return headers, rows


LOG_RATIO = 100.0   # log colour scale where the highest finite median / the lowest exceeds this
                    # (two decades, the rule of the curves' log y axis: style.DECADES_FOR_LOG)


def uses_log(medians) -> bool:
    """The overview's scale of one env: log when every finite median is positive and they span
    more than LOG_RATIO (cartpole1: 1e-11 to 1.8), else linear."""
    fin = [m for m in medians if math.isfinite(m)]
    return bool(fin) and min(fin) > 0 and max(fin) / min(fin) > LOG_RATIO


def score(median: float, lo: float, hi: float, log: bool) -> float:
    """Position of a median between the env's lowest (0) and highest (1) finite median, on a log
    or linear scale; +inf (no finite loss) scores 1, and 0 when all medians are equal."""
    if not math.isfinite(median):
        return 1.0
    if not hi > lo:
        return 0.0
    if log:
        return (math.log(median) - math.log(lo)) / (math.log(hi) - math.log(lo))
    return (median - lo) / (hi - lo)


def overview(panels: list, optimizers: list) -> list:
    """The answer table: one row per env (budget) with one cell per optimizer, dict(score, median,
    mark, n) or None (no done run), and log (the row's scale, uses_log). score: see score(), over
    the env's optimizers with a done run (0 = the lowest median, 1 = the highest). mark: 'best',
    '≈ best' (the Holm-corrected Mann-Whitney U test cannot tell it from the best), 'too few
    seeds' (no test could: see stats.too_few_seeds) or '' (worse)."""
    rows = []
    for it in panels:
        t = it["table"]
        t = t[t["n_seeds"] > 0].set_index("optimizer")
        med = t["median"].astype(float)
        fin = med[np.isfinite(med)]
        lo, hi = (float(fin.min()), float(fin.max())) if len(fin) else (math.nan, math.nan)
        log = uses_log(med)
        cells = {}
        for o in optimizers:
            if o not in t.index:
                cells[o] = None
                continue
            m = float(t.loc[o, "median"])
            mk = mark(t.loc[o])
            cells[o] = dict(score=score(m, lo, hi, log), median=m,
                            mark="" if mk == "worse" else mk, n=int(t.loc[o, "n_seeds"]))
        rows.append(dict(env=it["panel"].env, budget=it["panel"].budget, slug=it["panel"].slug,
                         cells=cells, log=log))
    return rows


def overview_text(cell) -> str:
    """A cell of the overview as text: the score with 2 decimals and the mark."""
    if cell is None:
        return "—"
    mk = {"best": "★ best", "≈ best": "≈ best"}.get(cell["mark"], cell["mark"])
    return f"{cell['score']:.2f}" + (f" {mk}" if mk else "")


def failures(panels: list, all_runs: pd.DataFrame, optimizers: list) -> list:
    """Failed episodes (NaN loss) of the analysed done runs and failed runs, per env (budget) and
    optimizer, for every (env, budget) with a run of any status (an env whose runs all failed has
    no panel but a row here): rows dict(env, budget, cells {optimizer: (episodes, runs) or None})."""
    by_key = {(it["panel"].env, it["panel"].budget): it["panel"] for it in panels}
    keys = sorted({(e, int(b)) for e, b in zip(all_runs["env"], all_runs["budget"])})
    rows = []
    for env, budget in keys:
        pn = by_key.get((env, budget))
        cell = all_runs[(all_runs["env"] == env) & (all_runs["budget"] == budget)]
        cells = {}
        for o in optimizers:
            c = cell[cell["optimizer"] == o]
            if c.empty:
                cells[o] = None
                continue
            eps = 0 if pn is None else int(pn.runs.loc[pn.runs["optimizer"] == o,
                                                      "failed_episodes"].sum())
            cells[o] = (eps, int((c["status"] == "failed").sum()))
        rows.append(dict(env=env, budget=budget, cells=cells))
    return rows
