"""summary.md: the report's tables in Markdown (overview, per-env finals, ranks, problems)."""
from __future__ import annotations

from . import captions, charts, metric_counts, plots
from .claim_runs import CLAIMS_SEEDS
from . import gradient_quality as gq
from .html import settle_text
from .tables import final_md_rows, fmt, md_table, overview_text, rank_md_rows


def _run_list(title: str, runs, headers: list, columns: list) -> list:
    """A section of runs: its title with their count, then their table (`columns` of `runs`
    under `headers`), or "None." when there are none."""
    out = [f"## {title} ({len(runs)})", ""]
    return out + (["None."] if runs.empty else [md_table(
        headers, [[str(v) for v in r] for r in runs[columns].itertuples(index=False, name=None)])])


def render(ctx) -> str:
    out = ["# diffsim-bench comparison report", "", ctx["headline"], ""]
    c = ctx["claims"]
    out += ["## The paper's claims", "", captions.CLAIMS, "", captions.CLAIMS_SETTLE.format(seeds=CLAIMS_SEEDS), "", md_table(
        ["claim", "env (budget)", "tested as", "seeds", "p (Holm)", "A12", "verdict", "why",
         "to settle, run"],
        [[r["id"], f"{r['env']} ({r['budget']})" if r["budget"] != "" else r["env"], r["test"],
          r["n"], fmt(r["p_claim"], 3), fmt(r["a12_claim"], 2), r["verdict"], r["reason"],
          settle_text(r)] for _, r in c.iterrows()]), ""]
    t = ctx["metric_counts"]
    if not t.empty:
        out += ["### Seeds that reach the metric claims' thresholds", "", captions.METRIC_COUNTS, "",
                md_table(*metric_counts.wide(t)), ""]
    opts = ctx["optimizers"]
    out += ["## Overview: final results per env and optimizer", "", captions.OVERVIEW, "",
            md_table(["env (budget)"] + list(opts),
                     [[f"{r['env']} ({r['budget']}{', log colour scale' if r['log'] else ''})"] +
                      [overview_text(r["cells"][o]) for o in opts] for r in ctx["overview"]]), ""]
    fl = ctx["failures"]
    out += ["## Failed episodes and failed runs", "", captions.FAILURES, "",
            md_table(["env (budget)"] + list(opts),
                     [[f"{r['env']} ({r['budget']})"] +
                      ["—" if r["cells"][o] is None else f"{r['cells'][o][0]} / {r['cells'][o][1]}"
                       for o in opts] for r in fl]), ""]
    out += [f"> {n}" for n in ctx["notes"]] + ([""] if ctx["notes"] else [])
    h, rows = rank_md_rows(ctx["mean_ranks"])
    out += ["## Average ranks", "", charts.named(plots.CHARTS, "ranks").caption, "", md_table(h, rows), ""]
    out += ["## Final best loss per env", "",
            "Over seeds at the budget; 95% CI = Student t; p (Holm) = one-sided Mann-Whitney U "
            "(worse than the env's best?), Holm-corrected over the env. " + ctx["minp_text"], ""]
    for it in ctx["panels"]:
        pn = it["panel"]
        out += [f"### {pn.env} (budget {pn.budget})", "", md_table(*final_md_rows(it["table"])), ""]
    g = ctx["gradient_quality"]
    out += ["## Gradient quality", ""]
    out += [f"No gradient survey: {ctx['gradient_quality_path']} does not exist.", ""] if g is None else [
        captions.GRADIENT_QUALITY.format(settings=gq.settings(g)), "",
        md_table(gq.HEADERS, gq.rows(g)), ""]
    m = ctx["missing"]
    key = ["env", "optimizer", "seed", "budget"]
    out += _run_list("Missing runs", m, key + ["reason", "error"], key + ["reason", "error"])
    out += [""] + _run_list("Failed runs", ctx["failed"], key + ["error"], key + ["error"])
    out += [""] + _run_list("Incomplete runs, status running", ctx["running"], key + ["started"],
                            key + ["started_at"])
    out += ["", "## Provenance", "", md_table(["item", "value"], ctx["provenance"])]
    return "\n".join(out) + "\n"
