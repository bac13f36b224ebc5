#!/usr/bin/env python3
"""Does the regression baseline cover the harness? Reads `harness list` on stdin and the result
table named on the command line (data/baselines/small-grid.csv), and checks that every env of
the list's env table has rows (a particle env, fluid or plb-NAME, through any of its NAME-hN
variants), and that every optimizer of its optimizer table, and an `ext:` one, has rows on at
least two envs. Prints what it found; exit 1 naming what is missing, 2 on unreadable input.

    harness list | regression_coverage.py data/baselines/small-grid.csv
"""
import csv
import re
import sys


def table(lines, header):
    """The first word of each row under the line that starts with `header`, to a blank line."""
    rows, inside = [], False
    for line in lines:
        if not inside:
            inside = line.split()[:1] == [header]
            continue
        if not line.strip():
            break
        rows.append(line.split()[0])
    return rows


def main(argv):
    if len(argv) != 2:
        print(__doc__.strip().splitlines()[-1].strip(), file=sys.stderr)
        return 2
    lines = sys.stdin.read().splitlines()
    envs, optimizers = table(lines, "env"), table(lines, "optimizer")
    if not envs or not optimizers:
        print("regression_coverage.py: `harness list` on stdin has no env or optimizer table", file=sys.stderr)
        return 2
    optimizers = [o for o in optimizers if not o.startswith("ext:")] + ["ext:"]
    try:
        with open(argv[1], newline="", encoding="utf-8") as f:
            rows = list(csv.DictReader(f))
    except OSError as e:
        print(f"regression_coverage.py: cannot read '{argv[1]}': {e.strerror}", file=sys.stderr)
        return 2
    base = lambda env: re.sub(r"-h[0-9]+$", "", env) if re.match(r"(fluid|plb-[a-z]+)-h[0-9]+$", env) else env
    env_optimizers = {}
    for r in rows:
        opt = "ext:" if r["optimizer"].startswith("ext:") else r["optimizer"]
        env_optimizers.setdefault(opt, set()).add(base(r["env"]))
    covered = {e for s in env_optimizers.values() for e in s}
    missing = [f"env {e}: no rows" for e in envs if e not in covered]
    missing += [f"optimizer {o}: rows on {len(env_optimizers.get(o, ()))} envs, needs 2" for o in optimizers
                if len(env_optimizers.get(o, ())) < 2]
    print(f"coverage: {len(envs) - sum(m.startswith('env') for m in missing)} of {len(envs)} envs, "
          f"{len(optimizers) - sum(m.startswith('optimizer') for m in missing)} of {len(optimizers)} optimizers "
          f"(ext: included) on at least two envs")
    for m in missing:
        print(f"coverage: missing: {m}")
    return 1 if missing else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
