#!/usr/bin/env python3
"""How a grid's start order plays out, from `harness plan --runs-csv` (planned seconds, start_rank,
lead_seed): the runner's rule (harness/run/runner.hpp) replayed on the planned costs with JOBS workers,
each free worker taking the first run in start order whose lead has ended. Prints when the first
env and the last light env (all but fluid and the PlasticineLab tasks) have every run done, when
fluid has, the whole grid's end, and the core-hours workers spent waiting for a lead.

    harness plan --all --seeds 5 --jobs 2 --runs-csv runs.csv && scripts/run-order-check.py runs.csv 2

A simulation of the plan, not a measurement: its times are as good as the plan's costs.
"""
import collections
import csv
import heapq
import sys


def main(path, jobs):
    rows = list(csv.DictReader(open(path)))
    cost = [float(r["planned_s"]) for r in rows]
    by_key = {(r["env"], r["optimizer"], r["budget"], r["seed"]): i for i, r in enumerate(rows)}
    lead = [by_key[(r["env"], r["optimizer"], r["budget"], r["lead_seed"])] if r["lead_seed"] else -1 for r in rows]
    order = sorted(range(len(rows)), key=lambda i: int(rows[i]["start_rank"]))
    end = [None] * len(rows)
    taken = [False] * len(rows)
    workers = [(0.0, w) for w in range(jobs)]
    ends, idle, left = [], 0.0, len(rows)
    while left:
        t, w = heapq.heappop(workers)
        pick = next((i for i in order if not taken[i] and (lead[i] < 0 or (end[lead[i]] is not None and end[lead[i]] <= t))), None)
        if pick is None:  # every open run waits for a running lead: wait for the next run to end
            nxt = min(e for e in ends if e > t)
            idle += nxt - t
            heapq.heappush(workers, (nxt, w))
            continue
        taken[pick], left = True, left - 1
        end[pick] = t + cost[pick]
        ends.append(end[pick])
        heapq.heappush(workers, (end[pick], w))
    env_end = collections.defaultdict(float)
    for i, r in enumerate(rows):
        env_end[r["env"]] = max(env_end[r["env"]], end[i])
    light = [e for e in env_end if not (e.startswith("plb") or e.startswith("fluid"))]
    h = lambda s: f"{s / 3600:.2f} h"
    first = min(env_end, key=env_end.get)
    print(f"{len(rows)} runs on {jobs} workers: first env done ({first}) {h(env_end[first])}", end="")
    if light:
        print(f"; light envs done {h(max(env_end[e] for e in light))}", end="")
    if "fluid" in env_end:
        print(f"; fluid done {h(env_end['fluid'])}", end="")
    print(f"; grid done {h(max(end))}; waiting for leads {idle / 3600:.1f} core-hours")


if __name__ == "__main__":
    if len(sys.argv) != 3 or not sys.argv[2].isdigit() or int(sys.argv[2]) < 1:
        sys.exit(f"usage: {sys.argv[0]} RUNS.csv JOBS (JOBS a positive integer, got {sys.argv[2:]!r})")
    main(sys.argv[1], int(sys.argv[2]))
