"""Figure style: one fixed color (and line style) per optimizer, fonts, dpi, the y-scale rule."""
from __future__ import annotations

import math
from dataclasses import dataclass

import matplotlib
import numpy as np

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402  (after the backend is fixed)

DPI = 110
LINESTYLES = ["-", "--", "-.", ":"]
MARKERS = ["o", "s", "^", "D", "v", "P", "X", "*", "<", ">", "h", "p"]
DECADES_FOR_LOG = 2.0            # log y when positive values span more than this many decades
DELTA_REL = 1e-8                 # offset of the shifted scale, relative to max - f*
REGRET_FLOOR_REL = 1e-15         # regret drawn at most at this, relative to max(1, |f*|)


def setup():
    plt.rcParams.update({
        "font.size": 10, "axes.titlesize": 11, "axes.labelsize": 10, "legend.fontsize": 9,
        "xtick.labelsize": 9, "ytick.labelsize": 9, "figure.dpi": DPI, "savefig.dpi": DPI,
        "axes.grid": True, "grid.alpha": 0.3, "svg.hashsalt": "dsb",
    })


def palette(optimizers: list) -> dict:
    """Sorted optimizer names -> (color, linestyle), the same in every figure of a report. The line
    style cycles with the optimizer's index, so two curves on top of each other still show both
    (the dashes of the upper one let the lower one through)."""
    colors = list(plt.get_cmap("tab10").colors) + list(plt.get_cmap("Dark2").colors)
    out = {}
    for i, name in enumerate(sorted(optimizers)):
        out[name] = (colors[i % len(colors)], LINESTYLES[i % len(LINESTYLES)])
    return out


def markers(optimizers: list) -> dict:
    """Sorted optimizer names -> a marker shape, distinct for the first len(MARKERS) optimizers."""
    return {name: MARKERS[i % len(MARKERS)] for i, name in enumerate(sorted(optimizers))}


@dataclass
class YScale:
    """How the loss of one panel is drawn: raw (linear or log); shifted, loss - f* + delta on log,
    f* the best loss found; or regret, loss - f* on log, f* the env's known optimum (values <= floor,
    a loss at f* to rounding, drawn at floor)."""
    log: bool
    shifted: bool
    fstar: float = 0.0
    delta: float = 0.0
    regret: bool = False
    floor: float = 0.0

    def __call__(self, v):
        v = np.asarray(v, dtype=float)
        if self.regret:
            r = v - self.fstar
            return np.where(np.isfinite(r) & (r < self.floor), self.floor, r)
        return v - self.fstar + self.delta if self.shifted else v

    def label(self, what: str = "best loss") -> str:
        if self.regret:
            return f"regret: {what} − f*\n(log; known optimum f* = {self.fstar:.10g})"
        if self.shifted:
            return f"{what} − f* + δ  (log; f* = {self.fstar:.6g}, δ = {self.delta:.1g})"
        return f"{what} (log scale)" if self.log else what

    def apply(self, ax):
        if self.log:
            ax.set_yscale("log")


def yscale_for(values: np.ndarray, known_fstar: float | None = None) -> YScale:
    """The rule: an env with a known optimum f* (optima.py) -> the regret loss - f* on a log scale
    (a regret <= 0, a loss at f* to rounding, drawn at the floor: a tenth of the smallest positive
    regret, at most 1e-15 max(1, |f*|)); otherwise all finite values positive -> log when they span
    more than 2 decades, else linear; any value <= 0 (negative losses, or an exact 0) -> plot
    loss - f* + delta on a log scale, where f* is the lowest value and delta = 1e-8 * (max - f*)
    keeps the best run visible."""
    v = np.asarray(values, dtype=float)
    v = v[np.isfinite(v)]
    if known_fstar is not None and math.isfinite(known_fstar):
        r = v - known_fstar
        pos = r[r > 0]
        floor = REGRET_FLOOR_REL * max(1.0, abs(known_fstar))
        if pos.size:
            floor = min(floor, float(pos.min())) / 10.0
        return YScale(log=True, shifted=False, fstar=float(known_fstar), regret=True, floor=floor)
    if v.size == 0:
        return YScale(log=False, shifted=False)
    lo, hi = float(v.min()), float(v.max())
    if lo > 0:
        return YScale(log=math.log10(hi / lo) > DECADES_FOR_LOG, shifted=False)
    span = hi - lo
    if span <= 0:
        return YScale(log=False, shifted=False)
    return YScale(log=True, shifted=True, fstar=lo, delta=DELTA_REL * span)


def save(fig, path: str):
    fig.savefig(path, dpi=DPI, bbox_inches="tight", metadata={"Software": None})
    plt.close(fig)
