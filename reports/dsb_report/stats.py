"""Statistics: per-cell summaries, Student-t CIs, Mann-Whitney U with Holm (one- or two-sided),
the exact sign test against an optimizer whose seeds are one run, the smallest reachable p and
seed count, Vargha-Delaney A12, ranks, target ECDF.

Conventions (also stated in the report):
- final best loss of a run = runs.best_loss of a 'done' run; NULL (no finite episode) counts as +inf;
- an optimizer whose seeds are one run on an env (seed_free: each of its runs there was recorded
  seed-free over all its episodes, so no seed changed anything) is ONE sample, a constant: the
  other side is tested against it by the exact sign test (compare_p), not by Mann-Whitney;
- quantiles: linear interpolation (numpy default); CI: mean +- t(0.975, n-1) * s / sqrt(n);
- best optimizer of an env = lowest median final loss (ties: lower mean, then name);
- ranks: rank of the median best-so-far over seeds among the optimizers of an env, ties averaged.
"""
from __future__ import annotations

import math

import numpy as np
import pandas as pd
from scipy import stats as sps

ALPHA = 0.05
_SENTINEL = np.finfo(float).max
TARGET_EXPONENTS = (1, 2, 3, 4, 5)


def pct(values: np.ndarray, q, axis=None):
    """np.percentile where +inf means 'no finite loss'. numpy's interpolation turns inf into NaN
    even at weight 0, so inf is replaced by a finite sentinel and results beyond 1e300 mapped back."""
    v = np.where(np.isposinf(values), _SENTINEL, values)
    r = np.percentile(v, q, axis=axis)
    return np.where(r > 1e300, np.inf, r)


def checkpoints(max_budget: int) -> list:
    """1, 2, 5, 10, 20, 50, ... up to max_budget."""
    out, base = [], 1
    while base <= max_budget:
        out += [m * base for m in (1, 2, 5) if m * base <= max_budget]
        base *= 10
    return out


def final_values(panel, optimizer: str) -> np.ndarray:
    v = panel.runs.loc[panel.runs["optimizer"] == optimizer, "best_loss"].to_numpy(dtype=float)
    return np.where(np.isnan(v), np.inf, v)


def seed_free(panel, optimizer: str) -> bool:
    """True when the optimizer's runs in the panel are one run, whatever their seeds: every run
    has its seed-free prefix recorded (runs.seed_free_episodes, counted by the harness's budget
    wrapper: the episodes before the optimizer's first draw from its RNG) and covering all its
    episodes, and their final best losses are equal (a check: one run key, one result). A run
    without the record (NULL, or a runs CSV from before the column) is not: equal final losses alone
    never make seeds one run, since two seeds can tie (nlopt-lbfgs on sphere-2 reaches 0.0 in the
    3 episodes before its first draw and every seed ties there, though its runs differ after)."""
    r = panel.runs[panel.runs["optimizer"] == optimizer]
    if r.empty or "seed_free_episodes" not in r.columns:
        return False
    free = pd.to_numeric(r["seed_free_episodes"], errors="coerce").to_numpy(dtype=float)
    episodes = pd.to_numeric(r["episodes"], errors="coerce").to_numpy(dtype=float)
    if not (np.all(np.isfinite(free)) and np.all(np.isfinite(episodes)) and np.all(free >= episodes)):
        return False
    v = final_values(panel, optimizer)
    return bool(np.all(v == v[0]))


def sample(panel, optimizer: str):
    """(values, constant): the final best losses the tests see. An optimizer whose seeds are one
    run (seed_free) is one value and constant=True; any other, one value per seed."""
    v = final_values(panel, optimizer)
    if v.size and seed_free(panel, optimizer):
        return v[:1], True
    return v, False


def sign_test_p(x: np.ndarray, c: float, alternative: str = "two-sided") -> float:
    """Exact sign test of a sample x against a constant c (a seed-free optimizer's one run).
    alternative 'less': whether x tends to be lower than c (H0: P(x < c) = P(x > c)); k = #(x < c)
    of the n values that differ from c, p = P(Bin(n, 1/2) >= k); 'greater' the mirror; 'two-sided'
    twice the smaller tail, at most 1 (scipy.stats.binomtest). Values equal to c drop out; 1.0 when
    none is left, NaN when x is empty. Valid for any continuous distribution of x (no symmetry
    assumed, unlike the one-sample Wilcoxon signed-rank test); with n values the smallest one-sided
    p is 2^-n (1/32 at 5 seeds)."""
    x = np.asarray(x, dtype=float)
    if x.size == 0 or (isinstance(c, float) and math.isnan(c)):
        return float("nan")
    below, above = int(np.sum(x < c)), int(np.sum(x > c))
    n = below + above
    if n == 0:
        return 1.0
    if alternative == "less":
        return float(sps.binomtest(below, n, 0.5, alternative="greater").pvalue)
    if alternative == "greater":
        return float(sps.binomtest(above, n, 0.5, alternative="greater").pvalue)
    return float(sps.binomtest(below, n, 0.5, alternative="two-sided").pvalue)


_MIRROR = {"less": "greater", "greater": "less", "two-sided": "two-sided"}


def test_name(a_constant: bool, b_constant: bool) -> str:
    """The test compare_p runs for these sides: 'mann-whitney' (two samples), 'sign' (a sample
    against one run), 'order' (two single runs)."""
    return "order" if a_constant and b_constant else "sign" if a_constant or b_constant else "mann-whitney"


def compare_p(a: np.ndarray, a_constant: bool, b: np.ndarray, b_constant: bool,
              alternative: str = "two-sided") -> float:
    """p-value of 'a tends lower than b' ('less'), 'higher' ('greater') or 'differs' ('two-sided'),
    each side a sample (one value per seed) or a constant (sample(): one value, the seed-free
    optimizer's run). Two samples: Mann-Whitney U (mwu_p). A sample against a constant: the exact
    sign test (sign_test_p). Two constants: nothing varies, so the order is certain: 0.0 when it is
    the alternative's (a < b for 'less', a > b for 'greater', a != b two-sided), else 1.0. NaN when a
    side is empty."""
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    if a.size == 0 or b.size == 0:
        return float("nan")
    if a_constant and b_constant:
        ca, cb = float(a[0]), float(b[0])
        certain = {"less": ca < cb, "greater": ca > cb, "two-sided": ca != cb}[alternative]
        return 0.0 if certain else 1.0
    if b_constant:
        return sign_test_p(a, float(b[0]), alternative)
    if a_constant:
        return sign_test_p(b, float(a[0]), _MIRROR[alternative])
    return mwu_p(a, b, alternative)


def min_p(n_a: int, a_constant: bool, n_b: int, b_constant: bool, sides: int = 2) -> float:
    """The smallest p compare_p can give for these sides: min_exact_p for two samples, sides x
    2^-n for n seeds against one run (the sign test), 0 for two single runs (their order is
    certain)."""
    if a_constant and b_constant:
        return 0.0 if n_a >= 1 and n_b >= 1 else float("nan")
    if a_constant or b_constant:
        n = n_b if a_constant else n_a
        return min(1.0, sides * 0.5 ** n) if n >= 1 and (n_a >= 1 and n_b >= 1) else float("nan")
    return min_exact_p(n_a, n_b, sides)


def t_ci(values: np.ndarray, level: float = 0.95):
    n = len(values)
    if n < 2 or not np.all(np.isfinite(values)):
        return float("nan"), float("nan")
    m, s = float(np.mean(values)), float(np.std(values, ddof=1))
    h = float(sps.t.ppf(0.5 + level / 2, n - 1)) * s / math.sqrt(n)
    return m - h, m + h


def holm(pvals: list) -> list:
    """Holm step-down adjusted p-values, same order as given; NaN stays NaN and is not counted."""
    idx = [i for i, p in enumerate(pvals) if not math.isnan(p)]
    m = len(idx)
    out = [float("nan")] * len(pvals)
    running = 0.0
    for rank, i in enumerate(sorted(idx, key=lambda i: pvals[i])):
        running = max(running, min(1.0, (m - rank) * pvals[i]))
        out[i] = running
    return out


def mwu_p(a: np.ndarray, b: np.ndarray, alternative: str = "two-sided") -> float:
    """Mann-Whitney U p-value of samples a and b (scipy: exact for small samples without ties,
    normal approximation otherwise). alternative 'less' tests whether a tends to be lower than b
    (one-sided); 'two-sided' whether they differ. NaN when a side is empty; 1.0 when every value
    is the same (nothing to tell apart)."""
    if len(a) == 0 or len(b) == 0:
        return float("nan")
    both = np.concatenate([a, b])
    if np.all(both == both[0]):
        return 1.0
    return float(sps.mannwhitneyu(a, b, alternative=alternative).pvalue)


def min_exact_p(n1: int, n2: int, sides: int = 2) -> float:
    """Smallest exact Mann-Whitney p-value for sample sizes n1, n2 (no ties): the probability of
    the one most extreme ranking, 1/C(n1+n2, n1), doubled for a two-sided test (sides=2)."""
    if n1 < 1 or n2 < 1:
        return float("nan")
    return min(1.0, sides / math.comb(n1 + n2, n1))


def min_seeds(comparisons: int, sides: int, alpha: float = ALPHA, limit: int = 100,
              against_one_run: bool = False) -> int:
    """Smallest n such that, with n seeds on each side, a claim of `comparisons` Holm-corrected
    Mann-Whitney tests can reach alpha at all: comparisons * min_exact_p(n, n, sides) < alpha
    (Holm multiplies the smallest p by the number of comparisons). One comparison: 4 seeds
    (one-sided 1/70, two-sided 2/70); with 3 the best possible one-sided p is 1/20 = alpha.
    against_one_run: n seeds tested by the sign test against a seed-free optimizer's one run,
    comparisons * sides * 2^-n < alpha: one one-sided comparison needs 5 (1/32; 4 give 1/16)."""
    for n in range(1, limit + 1):
        if comparisons * min_p(n, False, n, against_one_run, sides) < alpha:
            return n
    return limit


def too_few_seeds(comparisons: int, n1: int, n2: int, sides: int = 2, alpha: float = ALPHA,
                  constant1: bool = False, constant2: bool = False) -> bool:
    """True when a Holm-corrected test among `comparisons` cannot reach alpha even with perfectly
    separated samples of sizes n1 and n2: comparisons * min_p(...) >= alpha (the rule of the
    claims' 'not enough data'; a constant side is a seed-free optimizer's one run, min_p).
    'Cannot tell from the best' then says nothing."""
    if comparisons < 1 or n1 < 1 or n2 < 1:
        return False
    return comparisons * min_p(n1, constant1, n2, constant2, sides) >= alpha


def a12_lower(a: np.ndarray, b: np.ndarray) -> float:
    """Vargha-Delaney A12 oriented to 'lower is better': the probability that a run of a ends
    with a lower final loss than a run of b, ties counting half (0.5 = no effect, 1 = a always
    lower, 0 = a always higher). +inf (no finite loss) ties with +inf. NaN when a side is empty."""
    if len(a) == 0 or len(b) == 0:
        return float("nan")
    x, y = np.asarray(a, float)[:, None], np.asarray(b, float)[None, :]
    return float(np.mean((x < y) + 0.5 * (x == y)))


def final_table(panel, all_runs: pd.DataFrame) -> pd.DataFrame:
    """One row per optimizer of (env, budget): summaries of the final best loss over seeds, and the
    significance against the best optimizer (Mann-Whitney U, one-sided: is it worse than the best?
    Holm over the env)."""
    cell = all_runs[(all_runs["env"] == panel.env) & (all_runs["budget"] == panel.budget)]
    opts = sorted(set(panel.optimizers) | set(cell["optimizer"]))
    rows = []
    for opt in opts:
        v = final_values(panel, opt)
        c = cell[cell["optimizer"] == opt]
        sel = panel.runs[panel.runs["optimizer"] == opt]
        distinct, one_run = sample(panel, opt)
        lo, hi = t_ci(distinct)    # one run: no interval
        fin = v.size > 0
        rows.append(dict(
            env=panel.env, budget=panel.budget, optimizer=opt, n_seeds=int(v.size), seed_free=bool(one_run),
            failed_runs=int((c["status"] == "failed").sum()),
            running_runs=int((c["status"] == "running").sum()),
            failed_episodes=int(sel["failed_episodes"].sum()),
            median=float(pct(v, 50)) if fin else np.nan,
            q25=float(pct(v, 25)) if fin else np.nan,
            q75=float(pct(v, 75)) if fin else np.nan,
            mean=float(np.mean(v)) if fin else np.nan,
            std=float(np.std(distinct, ddof=1)) if distinct.size > 1 and np.all(np.isfinite(distinct)) else np.nan,
            ci95_low=lo, ci95_high=hi,
            min=float(np.min(v)) if fin else np.nan,
            max=float(np.max(v)) if fin else np.nan,
            median_wall_s=float(sel["wall_s"].median()) if fin else np.nan,
            metric_median=_metric_median(panel, opt)))
    df = pd.DataFrame(rows)
    return _add_significance(panel, df)


def _metric_median(panel, optimizer: str) -> float:
    """Median over seeds of the env's second metric at each run's best episode (NaN: none)."""
    m = panel.metric_at_best[panel.rows(optimizer)] if panel.metric_at_best.size else np.zeros(0)
    m = m[np.isfinite(m)]
    return float(np.median(m)) if m.size else np.nan


def _add_significance(panel, df: pd.DataFrame) -> pd.DataFrame:
    df["is_best"] = False
    df["p_raw"] = np.nan
    df["p_holm"] = np.nan
    df["indistinguishable_from_best"] = False
    df["too_few_seeds"] = False
    have = df[df["n_seeds"] > 0]
    if have.empty:
        return df
    best = have.sort_values(["median", "mean", "optimizer"]).iloc[0]["optimizer"]
    ref, ref_one = sample(panel, best)
    others = [o for o in have["optimizer"] if o != best]
    # one-sided: the question is whether an optimizer ends worse than the winner (the winner is the
    # lowest median by construction); two-sided tests could never separate 10 optimizers at the
    # default 5 seeds (9 x 2/C(10,5) = 0.071 > alpha after Holm; one-sided 9 x 1/252 = 0.036).
    # A side whose seeds are one run is one value: the sign test against it (compare_p)
    sides = {o: sample(panel, o) for o in others}
    raw = [compare_p(sides[o][0], sides[o][1], ref, ref_one, "greater") for o in others]
    adj = holm(raw)
    for o, p, q in zip(others, raw, adj):
        i = df.index[df["optimizer"] == o][0]
        df.loc[i, ["p_raw", "p_holm"]] = [p, q]
        tie = bool(not math.isnan(q) and q >= ALPHA)
        df.loc[i, "indistinguishable_from_best"] = tie
        # 'too few seeds' replaces a tie only: Holm multiplies the smallest p alone by the number
        # of comparisons, so a pair can come out significant though that bound says it could not
        df.loc[i, "too_few_seeds"] = tie and too_few_seeds(len(others), sides[o][0].size, ref.size, sides=1,
                                                          constant1=sides[o][1], constant2=ref_one)
    i = df.index[df["optimizer"] == best][0]
    df.loc[i, "is_best"] = True
    df.loc[i, "indistinguishable_from_best"] = True
    return df


def quantile_curves(panel, optimizer: str):
    """Median, q25, q75 over seeds of the best loss so far per episode (+inf = none yet)."""
    b = panel.best[panel.rows(optimizer)]
    if b.size == 0:
        return None
    q = pct(b, [50, 25, 75], axis=0)
    return q[0], q[1], q[2]


def ranks(panels: list) -> pd.DataFrame:
    """Long table env, episodes, optimizer, median_best, rank (1 = best, ties averaged)."""
    rows = []
    for p in panels:
        for c in checkpoints(p.budget):
            meds = {}
            for o in p.optimizers:
                b = p.best[p.rows(o), c - 1]
                meds[o] = float(pct(b, 50))
            r = pd.Series(meds).rank(method="average")
            for o in p.optimizers:
                rows.append((p.env, c, o, meds[o], float(r[o]), len(p.optimizers)))
    return pd.DataFrame(rows, columns=["env", "episodes", "optimizer", "median_best", "rank",
                                       "n_optimizers"])


def mean_ranks(by_env: pd.DataFrame) -> pd.DataFrame:
    if by_env.empty:
        return pd.DataFrame(columns=["episodes", "optimizer", "mean_rank", "n_envs"])
    g = by_env.groupby(["episodes", "optimizer"])["rank"]
    return (pd.DataFrame({"mean_rank": g.mean(), "n_envs": g.size()}).reset_index()
            .sort_values(["episodes", "optimizer"]).reset_index(drop=True))


def targets(panel) -> tuple:
    """Relative targets f* + (f0 - f*) 10^-k, k in TARGET_EXPONENTS."""
    fs, f0 = panel.fstar, panel.f0
    gap = f0 - fs if math.isfinite(f0) and math.isfinite(fs) and f0 > fs else 0.0
    return fs, f0, [fs + gap * 10.0 ** (-k) for k in TARGET_EXPONENTS]


def first_hits(panel, optimizer: str, tlist: list) -> np.ndarray:
    """Episodes (1-based) until best-so-far <= target, per (seed, target); inf if never."""
    b = panel.best[panel.rows(optimizer)]
    out = np.full((b.shape[0], len(tlist)), np.inf)
    for k, t in enumerate(tlist):
        hit = b <= t
        any_hit = hit.any(axis=1)
        out[any_hit, k] = hit[any_hit].argmax(axis=1) + 1
    return out.ravel()


def ecdf(panels: list, optimizers: list):
    """Fraction of (env, seed, target) triples solved per optimizer at every episode count.
    Returns (long table optimizer, episodes, fraction_solved, n_triples; per-env targets)."""
    hits = {o: [] for o in optimizers}
    tinfo = []
    for p in panels:
        fs, f0, tl = targets(p)
        tinfo.append(dict(env=p.env, budget=p.budget, f_star=fs, f0=f0,
                          **{f"target_1e-{k}": t for k, t in zip(TARGET_EXPONENTS, tl)}))
        for o in p.optimizers:
            hits[o].append(first_hits(p, o, tl))
    max_b = max((p.budget for p in panels), default=0)
    episodes = np.arange(1, max_b + 1)
    rows = []
    for o in optimizers:
        if not hits[o]:
            continue
        h = np.sort(np.concatenate(hits[o]))
        frac = np.searchsorted(h, episodes, side="right") / h.size
        rows.append(pd.DataFrame(dict(optimizer=o, episodes=episodes, fraction_solved=frac,
                                      n_triples=h.size)))
    table = pd.concat(rows, ignore_index=True) if rows else pd.DataFrame(
        columns=["optimizer", "episodes", "fraction_solved", "n_triples"])
    return table, pd.DataFrame(tinfo)
