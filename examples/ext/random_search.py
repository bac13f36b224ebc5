#!/usr/bin/env python3
"""A random search as an external optimizer (docs/ext-protocol.md), the smallest one to compare
with the published runs (docs/results.md, "Compare your optimizer with the published runs"):

    harness --env cartpole1 --optimizer ext:rs --ext 'rs=python3 examples/ext/random_search.py' --seeds 5
    harness report --db results.sqlite --with data/study --out report

Each run draws uniform points in the box from its hello's seed, so a rerun gives the same bits."""
import os
import random
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import dsb_protocol as dsb  # noqa: E402


def optimize(s):
    rng = random.Random(s.seed)
    while True:  # until the budget ends (dsb.BudgetEnd, caught by dsb.main)
        s.evaluate([rng.uniform(lo, hi) for lo, hi in zip(s.lower, s.upper)])


dsb.main("random-search", "1", optimize)
