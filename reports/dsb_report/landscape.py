"""Loss landscapes on 2-D slices from `harness landscape` CSVs: heat map + gradient arrows.

Input: DIR/<env>_<i>_<j>.csv with header i,j,xi,xj,loss,grad_i,grad_j and one row per grid point
(`harness landscape --check-step H` adds fd_i,fd_j,rel_err,agrees: the gradient checked against
central differences at every point). Output: landscape_<env>_<i>_<j>.png. Arrows show the descent
direction (minus the gradient) on at most MAX_ARROWS x MAX_ARROWS points, drawn with unit length and
colored by log10 |gradient|; where the file has the check, every point whose gradient disagrees with
central differences is marked with a small red cross.
"""
from __future__ import annotations

import math
import os
import re

import numpy as np
import pandas as pd
from matplotlib.colors import LogNorm

from .style import plt, save, yscale_for

NAME = re.compile(r"^(?P<env>.+)_(?P<i>\d+)_(?P<j>\d+)\.csv$")
COLUMNS = ["i", "j", "xi", "xj", "loss", "grad_i", "grad_j"]
MAX_ARROWS = 20


def find(directory: str) -> list:
    """(env, i, j, path) for every matching CSV in directory, sorted by file name."""
    out = []
    for name in sorted(os.listdir(directory)):
        m = NAME.match(name)
        if m and os.path.isfile(os.path.join(directory, name)):
            out.append((m["env"], int(m["i"]), int(m["j"]), os.path.join(directory, name)))
    return out


def _grid(df: pd.DataFrame, col: str, xs, ys) -> np.ndarray:
    return (df.pivot_table(index="xj", columns="xi", values=col, aggfunc="first", dropna=False)
            .reindex(index=ys, columns=xs).to_numpy(dtype=float))


def plot(env: str, i: int, j: int, csv_path: str, out_path: str) -> str:
    """Draw one file; returns a one-line description. Raises ValueError on a malformed file."""
    df = pd.read_csv(csv_path)
    if list(df.columns[:len(COLUMNS)]) != COLUMNS:
        raise ValueError(f"header must be {','.join(COLUMNS)}")
    for c in COLUMNS[2:]:
        df[c] = pd.to_numeric(df[c], errors="coerce")
    xs, ys = np.sort(df["xi"].dropna().unique()), np.sort(df["xj"].dropna().unique())
    if xs.size < 2 or ys.size < 2:
        raise ValueError("needs at least a 2 x 2 grid")
    loss = _grid(df, "loss", xs, ys)
    gi, gj = _grid(df, "grad_i", xs, ys), _grid(df, "grad_j", xs, ys)

    fig, ax = plt.subplots(figsize=(6.4, 5.2))
    sc = yscale_for(loss)             # same rule as the curves: log colors when it helps
    shown = sc(loss)
    fin = shown[np.isfinite(shown)]
    norm = LogNorm(vmin=fin.min(), vmax=fin.max()) if sc.log and fin.size else None
    what = sc.label("loss").replace("(log;", "(log colors;").replace("(log scale)", "(log colors)")
    mesh = ax.pcolormesh(xs, ys, np.ma.masked_invalid(shown), shading="nearest", cmap="viridis",
                         norm=norm)
    fig.colorbar(mesh, ax=ax, label=what)

    has_grad = np.isfinite(gi).any() and np.isfinite(gj).any()
    if has_grad:
        si = max(1, math.ceil(xs.size / MAX_ARROWS))
        sj = max(1, math.ceil(ys.size / MAX_ARROWS))
        X, Y = np.meshgrid(xs[::si], ys[::sj])
        u, v = -gi[::sj, ::si], -gj[::sj, ::si]
        mag = np.hypot(u, v)
        ok = np.isfinite(mag) & (mag > 0)
        un = np.where(ok, u / np.where(ok, mag, 1), np.nan)
        vn = np.where(ok, v / np.where(ok, mag, 1), np.nan)
        c = np.log10(np.where(ok, mag, np.nan))
        q = ax.quiver(X[ok], Y[ok], un[ok], vn[ok], c[ok], cmap="autumn", angles="xy",
                      pivot="middle", scale=1.1 * max(xs.size / si, ys.size / sj), width=0.005,
                      edgecolor="black", linewidth=0.4)
        fig.colorbar(q, ax=ax, label="log10 |gradient|", pad=0.02)
    checked = ""
    if "agrees" in df.columns:
        agrees = pd.to_numeric(df["agrees"], errors="coerce")
        bad = df[agrees != 1]
        ax.plot(bad["xi"], bad["xj"], linestyle="none", marker="x", markersize=3, color="red",
                markeredgewidth=0.8)
        checked = (f"gradient agrees with central differences at {int((agrees == 1).sum())} of "
                   f"{len(df)} points")
    ax.set_xlabel(f"x[{i}] (normalized)")
    ax.set_ylabel(f"x[{j}] (normalized)")
    arrows = "arrows: −gradient (descent), unit length" if has_grad else "no gradient in file"
    if checked:
        arrows += f"; red ×: disagrees ({checked.split(' at ')[1]} agree)"
    ax.set_title(f"{env}: loss on the slice x[{i}], x[{j}]\n{arrows}")
    ax.set_aspect("auto")
    save(fig, out_path)
    return (f"{xs.size} x {ys.size} grid, {'with' if has_grad else 'without'} gradients"
            + (f"; {checked}" if checked else ""))
