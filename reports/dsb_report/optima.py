"""Known optima f* of the envs that have one (the synthetic suite), read from the one table of them,
data/known_optima.csv: family, f_star, f_star_per_dim, source. A fixed-dimension family (branin,
hartmann6) is the env of that name with f* = f_star; a scalable family NAME is the env NAME-D with
f* = f_star + f_star_per_dim * D (styblinski-D: -39.16616570377142 D; sphere, rosenbrock,
rastrigin, ackley: 0, shifted as COCO does, docs/envs.md "Environments"). The values come from
envs/synthetic/synthetic.cpp (known_optimum). Envs without a row have no known optimum."""
from __future__ import annotations

import csv
import math
import os
import re

DEFAULT_PATH = os.path.join(os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(
    __file__)))), "data", "known_optima.csv")


def load(path: str = DEFAULT_PATH) -> dict:
    """family -> (f_star, f_star_per_dim); {} when the file does not exist."""
    if not os.path.isfile(path):
        return {}
    out = {}
    with open(path, newline="", encoding="utf-8") as f:
        for r in csv.DictReader(f):
            out[r["family"].strip()] = (float(r["f_star"]), float(r["f_star_per_dim"] or 0.0))
    return out


def f_star(env: str, table: dict) -> float | None:
    """The known optimum of env, or None."""
    if env in table:
        fs, per_dim = table[env]
        return fs if per_dim == 0.0 else None      # a scalable family needs its D
    m = re.fullmatch(r"(.+)-([1-9][0-9]*)", env)
    if m and m.group(1) in table:
        fs, per_dim = table[m.group(1)]
        v = fs + per_dim * int(m.group(2))
        return v if math.isfinite(v) else None
    return None
