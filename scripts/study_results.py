#!/usr/bin/python3
"""A study's published runs (one CSV, a row per run) and the tables made from them: the median
final best loss per env and optimizer, the paper's claims with their verdicts, and, where a claim
reads the env's second metric, how many seeds of each optimizer reach its threshold.

    /usr/bin/python3 scripts/study_results.py export DB RUNS.csv
    /usr/bin/python3 scripts/study_results.py tables RUNS.csv [MORE.csv ...] [--claims FILE]
                                                     [--harness BIN] [--update FILE]
    /usr/bin/python3 scripts/study_results.py record-seed-free RUNS.csv DB OUT.csv

`export` writes a database's runs (reports/dsb_report/runs_csv.py; a new file only).
`record-seed-free` copies RUNS.csv to OUT.csv (a new file) with the column seed_free_episodes
taken from DB's runs of the same run key (env, optimizer, seed, budget, config hashes), for a
runs CSV published before the column existed: DB holds the same runs rerun, and a row whose final
best loss is not the same bits in DB is refused (exit 2, nothing written); rows DB lacks keep what
they had (empty: not recorded). `tables`
prints the three tables as Markdown, from one runs CSV or several (a study's grids published apart,
such as data/study/runs.csv and the fluid grid's pieces data/study/fluid/*.csv; a run found in two
of them is refused); with --update it also replaces the text between the lines
`<!-- study_results.py: begin -->` and `<!-- study_results.py: end -->` of FILE (docs/results.md) with
them. The verdicts are the report's (reports/dsb_report/claims.py) on the same runs: from the CSV
or from the database they are the same; an (env, optimizer) whose seeds are one run (the runs
CSV's seed_free_episodes covers every run's episodes: reports/dsb_report/stats.py seed_free) counts
as one sample, and the medians table lists such cells. --harness BIN lets the claims table tell an env the
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
sys.path.insert(0, HERE)
from python_modules import cannot_import  # noqa: E402

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
    one = [f"{p.env}: " + ", ".join(o for o in p.optimizers if stats.seed_free(p, o)) for p in panels
           if any(stats.seed_free(p, o) for o in p.optimizers)]
    if one:
        lines += ["", "Seeds that are one run (every run recorded seed-free over all its episodes, so each "
                  "counts once in the tests: the other side's seeds against its value by the exact sign "
                  "test): " + "; ".join(one) + "."]
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


def record_seed_free(args) -> int:
    import csv
    import sqlite3
    from dsb_report import data as data_mod, runs_csv
    if os.path.exists(args.out):
        return fail(f"'{args.out}' exists: remove it or name another file")
    try:
        runs = runs_csv.load(args.runs).runs   # checks the file, every column
        con = data_mod.connect_ro(args.db)
    except (runs_csv.RunsCsvError, data_mod.DataError) as e:
        return fail(str(e))
    try:
        rows = con.execute("SELECT env, optimizer, seed, budget, env_config_hash, opt_config_hash, best_loss, "
                           "seed_free_episodes FROM runs WHERE status = 'done'").fetchall()
    except sqlite3.Error as e:
        return fail(f"cannot read runs of '{args.db}': {e}")
    finally:
        con.close()
    rerun = {tuple(map(str, r[:6])): (r[6], r[7]) for r in rows}
    with open(args.runs, newline="", encoding="utf-8") as f:
        table = list(csv.reader(f))
    header, body = table[0], table[1:]
    if "seed_free_episodes" not in header:
        header = header + ["seed_free_episodes"]
        body = [r + [""] for r in body]
    col = {c: i for i, c in enumerate(header)}
    filled = 0
    for r, (_, run) in zip(body, runs.iterrows()):
        key = tuple(str(run[c]) for c in runs_csv.RUN_KEY)
        if key not in rerun or rerun[key][1] is None:
            continue
        mine = float(r[col["best_loss"]]) if r[col["best_loss"]] else None
        theirs = rerun[key][0]
        if (mine is None) != (theirs is None) or (mine is not None and mine.hex() != float(theirs).hex()):
            return fail(f"run {'/'.join(key[:4])}: best loss {r[col['best_loss']] or 'none'} in '{args.runs}' "
                        f"but {theirs!r} in '{args.db}': not the same run")
        r[col["seed_free_episodes"]] = str(int(rerun[key][1]))
        filled += 1
    tmp = args.out + ".tmp"
    with open(tmp, "w", newline="", encoding="utf-8") as f:
        csv.writer(f, lineterminator="\n").writerows([header] + body)
    os.replace(tmp, args.out)
    print(f"study_results: {filled} of {len(body)} runs recorded from {args.db} -> {args.out}")
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
    r = sub.add_parser("record-seed-free", help="a runs CSV with seed_free_episodes from a rerun's database")
    r.add_argument("runs")
    r.add_argument("db")
    r.add_argument("out")
    a = ap.parse_args(argv)
    why = cannot_import("pandas", "scipy.stats")
    if why:
        return fail(why)
    return {"export": export, "tables": tables, "record-seed-free": record_seed_free}[a.command](a)


if __name__ == "__main__":
    sys.exit(main())
