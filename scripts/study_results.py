#!/usr/bin/python3
"""A study's published runs (one CSV, a row per run) and the tables made from them: the median
final best loss per env and optimizer, the paper's claims with their verdicts, and, where a claim
reads the env's second metric, how many seeds of each optimizer reach its threshold.

    /usr/bin/python3 scripts/study_results.py export DB RUNS.csv
    /usr/bin/python3 scripts/study_results.py tables RUNS.csv [MORE.csv ...] [--claims FILE]
                                                     [--harness BIN] [--update FILE]

`export` writes a database's runs (reports/dsb_report/runs_csv.py; a new file only). `tables`
prints the three tables as Markdown, from one runs CSV or several (a study's grids published apart,
such as data/study/runs.csv and the fluid grid's pieces data/study/fluid/*.csv; a run found in two
of them is refused); with --update it also replaces the text between the lines
`<!-- study_results.py: begin -->` and `<!-- study_results.py: end -->` of FILE (the README) with
them. The verdicts are the report's (reports/dsb_report/claims.py) on the same runs: from the CSV
or from the database they are the same. --harness BIN lets the claims table tell an env the
harness lacks from runs the file lacks (`harness list`). Needs pandas and scipy (Debian's
/usr/bin/python3). Exit codes: 0, 2 bad input (one line naming it).
"""
from __future__ import annotations

import argparse
import math
import os
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(os.path.dirname(HERE), "reports"))

BEGIN, END = "<!-- study_results.py: begin -->", "<!-- study_results.py: end -->"


def fail(msg: str) -> int:
    print(f"study_results: {msg}", file=sys.stderr)
    return 2


def fmt(v: float) -> str:
    if v is None or (isinstance(v, float) and math.isnan(v)):
        return "—"
    if math.isinf(v):
        return "inf"
    return f"{v:.4g}"


def medians_table(data) -> str:
    """env x optimizer: the median final best loss over the env's analysed runs (largest budget)"""
    import numpy as np
    from dsb_report import data as data_mod, stats
    panels = data_mod.main_panels(data)
    opts = sorted({o for p in panels for o in p.optimizers})
    lines = ["| env (budget, seeds) | " + " | ".join(opts) + " |", "|---" * (len(opts) + 1) + "|"]
    for p in panels:
        counts = [len(p.rows(o)) for o in p.optimizers]
        seeds = f"{min(counts)}" if min(counts) == max(counts) else f"{min(counts)}-{max(counts)}"
        cells = []
        for o in opts:
            v = stats.final_values(p, o) if o in p.optimizers else np.zeros(0)
            cells.append(fmt(float(np.median(v))) if v.size else "—")
        lines.append(f"| {p.env} ({p.budget}, {seeds}) | " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


def claims_table(verdicts) -> str:
    """one row per claim and env; an unsettled row names the command that makes its runs (the
    report's own column: `harness --claims --env ENV --seeds N`), a settled one '—'"""
    from dsb_report.html import settle_text
    lines = ["| claim | env | verdict | to settle, run | the paper says |", "|---|---|---|---|---|"]
    for _, r in verdicts.iterrows():
        cmd = settle_text(r)
        cmd = f"`{cmd}`" if r["settle"] else cmd
        lines.append(f"| {r['id']} | {r['env']} | {r['verdict']} | {cmd} | {r['statement']} |")
    return "\n".join(lines) + "\n"


def metric_table(data, claims) -> str:
    """for each env of a metric claim: per optimizer, the seeds whose metric at their best episode
    reaches the claim's threshold (reports/dsb_report/metric_counts.py, as the report shows it)"""
    from dsb_report import data as data_mod, metric_counts
    lines = metric_counts.lines(claims, data_mod.main_panels(data))
    return "\n".join(lines) + ("\n" if lines else "")


def tables(args) -> int:
    from dsb_report import claims as claims_mod, runs_csv
    try:
        data = runs_csv.load(*args.runs)
    except runs_csv.RunsCsvError as e:
        return fail(str(e))
    try:
        claims = claims_mod.load(args.claims)
    except Exception as e:  # the claims module names the bad row
        return fail(f"--claims: {e}")
    registry = None
    if args.harness:
        from dsb_report import registry as registry_mod
        registry = registry_mod.load(args.harness)
    from dsb_report import data as data_mod
    verdicts, _ = claims_mod.evaluate(claims, data_mod.main_panels(data), data.runs, registry)
    text = ("Median final best loss over each env's seeds (the largest budget):\n\n" + medians_table(data)
            + "\nThe paper's claims:\n\n" + claims_table(verdicts))
    metric = metric_table(data, claims)
    if metric:
        text += "\nSeeds that reach the claims' metric thresholds:\n\n" + metric
    sys.stdout.write(text)
    if args.update:
        try:
            with open(args.update, encoding="utf-8") as f:
                old = f.read()
        except OSError as e:
            return fail(f"--update: cannot read '{args.update}': {e.strerror}")
        if old.count(BEGIN) != 1 or old.count(END) != 1 or old.index(BEGIN) > old.index(END):
            return fail(f"--update: '{args.update}' has no single '{BEGIN}' ... '{END}' block")
        new = old[:old.index(BEGIN) + len(BEGIN)] + "\n" + text + old[old.index(END):]
        tmp = args.update + ".tmp"
        with open(tmp, "w", encoding="utf-8") as f:
            f.write(new)
        os.replace(tmp, args.update)
    return 0


def export(args) -> int:
    from dsb_report import data as data_mod, runs_csv
    try:
        data = data_mod.load(args.db)
        n = runs_csv.write(data, args.out)
    except (data_mod.DataError, runs_csv.RunsCsvError) as e:
        return fail(str(e))
    print(f"study_results: {n} runs -> {args.out}")
    return 0


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    sub = ap.add_subparsers(dest="command", required=True)
    e = sub.add_parser("export", help="a database's runs as a runs CSV (a new file)")
    e.add_argument("db")
    e.add_argument("out")
    t = sub.add_parser("tables", help="the tables from a runs CSV, as Markdown")
    t.add_argument("runs", nargs="+")
    t.add_argument("--claims", default=os.path.join(os.path.dirname(HERE), "reports", "paper_claims.csv"))
    t.add_argument("--harness", help="the harness, to tell a missing env from missing runs")
    t.add_argument("--update", help="a file whose study_results.py block gets the tables")
    a = ap.parse_args(argv)
    try:
        import pandas  # noqa: F401
        import scipy.stats  # noqa: F401
    except ImportError as err:
        return fail(f"{sys.executable} cannot import {err.name}; use /usr/bin/python3")
    return export(a) if a.command == "export" else tables(a)


if __name__ == "__main__":
    sys.exit(main())
