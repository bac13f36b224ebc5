"""CSV and Markdown output, and the number format shared with the HTML page."""
from __future__ import annotations

import math

import pandas as pd

FINAL_COLUMNS = ["env", "budget", "optimizer", "n_seeds", "failed_runs", "running_runs",
                 "failed_episodes", "median", "q25", "q75", "mean", "std", "ci95_low", "ci95_high",
                 "min", "max", "median_wall_s", "is_best", "p_raw", "p_holm",
                 "indistinguishable_from_best", "metric_median"]
SIGNIFICANCE_COLUMNS = ["env", "optimizer", "p_raw", "p_holm", "indistinguishable_from_best"]


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
    each run's best episode, e.g. PlasticineLab's soft IoU) when any run recorded one."""
    headers = ["optimizer", "n", "failed runs", "median", "q25", "q75", "mean", "std",
               "95% CI (t)", "p (Holm)", "vs best"]
    metric = "metric_median" in table.columns and bool(table["metric_median"].notna().any())
    if metric:
        headers.append("metric at best (median)")
    rows = []
    for _, r in table.iterrows():
        ci = "—" if math.isnan(r["ci95_low"]) else f"[{fmt(r['ci95_low'])}, {fmt(r['ci95_high'])}]"
        rows.append([r["optimizer"], str(r["n_seeds"]), str(r["failed_runs"]), fmt(r["median"]),
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
