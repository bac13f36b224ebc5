#!/usr/bin/python3
"""One CSV row per env from `harness gradcheck --json` outputs (scripts/gradient-quality.sh).

usage: gradient_quality_csv.py OUT.csv ENV=FILE.json [ENV=FILE.json ...]

ENV is the env of `harness list`; the JSON's own env is the one surveyed (fluid-h5 for fluid).
Columns (definitions in docs/gradient-quality.md "Gradient quality"): fractions of the points, with 4 decimals;
gradient norms and the median large-step ratio with 6 significant digits. Standard library only.
"""
import csv
import json
import sys

COLUMNS = ["env", "surveyed", "dim", "points", "seed", "amplitude", "step", "tolerance",
           "large_step", "agreeing", "agree_fraction", "exactly_zero", "zero_fraction",
           "norm_min", "norm_median", "norm_max", "small_step_opposed", "large_step_directed",
           "large_step_opposed", "large_step_opposed_fraction", "large_step_flat",
           "large_step_ratio_median", "non_finite", "value_mismatches"]


def number(v, digits=6):
    return "" if v is None else f"{v:.{digits}g}"


def fraction(count, total):
    return "" if total == 0 else f"{count / total:.4f}"


def row(env, j):
    s, o = j["summary"], j["options"]
    return {"env": env, "surveyed": j["env"], "dim": j["dim"], "points": s["points"],
            "seed": o["seed"], "amplitude": o["amplitude"], "step": o["step"],
            "tolerance": o["tolerance"], "large_step": o["large_step"],
            "agreeing": s["agreeing"], "agree_fraction": fraction(s["agreeing"], s["points"]),
            "exactly_zero": s["exactly_zero"],
            "zero_fraction": fraction(s["exactly_zero"], s["points"]),
            "norm_min": number(s["gradient_norm"]["min"]),
            "norm_median": number(s["gradient_norm"]["median"]),
            "norm_max": number(s["gradient_norm"]["max"]),
            "small_step_opposed": s["opposed"],
            "large_step_directed": s["large_step_directed"],
            "large_step_opposed": s["large_step_opposed"],
            "large_step_opposed_fraction": fraction(s["large_step_opposed"],
                                                    s["large_step_directed"]),
            "large_step_flat": s["large_step_flat"],
            "large_step_ratio_median": number(s["large_step_ratio"]["median"]),
            "non_finite": s["non_finite"], "value_mismatches": s["value_mismatches"]}


def main(argv):
    if len(argv) < 3:
        print(__doc__, file=sys.stderr)
        return 2
    rows = []
    for arg in argv[2:]:
        env, _, path = arg.partition("=")
        with open(path, encoding="utf-8") as f:
            rows.append(row(env, json.load(f)))
    with open(argv[1], "w", newline="", encoding="utf-8") as f:
        w = csv.DictWriter(f, COLUMNS, lineterminator="\n")
        w.writeheader()
        w.writerows(rows)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
