"""What a claim that the database cannot settle yet still needs, and the command that makes it.

A claim on an env needs CLAIMS_SEEDS seeds (0..CLAIMS_SEEDS-1) of every optimizer it names (for
kind a_best: its optimizer and every optimizer `harness --all` runs on the env, from `harness
list`; without that list, the optimizers with a run of the env) at the largest budget of the env's
runs in the database. Each such run is 'done', 'running' (in progress, or a harness killed
part-way), 'failed' or 'absent'. The claims grid of the harness (`harness --claims`) makes exactly
these runs; settle_command is its command line, the one place that spells it.
"""
from __future__ import annotations

import pandas as pd

CLAIMS_SEEDS = 5
ENV_MISSING = "env missing"
STATES = ("done", "running", "failed", "absent")


def settle_command(env: str, seeds: int = CLAIMS_SEEDS) -> str:
    """The command that makes the runs the claims on `env` need: the claims grid for that env."""
    return f"harness --claims --env {env} --seeds {seeds}"


def runs_missing(done: int, needed) -> str:
    return f"runs missing: {done} of {needed} done"


def runs_incomplete(done: int, needed) -> str:
    return f"runs incomplete: {done} of {needed} done"


def needed_optimizers(kind: str, a: list, b: list, env: str, runs: pd.DataFrame, registry) -> list:
    """The optimizers a claim on env needs runs of (a, then b or the rivals of an a_best claim)."""
    if kind != "a_best":
        return list(dict.fromkeys(a + b))
    if registry is not None and registry.has_env(env):
        rivals = registry.optimizers_for(env)
    else:
        rivals = sorted(runs.loc[runs["env"] == env, "optimizer"].unique())
    return list(dict.fromkeys(a + rivals))


def run_states(runs: pd.DataFrame, env: str, optimizers: list, seeds: int):
    """(budget, {(optimizer, seed): state}) at the largest budget of env's runs (None: no run of
    env, every state 'absent'). A key with a done run is 'done'; else its newest run's status."""
    mine = runs[runs["env"] == env]
    budget = int(mine["budget"].max()) if len(mine) else None
    if budget is not None:
        mine = mine[mine["budget"] == budget]
    states = {}
    for o in optimizers:
        for s in range(seeds):
            r = mine[(mine["optimizer"] == o) & (mine["seed"] == s)]
            if r.empty:
                states[(o, s)] = "absent"
            elif (r["status"] == "done").any():
                states[(o, s)] = "done"
            else:
                states[(o, s)] = str(r.sort_values("run_id")["status"].iloc[-1])
    return budget, states


def seed_text(seeds: list) -> str:
    """[0, 1, 2, 4] -> 'seeds 0-2, 4'; [3] -> 'seed 3'."""
    parts, start = [], None
    for k, s in enumerate(seeds):
        if start is None:
            start = s
        if k + 1 == len(seeds) or seeds[k + 1] != s + 1:
            parts.append(str(s) if s == start else f"{start}-{s}")
            start = None
    return ("seed " if len(seeds) == 1 else "seeds ") + ", ".join(parts)


def describe(states: dict, state: str) -> str:
    """'bo, boleap seeds 0-4; cmaes seeds 3-4' for the runs in `state`, optimizers with the same
    seeds grouped."""
    by_opt = {}
    for (o, s), st in states.items():
        if st == state:
            by_opt.setdefault(o, []).append(s)
    groups = {}
    for o, seeds in by_opt.items():
        groups.setdefault(seed_text(sorted(seeds)), []).append(o)
    return "; ".join(f"{', '.join(opts)} {seeds}" for seeds, opts in groups.items())


def assess(kind: str, a: list, b: list, env: str, runs: pd.DataFrame, registry,
           seeds: int = CLAIMS_SEEDS) -> dict:
    """For a claim on env that the database cannot settle: runs_done, runs_needed and settle (the
    command), plus verdict and reason where the env is missing or runs are missing or not done
    (None: every run the claim needs is done, the judged verdict stands)."""
    if registry is not None and not registry.has_env(env):
        return dict(verdict=ENV_MISSING, runs_done="", runs_needed="", settle="",
                    reason=f"the harness has no env {env} (`harness list` of {registry.source}); "
                           "no run can settle the claim until it does")
    need = needed_optimizers(kind, a, b, env, runs, registry)
    budget, states = run_states(runs, env, need, seeds)
    count = {st: sum(1 for v in states.values() if v == st) for st in STATES}
    out = dict(runs_done=count["done"], runs_needed=len(states), settle=settle_command(env, seeds),
               verdict=None, reason=None)
    if count["done"] == len(states):
        return out
    # an a_best claim's rivals are every optimizer --all runs on the env: only `harness list` knows
    needed = f"at least {len(states)}" if kind == "a_best" and registry is None else len(states)
    state = runs_incomplete if count["running"] + count["failed"] else runs_missing
    grid = f"{', '.join(need)} x {seed_text(list(range(seeds)))}"
    return dict(out, verdict=state(count["done"], needed),
                reason=_reason(env, grid, needed, budget, states, registry is not None))


def _reason(env: str, grid: str, needed, budget, states: dict, registry_known: bool) -> str:
    """Which of the runs a claim needs are done, running, failed, absent."""
    if budget is None:
        text = f"No run of {env} in the database; the claim needs {needed} runs ({grid})."
        if not registry_known:
            text += (f" Whether the harness has env {env} is unknown (no `harness list`: "
                     "make_report.py --harness BIN).")
        return text
    done = sum(1 for v in states.values() if v == "done")
    parts = [f"{done} of {needed} runs done ({grid}, budget {budget})."]
    parts += [f"{st.capitalize()}: {describe(states, st)}." for st in ("running", "failed", "absent")
              if st in states.values()]
    return " ".join(parts)
