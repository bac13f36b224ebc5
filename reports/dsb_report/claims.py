"""The paper's qualitative claims as tests over the database, each with a verdict.

The claims are data (reports/paper_claims.csv, one row per claim; `--claims FILE` for another):
id, env (one env or several separated by spaces: one verdict per env), kind, a and b (optimizer
names separated by spaces), threshold (metric kinds only), statement (the paper's words), source
(figure), note (why a claim cannot be tested, shown as the reason).

Kinds and how each is decided, on the final best losses of the env's 'done' runs (the panel with
the env's largest budget; NULL = +inf, stats.final_values):
- a_below_b:       every optimizer of a has a lower final loss than every one of b: one one-sided
                   Mann-Whitney U test (a < b) per pair; holds when every Holm-corrected p < alpha.
- a_best:          a_below_b with b = every other optimizer with a done run on the env.
- not_below:       a is not significantly lower than b: one-sided tests (a < b); holds when no
                   Holm-corrected p < alpha.
- not_significant: a and b do not differ: two-sided tests; holds when no Holm-corrected p < alpha.
- metric_most / metric_few: each optimizer of a reaches the env's second metric (evals.metric at
                   each run's best episode) >= threshold in more / fewer than half of its seeds.
- not_testable:    what the paper says cannot be read from the database (the note says why).
An optimizer whose seeds are one run on the env (stats.seed_free: every run recorded seed-free over
all its episodes, as gd's from the box centre) is one sample, not one per seed: a pair with it is
tested by the exact sign test of the other side's seeds against its one value, and a pair of two
such optimizers by their order, which is certain (stats.compare_p); its metric share is exact.
Holm runs over the comparisons of one claim on one env. Verdicts: 'holds', 'does not hold', 'not
testable from the database', and for a claim the data cannot settle yet (no done run of the env
or of an optimizer of the claim, or 'not enough data': some comparison could not reach alpha even
with perfectly separated samples, comparisons x smallest exact p >= alpha, see stats.min_seeds;
but a claim needing every comparison significant does not hold once a testable one has p >= alpha
before Holm, whatever its short ones would give)
what it still needs (claim_runs.assess): 'env missing' (the harness has no such env), 'runs
missing: k of n done' (runs it needs are absent from the database), 'runs incomplete: k of n done'
(some of them are running or failed), or 'not enough data' when every run it needs is done. Such
a row names the command that makes its runs (settle).
"""
from __future__ import annotations

import csv
import math
from dataclasses import dataclass

import numpy as np
import pandas as pd

from . import claim_runs, stats

HOLDS, FAILS = "holds", "does not hold"
NO_DATA, UNTESTABLE = "not enough data", "not testable from the database"
NO_RUNS = "no done run"      # as judged; _still_needed says what is missing (claim_runs.assess)
MISSING = claim_runs.ENV_MISSING
TEST_KINDS = {"a_below_b": (1, True), "a_best": (1, True),      # (sides, holds if significant)
              "not_below": (1, False), "not_significant": (2, False)}
METRIC_KINDS = ("metric_most", "metric_few")
KINDS = tuple(TEST_KINDS) + METRIC_KINDS + ("not_testable",)
RATE_MIN_SEEDS = stats.min_seeds(1, 1)   # a rate over fewer seeds than one test needs says nothing
REQUIRED_COLUMNS = ("id", "env", "kind", "a", "b", "statement", "source")
CLAIM_COLUMNS = ["id", "env", "budget", "kind", "statement", "source", "test", "a", "b", "n", "comparisons",
                 "min_n", "p_holm", "p_claim", "a12", "a12_claim", "verdict", "reason", "runs_done",
                 "runs_needed", "settle"]
COMPARISON_COLUMNS = ["id", "env", "a", "b", "alternative", "test", "n_a", "n_b", "p_raw", "p_holm", "a12"]


class ClaimsError(Exception):
    """The claims file cannot be used (one-line message)."""


@dataclass
class Claim:
    id: str
    envs: list
    kind: str
    a: list
    b: list
    threshold: float
    statement: str
    source: str
    note: str


def load(path: str) -> list:
    """Read and check the claims file: known kind, unique id, an optimizer in a, b where needed."""
    try:
        with open(path, newline="", encoding="utf-8") as f:
            rows = list(csv.DictReader(f))
    except OSError as e:
        raise ClaimsError(f"cannot read claims file '{path}': {e.strerror or e}") from None
    if rows and any(c not in rows[0] for c in REQUIRED_COLUMNS):
        raise ClaimsError(f"claims file '{path}' needs the columns {', '.join(REQUIRED_COLUMNS)}")
    claims, seen = [], set()
    for line, r in enumerate(rows, start=2):
        where = f"claims file '{path}' line {line}"
        c = Claim(id=(r.get("id") or "").strip(), envs=(r.get("env") or "").split(),
                  kind=(r.get("kind") or "").strip(), a=(r.get("a") or "").split(),
                  b=(r.get("b") or "").split(), threshold=_number(r.get("threshold"), where),
                  statement=(r.get("statement") or "").strip(),
                  source=(r.get("source") or "").strip(), note=(r.get("note") or "").strip())
        if not c.id or c.id in seen:
            raise ClaimsError(f"{where}: empty or repeated id '{c.id}'")
        if c.kind not in KINDS:
            raise ClaimsError(f"{where}: kind '{c.kind}' is not one of {', '.join(KINDS)}")
        if not c.envs or not c.a:
            raise ClaimsError(f"{where}: env and a must name at least one env and optimizer")
        if c.kind in ("a_below_b", "not_below", "not_significant") and not c.b:
            raise ClaimsError(f"{where}: kind {c.kind} needs optimizers in b")
        seen.add(c.id)
        claims.append(c)
    return claims


def _number(text, where) -> float:
    if text is None or not text.strip():
        return float("nan")
    try:
        return float(text)
    except ValueError:
        raise ClaimsError(f"{where}: threshold '{text}' is not a number") from None


def evaluate(claims: list, panels: list, runs: pd.DataFrame | None = None, registry=None):
    """Verdict table (CLAIM_COLUMNS, one row per claim and env) and the comparisons behind it
    (COMPARISON_COLUMNS, one row per pair tested). panels: one per env (data.main_panels); runs:
    every run of the database (data.runs, any status); registry: `harness list` (registry.py) or
    None when no harness could be asked."""
    if runs is None:
        runs = pd.DataFrame(columns=["run_id", "env", "optimizer", "seed", "budget", "status"])
    by_env = {p.env: p for p in panels}
    rows, comps = [], []
    for c in claims:
        for env in c.envs:
            panel = by_env.get(env)
            row = dict(id=c.id, env=env, budget=panel.budget if panel else "", kind=c.kind,
                       statement=c.statement, source=c.source,
                       test=test_text(c), a=" ".join(c.a), b=" ".join(c.b), n="", comparisons=0,
                       min_n="", p_holm="", p_claim=np.nan, a12="", a12_claim=np.nan,
                       runs_done="", runs_needed="", settle="")
            row.update(_judge(c, env, panel, comps))
            row.update(_still_needed(c, env, row, runs, registry))
            rows.append(row)
    return (pd.DataFrame(rows, columns=CLAIM_COLUMNS),
            pd.DataFrame(comps, columns=COMPARISON_COLUMNS))


def _still_needed(c: Claim, env: str, row: dict, runs: pd.DataFrame, registry) -> dict:
    """For a row the data cannot settle yet ('env missing' or 'not enough data' as judged): the
    runs it still needs and the command (claim_runs.assess). 'not enough data' with every run of
    CLAIMS_SEEDS seeds done asks for the seeds the claim needs (min_n) and keeps its reason."""
    if row["verdict"] not in (NO_RUNS, NO_DATA):
        return {}
    seeds = claim_runs.CLAIMS_SEEDS
    if row["verdict"] == NO_DATA and row["min_n"] != "":
        seeds = max(seeds, int(row["min_n"]))
    out = claim_runs.assess(c.kind, c.a, c.b, env, runs, registry, seeds)
    if out["verdict"] is None:
        return {k: v for k, v in out.items() if k not in ("verdict", "reason")}
    if row["verdict"] == NO_DATA and out["verdict"] != MISSING:
        out["reason"] += " " + row["reason"][:1].upper() + row["reason"][1:] + "."
    return out


def test_text(c: Claim) -> str:
    if c.kind in TEST_KINDS:
        b = "every other optimizer" if c.kind == "a_best" else " ".join(c.b)
        side = "two-sided" if c.kind == "not_significant" else "one-sided, a lower"
        return f"Mann-Whitney U ({side}) of {' '.join(c.a)} vs {b}, Holm over the pairs"
    if c.kind in METRIC_KINDS:
        share = "more" if c.kind == "metric_most" else "fewer"
        return f"share of seeds with metric >= {stats_fmt(c.threshold)}: {share} than half"
    return "none"


def stats_fmt(v: float) -> str:
    return "?" if math.isnan(v) else f"{v:g}"


def _judge(c: Claim, env: str, panel, comps: list) -> dict:
    if c.kind == "not_testable":      # no run can settle it: before any check of the runs
        return dict(verdict=UNTESTABLE, reason=c.note or "the database does not record it")
    if panel is None:
        return dict(verdict=NO_RUNS, reason=f"no done run of {env}")
    b = [o for o in panel.optimizers if o not in c.a] if c.kind == "a_best" else c.b
    absent = [o for o in c.a + b if o not in panel.optimizers]
    if absent:
        return dict(verdict=NO_RUNS, reason=f"no done run of {', '.join(absent)} on {panel.env}")
    if c.kind == "a_best" and not b:
        return dict(verdict=NO_RUNS, reason=f"no other optimizer has a done run on {panel.env}")
    if c.kind in METRIC_KINDS:
        return _judge_rate(c, panel)
    return _judge_tests(c, b, panel, comps)


def _seeds_text(o: str, vals: dict, one: dict) -> str:
    """'cmaes 5', or 'gd 5 seeds = 1 run' for an optimizer whose seeds are one run."""
    return f"{o} {len(vals[o])} seeds = 1 run" if one[o] else f"{o} {len(vals[o])}"


def _judge_tests(c: Claim, b: list, panel, comps: list) -> dict:
    """One test per pair (a_i, b_j): Mann-Whitney U, or the exact sign test against an optimizer
    whose seeds are one run (stats.compare_p); Holm over the claim's pairs, and the verdict."""
    sides, want_significant = TEST_KINDS[c.kind]
    alternative = "two-sided" if sides == 2 else "less"
    pairs = [(x, y) for x in c.a for y in b if x != y]
    names = list(dict.fromkeys(c.a + b))
    vals = {o: stats.final_values(panel, o) for o in names}   # one value per seed (A12, n)
    tested = {o: stats.sample(panel, o) for o in names}        # what the tests see
    one = {o: tested[o][1] for o in names}
    m = len(pairs)
    raw = [stats.compare_p(tested[x][0], one[x], tested[y][0], one[y], alternative) for x, y in pairs]
    adj = stats.holm(raw)
    a12 = [stats.a12_lower(vals[x], vals[y]) for x, y in pairs]
    for (x, y), p, q, e in zip(pairs, raw, adj, a12):
        comps.append(dict(id=c.id, env=panel.env, a=x, b=y, alternative=alternative,
                          test=stats.test_name(one[x], one[y]), n_a=len(tested[x][0]),
                          n_b=len(tested[y][0]), p_raw=p, p_holm=q, a12=e))
    against_one = any(one[x] != one[y] for x, y in pairs)
    out = dict(n="; ".join(_seeds_text(o, vals, one) for o in names),
               comparisons=m,
               min_n=max(stats.min_seeds(m, sides), stats.min_seeds(m, sides, against_one_run=True)
                         if against_one else 0),
               p_holm="; ".join(f"{x} vs {y} {q:.3g}" for (x, y), q in zip(pairs, adj)),
               a12="; ".join(f"{x} vs {y} {e:.2f}" for (x, y), e in zip(pairs, a12)))
    signs = [f"{x} vs {y}" for x, y in pairs if stats.test_name(one[x], one[y]) == "sign"]
    orders = [f"{x} vs {y}" for x, y in pairs if stats.test_name(one[x], one[y]) == "order"]
    if signs or orders:
        runs_text = ", ".join(o for o in names if one[o])
        out["test"] = test_text(c) + (
            f"; {runs_text}: seeds that are one run, so "
            + "; ".join(([f"exact sign test for {', '.join(signs)}"] if signs else [])
                        + ([f"the certain order of two single runs for {', '.join(orders)}"] if orders else [])))
    significant = [q < stats.ALPHA for q in adj]
    if want_significant:
        out.update(p_claim=max(adj), a12_claim=min(a12))
    else:
        out.update(p_claim=min(adj), a12_claim=max(a12) if sides == 1 else
                   max(a12, key=lambda e: abs(e - 0.5)))
    def reachable(x, y):   # a bound on the Holm p this pair could give (Holm's largest factor)
        return m * stats.min_p(len(tested[x][0]), one[x], len(tested[y][0]), one[y], sides)

    # what the tests already settle, short of seeds or not: every pair significant (a claim of
    # differences holds), or one pair significant (a claim of none fails). Holm multiplies only the
    # smallest p by m, so a pair whose bound m x min_p is >= alpha can still come out significant
    # when its test's smallest p is larger than the others' (a sign test's 1/32 beside
    # Mann-Whitney's 1/252 in one claim)
    settled = all(significant) if want_significant else any(significant)
    short = [] if settled else [(x, y) for x, y in pairs if reachable(x, y) >= stats.ALPHA]
    # a claim that needs every comparison significant fails on a testable one whose p is >= alpha
    # before Holm (Holm's p is never below the raw p): the comparisons still short of seeds cannot
    # make it hold, so they do not hold the verdict back
    unreachable = sorted(((x, y, p) for (x, y), p in zip(pairs, raw) if (x, y) not in short and p >= stats.ALPHA),
                         key=lambda t: -t[2]) if want_significant and short else []
    if unreachable:
        x, y, p = unreachable[0]
        out.update(verdict=FAILS, reason=(
            f"{x} vs {y}: p {p:.3g} >= {stats.ALPHA} before Holm"
            + (f" (and {len(unreachable) - 1} more)" if len(unreachable) > 1 else "")
            + f"; {len(short)} comparison(s) short of seeds cannot change that"))
        return out
    if short:
        x, y = short[0]
        out.update(verdict=NO_DATA, reason=(
            f"{_seeds_text(x, vals, one)} vs {_seeds_text(y, vals, one)}"
            f"{'' if one[x] or one[y] else ' seeds'}: with {m} comparison(s) the smallest "
            f"reachable Holm p is {reachable(x, y):.3g} "
            f">= {stats.ALPHA}; needs >= {out['min_n']} seeds per optimizer"))
        return out
    if want_significant:
        bad = sorted(((x, y, q) for (x, y), q, s in zip(pairs, adj, significant) if not s),
                     key=lambda t: -t[2])
        out.update(verdict=FAILS if bad else HOLDS, reason=(
            f"{bad[0][0]} vs {bad[0][1]}: Holm p {bad[0][2]:.3g} >= {stats.ALPHA}"
            + (f" (and {len(bad) - 1} more)" if len(bad) > 1 else "") if bad else
            f"all {m} Holm-corrected p < {stats.ALPHA}"))
    else:
        hit = sorted(((x, y, q) for (x, y), q, s in zip(pairs, adj, significant) if s),
                     key=lambda t: t[2])
        out.update(verdict=FAILS if hit else HOLDS, reason=(
            f"{hit[0][0]} vs {hit[0][1]}: Holm p {hit[0][2]:.3g} < {stats.ALPHA}"
            + (f" (and {len(hit) - 1} more)" if len(hit) > 1 else "") if hit else
            f"no Holm-corrected p < {stats.ALPHA} ({m} comparison(s))"))
    return out


def _judge_rate(c: Claim, panel) -> dict:
    """Share of seeds whose metric at the run's best episode is >= threshold, per optimizer of a."""
    if not panel.has_metric:
        return dict(verdict=UNTESTABLE,
                    reason=f"{panel.env} stores no per-episode metric in this database (evals.metric is NULL)")
    if math.isnan(c.threshold):
        return dict(verdict=UNTESTABLE, reason="the claim gives no metric threshold")
    shares, ns, one = {}, {}, {}
    for o in c.a:
        m = panel.metric_at_best[panel.rows(o)]
        ns[o] = m.size
        one[o] = stats.seed_free(panel, o)   # its seeds are one run: its share is exact (0 or 1)
        shares[o] = float(np.mean(m >= c.threshold)) if m.size else float("nan")
    out = dict(n="; ".join(f"{o} {ns[o]}" + (" seeds = 1 run" if one[o] else "") for o in c.a),
               min_n=RATE_MIN_SEEDS, p_holm="", a12="")
    sampled = [ns[o] for o in c.a if not one[o]]
    if sampled and min(sampled) < RATE_MIN_SEEDS:
        return dict(out, verdict=NO_DATA, reason=f"fewer than {RATE_MIN_SEEDS} seeds")
    ok = [(s > 0.5) if c.kind == "metric_most" else (s < 0.5) for s in shares.values()]
    text = "; ".join(f"{o} {shares[o]:.0%} of {ns[o]} seeds" + (" (one run)" if one[o] else "") for o in c.a)
    return dict(out, verdict=HOLDS if all(ok) else FAILS,
                reason=f"metric >= {c.threshold:g}: {text}")
