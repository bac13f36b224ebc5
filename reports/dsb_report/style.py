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
DECADES_FOR_LOG = 2.0            # log y when positive values span more than this many decades
DELTA_REL = 1e-8                 # offset of the shifted scale, relative to max - f*


def setup():
    plt.rcParams.update({
        "font.size": 10, "axes.titlesize": 11, "axes.labelsize": 10, "legend.fontsize": 9,
        "xtick.labelsize": 9, "ytick.labelsize": 9, "figure.dpi": DPI, "savefig.dpi": DPI,
        "axes.grid": True, "grid.alpha": 0.3, "svg.hashsalt": "dsb",
    })


def palette(optimizers: list) -> dict:
    """Sorted optimizer names -> (color, linestyle), the same in every figure of a report."""
    colors = list(plt.get_cmap("tab10").colors) + list(plt.get_cmap("Dark2").colors)
    out = {}
    for i, name in enumerate(sorted(optimizers)):
        out[name] = (colors[i % len(colors)], LINESTYLES[(i // len(colors)) % len(LINESTYLES)])
    return out


@dataclass
class YScale:
    """How the loss of one panel is drawn: raw (linear or log) or shifted, loss - f* + delta, on log."""
    log: bool
    shifted: bool
    fstar: float = 0.0
    delta: float = 0.0

    def __call__(self, v):
        v = np.asarray(v, dtype=float)
        return v - self.fstar + self.delta if self.shifted else v

    def label(self, what: str = "best loss") -> str:
        if self.shifted:
            return f"{what} − f* + δ  (log; f* = {self.fstar:.6g}, δ = {self.delta:.1g})"
        return f"{what} (log scale)" if self.log else what

    def apply(self, ax):
        if self.log:
            ax.set_yscale("log")


def yscale_for(values: np.ndarray) -> YScale:
    """The rule: all finite values positive -> log when they span more than 2 decades, else linear;
    any value <= 0 (negative losses, or an exact 0) -> plot loss - f* + delta on a log scale, where
    f* is the lowest value and delta = 1e-8 * (max - f*) keeps the best run visible."""
    v = np.asarray(values, dtype=float)
    v = v[np.isfinite(v)]
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
