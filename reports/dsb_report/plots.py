"""The report's charts: a function that draws each (one PNG) and, last, CHARTS, the declaration of
each chart (its file, section, alt text and caption: charts.py), which build.py draws and
index.html places. Adding a chart is its function and its declaration here."""
from __future__ import annotations

import numpy as np
import pandas as pd

from . import stats, with_archive
from .charts import ACROSS, PER_ENV, Chart
from .style import plt, save

WIDE = (7.6, 4.4)


def _finite_or_nan(v):
    v = np.asarray(v, dtype=float).copy()
    v[~np.isfinite(v)] = np.nan
    return v


def _log_episodes_axis(ax, max_episode: int):
    """Log x axis with plain-number ticks at 1, 2, 5, 10, ... episodes."""
    ax.set_xscale("log")
    ticks = stats.checkpoints(max(1, max_episode))
    ax.set_xticks(ticks, [str(t) for t in ticks])
    ax.minorticks_off()
    ax.set_xlabel("episodes (log scale)")


def _legend(ax):
    if not ax.get_legend_handles_labels()[0]:
        ax.text(0.5, 0.5, "no completed runs", transform=ax.transAxes, ha="center", va="center")
        return
    ax.legend(loc="center left", bbox_to_anchor=(1.01, 0.5), frameon=False)


MARKS_PER_CURVE = 4


def marker_episodes(budget: int, k: int, n: int, per_curve: int = MARKS_PER_CURVE) -> list:
    """Episodes (1-based) of the markers of the k-th of n curves: per_curve points spread evenly on
    a log scale over 1..budget, shifted by k/n of a step, so no two optimizers share a marker
    position (where the budget has room) and a curve lying under another still shows its marks."""
    if budget < 2:
        return [1]
    span = np.log(budget)
    out = []
    for m in range(per_curve):
        e = int(round(np.exp(span * (m + (k + 0.5) / max(n, 1)) / per_curve)))
        out.append(min(max(e, 1), budget))
    return sorted(set(out))


def curves(panel, pal: dict, ys, path: str, marks: dict | None = None):
    fig, ax = plt.subplots(figsize=WIDE)
    x = np.arange(1, panel.budget + 1)
    marks = marks or {}
    n = len(panel.optimizers)
    for k, o in enumerate(panel.optimizers):
        med, q25, q75 = stats.quantile_curves(panel, o)
        color, ls = pal[o]
        ax.fill_between(x, _finite_or_nan(ys(q25)), _finite_or_nan(ys(q75)), color=color,
                        alpha=0.18, lw=0, step="post")
        y = _finite_or_nan(ys(med))
        at = [e - 1 for e in marker_episodes(panel.budget, k, n)]
        mk = marks.get(o, "o")
        ax.plot(x, y, color=color, ls=ls, lw=1.8, drawstyle="steps-post", marker=mk, ms=6,
                markevery=at, mec="black", mew=0.6, label=with_archive.label(panel, o))
        # the markers again above every line, so a curve hidden under another keeps its marks
        ax.plot(x[at], y[at], ls="none", marker=mk, ms=6, color=color, mec="black", mew=0.6,
                zorder=5)
    ys.apply(ax)
    ax.set_xlim(1, panel.budget)
    ax.set_xlabel("episodes")
    ax.set_ylabel(ys.label("best loss so far"))
    ax.set_title(f"{panel.env}: best loss so far, median and IQR over seeds (budget {panel.budget})")
    _legend(ax)
    save(fig, path)


def finals(panel, table: pd.DataFrame, pal: dict, ys, path: str) -> dict:
    """The bar plot of the final best loss. Returns the pixel boxes (x0, y0, x1, y1) of the mean
    labels and of the tick labels as drawn, {'means': [...], 'ticks': [...]} (the test checks that
    they do not overlap)."""
    t = table[table["n_seeds"] > 0].reset_index(drop=True)
    fig, ax = plt.subplots(figsize=(max(4.8, 1.1 * len(t) + 2.5), 4.4))
    xs = np.arange(len(t))
    floor = ys.delta if ys.shifted else None
    for i, r in t.iterrows():
        color, _ = pal[r["optimizer"]]
        h = float(ys(r["mean"]))
        ax.bar(i, h if np.isfinite(h) else np.nan, width=0.65, color=color, alpha=0.85,
               edgecolor="black", lw=0.6)
        if not np.isfinite(h):
            ax.text(i, 0.97, "mean = ∞\n(a seed without\nfinite loss)", ha="center", va="top",
                    fontsize=8, transform=ax.get_xaxis_transform())
        lo, hi = float(ys(r["ci95_low"])), float(ys(r["ci95_high"]))
        if np.isfinite(lo) and np.isfinite(hi) and np.isfinite(h):
            if ys.log:
                lo = max(lo, floor if floor else h * 1e-3)
            ax.errorbar(i, h, yerr=[[max(h - lo, 0)], [max(hi - h, 0)]], color="black",
                        capsize=4, lw=1.2)
        v = _finite_or_nan(ys(stats.final_values(panel, r["optimizer"])))
        off = np.linspace(-0.18, 0.18, len(v)) if len(v) > 1 else np.zeros(len(v))
        ax.plot(i + off, v, "o", ms=3.5, color="black", alpha=0.75, zorder=3)
    labels = []
    for _, r in t.iterrows():
        mark = ("\n(best)" if r["is_best"] else "\n(too few seeds)" if r.get("too_few_seeds", False)
                else "\n≈ best" if r["indistinguishable_from_best"] else "")
        labels.append(f"{r['optimizer']}{mark}")
    ax.set_xticks(xs, labels, rotation=0 if len(t) <= 5 else 30,
                  ha="center" if len(t) <= 5 else "right")
    ys.apply(ax)
    ax.set_ylabel(ys.label("final best loss"))
    ax.set_title(f"{panel.env}: final best loss at {panel.budget} episodes\n"
                 f"bars = mean (value on the bar), whiskers = 95% CI (Student t), dots = seeds")
    ax.grid(axis="x", visible=False)
    lo, hi = ax.get_ylim()     # headroom above the tallest whisker for the mean labels
    if ys.log and lo > 0:
        ax.set_ylim(lo, hi * (hi / lo) ** 0.18)
    elif hi > lo:
        ax.set_ylim(lo, hi + 0.18 * (hi - lo))
    means = _mean_labels(ax, t, ys)
    fig.canvas.draw()
    boxes = {"means": [tuple(m.get_window_extent().extents) for m in means],
             "ticks": [tuple(lb.get_window_extent().extents) for lb in ax.get_xticklabels()
                       if lb.get_text()]}
    save(fig, path)
    return boxes


def _mean_labels(ax, t: pd.DataFrame, ys) -> list:
    """The mean of each bar (as plotted: the regret mean - f* on a regret axis, else the loss)
    written inside the axes, just above the bar's top and clamped to the axes' height band
    [0.04, 0.86] (axes fraction), so it never reaches the tick labels below the axis nor the
    title above; a mean that is not finite is already written at the top."""
    out = []
    lo, hi = ax.get_ylim()
    log = ax.get_yscale() == "log"
    for i, r in t.iterrows():
        m = float(ys(r["mean"])) if ys.regret else float(r["mean"])
        h, ci = float(ys(r["mean"])), float(ys(r["ci95_high"]))
        if not np.isfinite(m) or not np.isfinite(h):
            continue
        y = max(h, ci) if np.isfinite(ci) else h
        if log:
            frac = (np.log10(y) - np.log10(lo)) / (np.log10(hi) - np.log10(lo)) if y > 0 else 0.0
        else:
            frac = (y - lo) / (hi - lo) if hi > lo else 0.5
        frac = float(np.clip(frac + 0.02, 0.04, 0.86)) if np.isfinite(frac) else 0.04
        out.append(ax.text(i, frac, f"{m:.3g}", ha="center", va="bottom", fontsize=8,
                           transform=ax.get_xaxis_transform(), clip_on=True,
                           bbox=dict(boxstyle="round,pad=0.15", fc="white", ec="none", alpha=0.8)))
    return out


def ranks(mean_ranks: pd.DataFrame, pal: dict, n_envs: int, path: str):
    fig, ax = plt.subplots(figsize=WIDE)
    for o in sorted(mean_ranks["optimizer"].unique()):
        g = mean_ranks[mean_ranks["optimizer"] == o].sort_values("episodes")
        color, ls = pal[o]
        ax.plot(g["episodes"], g["mean_rank"], color=color, ls=ls, lw=1.8, marker="o", ms=4,
                label=f"{o} ({int(g['n_envs'].max())} envs)")
    _log_episodes_axis(ax, int(mean_ranks["episodes"].max()) if len(mean_ranks) else 1)
    ax.set_ylabel("average rank (1 = best, lower is better)")
    ax.set_title(f"Average rank of the median best-so-far over {n_envs} envs")
    _legend(ax)
    save(fig, path)


def ecdf(table: pd.DataFrame, pal: dict, n_envs: int, path: str):
    fig, ax = plt.subplots(figsize=WIDE)
    for o in sorted(table["optimizer"].unique()):
        g = table[table["optimizer"] == o]
        color, ls = pal[o]
        ax.plot(g["episodes"], g["fraction_solved"], color=color, ls=ls, lw=1.8,
                drawstyle="steps-post", label=f"{o} ({int(g['n_triples'].iloc[0])} triples)")
    max_e = int(table["episodes"].max()) if len(table) else 1
    _log_episodes_axis(ax, max_e)
    ax.set_ylim(-0.02, 1.02)
    ax.set_xlim(1, max(max_e, 2))
    ax.set_ylabel("fraction of (env, seed, target) solved")
    ax.set_title(f"Data profile over {n_envs} envs: targets f* + (f0 − f*)·10^−k, k = 1..5")
    _legend(ax)
    save(fig, path)


# Every chart of the report, in the order index.html shows them within their section.
CHARTS = (
    Chart(name="curves", section=PER_ENV, png="curves_{slug}.png",
          draw=lambda v, path: curves(v.panel, v.pal, v.ys, path, v.marks), alt="curves {env}",
          caption=("Each line is the median over seeds of the best loss found so far after that many "
                   "episodes; the shaded band spans the 25th to 75th percentile over seeds. Lower is "
                   "better. The legend gives n, the number of completed seeds. {scale}")),
    Chart(name="final", section=PER_ENV, png="final_{slug}.png",
          draw=lambda v, path: finals(v.panel, v.table, v.pal, v.ys, path), alt="final {env}",
          caption=("Bars: mean over seeds of the final best loss at the budget; whiskers: 95% "
                   "confidence interval of the mean (Student t with n−1 degrees of freedom, no "
                   "bootstrap); dots: the individual seeds. '(best)' marks the optimizer with the "
                   "lowest median final loss; '≈ best' marks those that a one-sided Mann-Whitney U "
                   "test (worse than it?), Holm-corrected over this env's comparisons, cannot tell "
                   "apart at α = 0.05; '(too few seeds)' where the seeds are too few for any test to "
                   "tell them apart (even perfectly separated samples would not reach α). The number "
                   "on each bar is its mean (the mean regret on a regret axis). {scale}")),
    Chart(name="ranks", section=ACROSS, png="ranks.png",
          draw=lambda v, path: ranks(v.mean_ranks, v.pal, v.n_envs, path), alt="average ranks",
          caption=("For each env and episode count, the optimizers are ranked by the median over "
                   "seeds of their best loss so far (1 = best; ties share the average rank). Each "
                   "line is the mean rank over the envs the optimizer ran on. Gradient optimizers do "
                   "not run on non-differentiable envs, so they may be ranked over fewer envs and "
                   "among fewer competitors (see the env count in the legend).")),
    Chart(name="ecdf", section=ACROSS, png="ecdf.png",
          draw=lambda v, path: ecdf(v.ecdf, v.pal, v.n_envs, path), alt="data profile",
          caption=("COCO-style data profile. For each env, f* is the best loss any optimizer found "
                   "and f0 the median loss of the first episode over all its runs; the targets are "
                   "f* + (f0 − f*)·10^−k for k = 1, 2, 3, 4, 5 (relative targets). An (env, seed, "
                   "target) triple is solved after e episodes when the best loss so far is ≤ the "
                   "target. Each line is the fraction of the optimizer's triples solved after e "
                   "episodes (over the envs it ran on): higher and further left is better; the right "
                   "end is the fraction solved within the budget.")),
)
