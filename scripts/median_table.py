#!/usr/bin/env python3
"""Median (and min/max) final best loss per env and optimizer over seeds, straight from a harness
database, as a Markdown table. Standard library only (sqlite3), so any python3 runs it.

usage: scripts/median_table.py [results.sqlite] [--env NAME ...]
"""
import argparse
import sqlite3
import statistics
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "reports"))
from dsb_report import read_only_db  # noqa: E402


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("db", nargs="?", default="results.sqlite")
    p.add_argument("--env", action="append", help="only these envs (repeatable)")
    a = p.parse_args()
    try:
        con = read_only_db.connect(a.db)
        rows = con.execute(
            "SELECT env, optimizer, seed, best_loss, episodes FROM runs WHERE status='done' "
            "ORDER BY env, optimizer, seed").fetchall()
    except sqlite3.Error as e:
        print(f"median_table: cannot read '{a.db}': {e}", file=sys.stderr)
        return 2
    cells, opts, envs = {}, [], []
    for env, opt, seed, best, episodes in rows:
        if a.env and env not in a.env:
            continue
        cells.setdefault((env, opt), []).append((best, episodes))
        if opt not in opts:
            opts.append(opt)
        if env not in envs:
            envs.append(env)
    print("| env | " + " | ".join(opts) + " |")
    print("|---|" + "---|" * len(opts))
    for env in envs:
        line = []
        for opt in opts:
            vals = [b for b, _ in cells.get((env, opt), []) if b is not None]
            line.append(f"{statistics.median(vals):.4g} (n={len(vals)})" if vals else "—")
        print(f"| {env} | " + " | ".join(line) + " |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
