"""Pictures of each env's best run (`harness render`, made by scripts/render-best.sh): copied
into the report and shown in the env's section with a caption naming the run."""
from __future__ import annotations

import math
import os
import re
import shutil
from html import escape

FILE = re.compile(r"^render_(.+)\.png$")
# the roles' colours of render/palette.cpp
COLOURS = ("target in red, the state in orange (its path so far light orange), what the "
           "parameters move in blue, fixed geometry in grey")


def best_run(runs, env: str):
    """The env's best done run as `harness render --best-of` picks it: the smallest best_loss,
    ties to the smallest run_id; None when there is none."""
    r = runs[(runs["env"] == env) & (runs["status"] == "done") & runs["best_loss"].notna()]
    if not len(r):
        return None
    return r.sort_values(["best_loss", "run_id"], kind="mergesort").iloc[0]


def collect(runs, render_dir, out: str, written: list) -> dict:
    """Copies DIR/render_<env>.png of the envs in `runs` into `out` (names added to `written`);
    returns {env: {png, caption}}. No directory: nothing."""
    if render_dir is None:
        return {}
    found = {}
    envs = set(runs["env"])
    for name in sorted(os.listdir(render_dir)):
        m = FILE.match(name)
        if not m or m.group(1) not in envs:
            continue
        env = m.group(1)
        shutil.copyfile(os.path.join(render_dir, name), os.path.join(out, name))
        written.append(name)
        b = best_run(runs, env)
        who = ("best run" if b is None else
               f"best run ({b['optimizer']}, seed {int(b['seed'])}, loss {_num(b['best_loss'])})")
        found[env] = dict(png=name, caption=f"{env}: {who} at 4 time points, left to right from the "
                                            f"start to the end of the episode; {COLOURS}.")
    return found


def _num(v) -> str:
    return f"{v:.4g}" if isinstance(v, float) and math.isfinite(v) else str(v)


def figure(ctx, env: str) -> str:
    """The env's render as an HTML figure, or '' when the report has none."""
    it = ctx.get("renders", {}).get(env)
    if not it:
        return ""
    return (f'<figure><img src="{escape(it["png"])}" alt="{escape("render " + env)}">'
            f"<figcaption>{escape(it['caption'])}</figcaption></figure>")
