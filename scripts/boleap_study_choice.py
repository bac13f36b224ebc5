#!/usr/bin/env python3
"""BO-Leap's defaults by the rule stated before the study ran (scripts/boleap-study.sh, issue 28).

Reads the study's table (scripts/knob_study_table.py's CSV: env, optimizer, variant, median, ...)
and applies the rule:
  - candidates: BO-Leap's default, its single moves and the pair; not the ablation;
  - per env (cartpole1, cartpole3, rastrigin-10), rank the candidates by median final best loss
    (rank 1 = lowest; equal medians share the mean of their ranks);
  - the best mean rank over the envs wins; a candidate missing an env is not eligible;
  - a tie goes to the paper's reading: plain gradient steps over Adam, a leap counted in episodes
    over one counted in local iterations, then the smaller change from the base (fewer knobs
    moved, then the smaller |log10(value / base)| summed over the numeric knobs).
It also names the pair the study runs next: the two single moves on different knobs with the best
mean ranks (plain_steps and adam_per_leap are one knob, the descent's step), as the PAIR_FLAGS
that scripts/boleap-study.sh takes.

    python3 scripts/boleap_study_choice.py boleap_study.csv [--markdown OUT.md]

Prints the ranks, the choice and PAIR_FLAGS; exits 2 naming the problem when the table lacks a
column or holds no eligible candidate.
"""
import argparse
import csv
import math
import sys

ENVS = ("cartpole1", "cartpole3", "rastrigin-10")
# the base the single moves start from (boleap-study.sh's `base`)
BASE = {"sigma0": 0.3, "max_descent_steps": 10.0}
# a single move's label -> the --set flags (without "boleap.") that boleap-study.sh gives it
FLAGS = {"plain_steps": "plain_steps=true step_size=0.1", "adam_per_leap": "adam_per_leap=true"}


def knob(label):
    """the knob a single move turns: 'sigma0=0.1' -> 'sigma0'; the two descent-step moves share one"""
    if label in ("plain_steps", "adam_per_leap"):
        return "descent step"
    return label.split("=")[0]


def flags(label):
    return FLAGS.get(label, label)


def is_single(label):
    return label not in ("default", "pair", "ablation")


def paper_order(label, pair_labels):
    """the tie-break key: smaller is closer to the paper's reading and to the base"""
    moves = [] if label == "default" else (pair_labels if label == "pair" else [label])
    adam = 0 if "plain_steps" in moves else 1
    iterations = 1 if any(m.startswith("leap_iterations") for m in moves) else 0
    distance = 0.0
    for m in moves:
        k, _, v = m.partition("=")
        if k in BASE and v:
            distance += abs(math.log10(float(v) / BASE[k]))
    return (adam, iterations, len(moves), distance, label)


def mean_ranks(medians, envs):
    """medians: {label: {env: median}} -> ({label: mean rank}, {label: {env: rank}}) over the
    labels that have every env"""
    eligible = [l for l in medians if all(e in medians[l] for e in envs)]
    ranks = {l: {} for l in eligible}
    for e in envs:
        values = sorted(medians[l][e] for l in eligible)
        for l in eligible:
            v = medians[l][e]
            first = values.index(v) + 1
            last = len(values) - values[::-1].index(v)
            ranks[l][e] = (first + last) / 2.0
    return {l: sum(ranks[l].values()) / len(envs) for l in eligible}, ranks


def choose(rows, envs=ENVS, pair_labels=None):
    """rows: the table's dicts. Returns (chosen label, {label: mean}, {label: {env: rank}},
    {label: {env: median}}, PAIR_FLAGS or None)"""
    medians = {}
    for r in rows:
        if r["optimizer"] != "boleap" or r["env"] not in envs or r["variant"] == "ablation":
            continue
        m = float(r["median"]) if r["median"] not in ("", "inf") else math.inf
        medians.setdefault(r["variant"], {})[r["env"]] = m
    means, ranks = mean_ranks(medians, envs)
    if not means:
        raise ValueError(f"no BO-Leap variant has a median on every env of {', '.join(envs)}")
    # the pair: the best single move, then the best on another knob (ties by the paper's order)
    singles = sorted((l for l in means if is_single(l)), key=lambda l: (means[l], paper_order(l, [])))
    pair = None
    if singles:
        second = [l for l in singles[1:] if knob(l) != knob(singles[0])]
        if second:
            pair = [singles[0], second[0]]
    chosen = min(means, key=lambda l: (means[l], paper_order(l, pair_labels or pair or [])))
    pair_flags = " ".join(flags(l) for l in pair) if pair else None
    return chosen, means, ranks, medians, pair_flags


def markdown(chosen, means, ranks, medians, envs):
    lines = ["| variant | " + " | ".join(f"{e}: median (rank)" for e in envs) + " | mean rank |",
             "|---" * (len(envs) + 2) + "|"]
    for l in sorted(means, key=lambda l: (means[l], l)):
        cells = [f"{medians[l][e]:.4g} ({ranks[l][e]:g})" for e in envs]
        name = f"**{l}** (chosen)" if l == chosen else l
        lines.append(f"| {name} | " + " | ".join(cells) + f" | {means[l]:.2f} |")
    return "\n".join(lines) + "\n"


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("table", help="the study's table (scripts/knob_study_table.py --out)")
    ap.add_argument("--envs", default=",".join(ENVS), help="comma-separated envs of the rule")
    ap.add_argument("--pair", default="", help="the pair's two single moves, comma-separated, when "
                    "the table holds a 'pair' row (for the tie-break; default: the pair this rule names)")
    ap.add_argument("--markdown", help="write the ranks as a markdown table here")
    a = ap.parse_args(argv)
    envs = tuple(e for e in a.envs.split(",") if e)
    try:
        with open(a.table, newline="") as f:
            rows = list(csv.DictReader(f))
    except OSError as e:
        sys.stderr.write(f"boleap_study_choice: cannot read '{a.table}': {e.strerror}\n")
        return 2
    missing = {"env", "optimizer", "variant", "median"} - set(rows[0] if rows else {})
    if missing:
        sys.stderr.write(f"boleap_study_choice: '{a.table}' lacks the column(s) {', '.join(sorted(missing))}\n")
        return 2
    try:
        chosen, means, ranks, medians, pair_flags = choose(rows, envs, [p for p in a.pair.split(",") if p])
    except ValueError as e:
        sys.stderr.write(f"boleap_study_choice: {e}\n")
        return 2
    text = markdown(chosen, means, ranks, medians, envs)
    sys.stdout.write(text)
    print(f"chosen: {chosen} (mean rank {means[chosen]:.2f} over {', '.join(envs)})")
    print(f"PAIR_FLAGS={pair_flags!r}" if pair_flags else "PAIR_FLAGS: no two single moves on different knobs yet")
    if a.markdown:
        with open(a.markdown, "w") as f:
            f.write(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
