"""Which stored runs are stale: made by other results versions than the harness's the report asks
(docs/database.md "Results versions"; harness/core/results_versions.cpp, whose rules this mirrors).

A run stores `runs.results_versions` = 'env E, optimizer O, run R' ('' in a database of schema 4
or older, which has no such column: made before versions). It is current when the three equal the
versions `harness list` gives its env and optimizer (registry.Registry.current_versions), and
stale otherwise, also when the harness does not know its env or optimizer. Without a harness to
ask (or a `harness list` without versions) nothing can be judged: every run counts as current.

By default the report leaves stale runs out of everything it computes. With --include-stale it
shows them as optimizers of their own, named as `harness export --format ioh --include-stale`
names them (OPT-stale-eEoOrR, OPT-stale-unversioned), so they are never pooled with the current
runs of their optimizer nor with another version's; the claims still judge current runs only.
"""
from __future__ import annotations

import re
from dataclasses import dataclass, field

import pandas as pd

UNVERSIONED = "made before results versions (a database of schema 4 or older)"
COLUMNS = ["env", "optimizer", "results_versions", "reason", "done", "unfinished", "shown_as"]
NOTE_GROUPS = 10     # the overview's note names at most this many (env, optimizer, reason) groups
_TEXT = re.compile(r"env ([0-9]+), optimizer ([0-9]+), run ([0-9]+)")


def parse(text: str) -> tuple:
    """(env, optimizer, run) of a stored results_versions; (0, 0, 0) for '' and for any text that
    is not exactly 'env E, optimizer O, run R' as the harness writes it (unknown)."""
    m = _TEXT.fullmatch(text or "")
    if not m:
        return (0, 0, 0)
    v = tuple(int(g) for g in m.groups())
    return v if _text(v) == text else (0, 0, 0)


def _text(v: tuple) -> str:
    return "" if v == (0, 0, 0) else f"env {v[0]}, optimizer {v[1]}, run {v[2]}"


def judgeable(registry) -> bool:
    """Whether `registry` lists results versions (a harness of schema 5 on)."""
    return registry is not None and bool(registry.versions) and registry.versions.get("run") is not None


def current(registry, env: str, optimizer: str) -> tuple:
    """This harness's (env, optimizer, run) versions for a run of env with optimizer; 0 for a name
    it does not know (an env variant has its listed env's, ext:NAME the adapter's)."""
    entry = registry.env_entry(env)
    e = registry.versions["env"].get(entry, 0) if entry is not None else 0
    o = registry.versions["optimizer"].get("ext:NAME" if optimizer.startswith("ext:") else optimizer, 0)
    return (e, o, registry.versions["run"])


def reason(registry, env: str, optimizer: str, stored_text: str) -> str:
    """Why a run of env and optimizer stored with `stored_text` is stale for this harness, e.g.
    'optimizer cmaes version 1, this binary's 2'; '' when it is current."""
    stored, now = parse(stored_text), current(registry, env, optimizer)
    if stored == now and now[0] > 0 and now[1] > 0:
        return ""
    if stored == (0, 0, 0):
        return UNVERSIONED
    parts = []
    for what, was, is_ in ((f"env {env}", stored[0], now[0]), (f"optimizer {optimizer}", stored[1], now[1]),
                           ("run code", stored[2], now[2])):
        if was == is_ and is_ > 0:
            continue
        parts.append(f"{what} version {was}, this binary's " + (str(is_) if is_ > 0 else "none (unknown here)"))
    return "; ".join(parts)


def label(optimizer: str, stored_text: str) -> str:
    """The name a stale run is shown under: its optimizer and its versions, as the IOH export
    names it (cmaes-stale-e1o2r1; cmaes-stale-unversioned when it stores none)."""
    if not stored_text:
        return f"{optimizer}-stale-unversioned"
    e, o, r = parse(stored_text)
    return f"{optimizer}-stale-e{e}o{o}r{r}"


@dataclass
class Staleness:
    """What the report did about results versions. judged: False when no harness could say
    (why_not); runs: the stale runs (their own optimizer names, status, results_versions, reason,
    label); shown: --include-stale."""
    judged: bool
    source: str = ""
    why_not: str = ""
    shown: bool = False
    runs: pd.DataFrame = field(default_factory=pd.DataFrame)

    @property
    def count(self) -> int:
        return len(self.runs)

    def table(self) -> pd.DataFrame:
        """One row per (env, optimizer, stored versions): COLUMNS (done and unfinished counts,
        shown_as the label when shown, else '')."""
        if not self.count:
            return pd.DataFrame(columns=COLUMNS)
        r = self.runs.assign(is_done=self.runs["status"].eq("done"))
        g = (r.groupby(["env", "optimizer", "results_versions", "reason", "stale_label"], sort=True)
             .agg(done=("is_done", "sum"), runs=("is_done", "size")).reset_index())
        g["unfinished"] = g["runs"] - g["done"]
        g["shown_as"] = g["stale_label"] if self.shown else ""
        return g[COLUMNS].astype({"done": int, "unfinished": int}).reset_index(drop=True)

    def note(self, total_runs: int) -> str:
        """The overview's sentence: how many runs were left out (or shown) and why, by env,
        optimizer and reason; or that staleness could not be judged. '' when nothing is stale."""
        if not self.judged:
            return (f"Staleness could not be judged: {self.why_not}, so all {total_runs} run(s) are kept, "
                    "whatever versions of the code made them (docs/database.md, \"Results versions\").")
        if not self.count:
            return ""
        t = self.table()
        done, unfinished = int(t["done"].sum()), int(t["unfinished"].sum())
        head = (f"{'Shown' if self.shown else 'Left out'}: {self.count} stale run(s) ({done} done, "
                f"{unfinished} unfinished), made by other results versions than this harness's "
                f"(`harness list` of {self.source}); "
                + ("each is its own optimizer, OPT-stale-eEoOrR or OPT-stale-unversioned, never pooled "
                   "with current runs, and the claims judge current runs only:" if self.shown else
                   "--include-stale shows them, marked:"))
        groups = [f"{r['env']} / {r['optimizer']}: {r['done']} done, {r['unfinished']} unfinished: {r['reason']}"
                  + (f" (shown as {r['shown_as']})" if self.shown else "") for _, r in t.iterrows()]
        more = len(groups) - NOTE_GROUPS
        text = head + " " + "; ".join(groups[:NOTE_GROUPS])
        return text + (f"; and {more} more: see Stale runs." if more > 0 else ".")


def judge(runs: pd.DataFrame, registry, include_stale: bool) -> tuple:
    """(runs to analyse, Staleness). runs: every run, with results_versions ('' when not stored).
    The runs to analyse are the current ones, or with include_stale every run, a stale one under
    its label; each gets columns `stale` (bool) and `stale_reason`."""
    runs = runs.copy()
    runs["stale"] = False
    runs["stale_reason"] = ""
    if not judgeable(registry):
        why = ("no harness to ask for its results versions (make_report.py --harness BIN, $DSB_HARNESS "
               "or build/bin/harness)" if registry is None else
               f"`harness list` of {registry.source} lists no results versions")
        return runs, Staleness(judged=False, why_not=why)
    runs["stale_reason"] = [reason(registry, e, o, v) for e, o, v in
                            zip(runs["env"], runs["optimizer"], runs["results_versions"])]
    runs["stale"] = runs["stale_reason"] != ""
    stale = runs[runs["stale"]].copy()
    stale["reason"] = stale["stale_reason"]
    stale["stale_label"] = [label(o, v) for o, v in zip(stale["optimizer"], stale["results_versions"])]
    info = Staleness(judged=True, source=registry.source, shown=include_stale, runs=stale.reset_index(drop=True))
    if not include_stale:
        return runs[~runs["stale"]].reset_index(drop=True), info
    runs.loc[runs["stale"], "optimizer"] = stale["stale_label"].to_numpy()
    return runs, info
