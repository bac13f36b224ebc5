"""The "Gradient quality" table: one row per env from the CSV of scripts/gradient-quality.sh
(`harness gradcheck --json` at seeded random points of each env; definitions in
captions.GRADIENT_QUALITY and docs/gradient-quality.md "Gradient quality")."""
from __future__ import annotations

import os

import pandas as pd

REQUIRED = ["env", "surveyed", "dim", "points", "seed", "amplitude", "step", "tolerance",
            "large_step", "agreeing", "agree_fraction", "exactly_zero", "zero_fraction",
            "norm_min", "norm_median", "norm_max", "large_step_directed", "large_step_opposed",
            "large_step_opposed_fraction", "large_step_ratio_median"]

HEADERS = ["env", "dim", "points", "agree", "exactly zero", "|grad| min", "|grad| median",
           "|grad| max", "opposed at large step", "large-step slope / |grad| (median)"]


class GradientQualityError(Exception):
    pass


def load(path: str) -> pd.DataFrame:
    """The survey's rows, in file order; GradientQualityError names what is wrong."""
    if not os.path.isfile(path):
        raise GradientQualityError(f"--gradient-quality: no file '{path}'")
    try:
        df = pd.read_csv(path, dtype={"env": str, "surveyed": str}, keep_default_na=False,
                         na_values=[""])
    except Exception as e:  # pandas' parser errors have several types
        raise GradientQualityError(f"--gradient-quality '{path}': cannot read it as CSV: {e}")
    missing = [c for c in REQUIRED if c not in df.columns]
    if missing:
        raise GradientQualityError(f"--gradient-quality '{path}': missing column(s) "
                                   + ", ".join(missing))
    return df


def _percent(v) -> str:
    return "—" if pd.isna(v) else f"{100.0 * float(v):.1f}%"


def _g(v, digits=3) -> str:
    return "—" if pd.isna(v) else f"{float(v):.{digits}g}"


def env_label(r) -> str:
    """The env, and the variant surveyed when it is another (fluid surveyed as fluid-h5)."""
    return r["env"] if r["surveyed"] == r["env"] else f"{r['env']} (as {r['surveyed']})"


def rows(df: pd.DataFrame) -> list:
    out = []
    for _, r in df.iterrows():
        opposed = ("—" if int(r["large_step_directed"]) == 0 else
                   f"{_percent(r['large_step_opposed_fraction'])} of {int(r['large_step_directed'])}")
        out.append([env_label(r), str(int(r["dim"])), str(int(r["points"])),
                    _percent(r["agree_fraction"]), _percent(r["zero_fraction"]),
                    _g(r["norm_min"]), _g(r["norm_median"]), _g(r["norm_max"]), opposed,
                    _g(r["large_step_ratio_median"])])
    return out


def row_classes(df: pd.DataFrame) -> list:
    """'best' where every point agrees and none is opposed; 'bad' where fewer than half agree or
    a quarter or more of the directed points are opposed at the large step."""
    cls = []
    for _, r in df.iterrows():
        agree = float(r["agree_fraction"])
        opposed = r["large_step_opposed_fraction"]
        opposed = 0.0 if pd.isna(opposed) else float(opposed)
        cls.append("best" if agree == 1.0 and opposed == 0.0 else
                   "bad" if agree < 0.5 or opposed >= 0.25 else "")
    return cls


def settings(df: pd.DataFrame) -> str:
    """The survey's settings as one phrase (each distinct value once)."""
    def values(col):
        return "/".join(str(v) for v in dict.fromkeys(df[col].tolist()))
    return (f"seed {values('seed')}, points uniform in [−a, a]^d with a = {values('amplitude')}, "
            f"step h = {values('step')}, tolerance {values('tolerance')}, large step "
            f"H = {values('large_step')}")
