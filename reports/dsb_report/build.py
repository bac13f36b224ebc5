"""Compute everything once and write the report folder; returns the names of the files written."""
from __future__ import annotations

import os
import platform
import shutil

import matplotlib
import numpy as np
import pandas as pd
import scipy

from . import (captions, charts, claims, grid, html, landscape, metric_counts, optima, plots, renders, stats, style,
               summary, with_archive)
from .data import current_view, main_panels, slugify
from .tables import FINAL_COLUMNS, SIGNIFICANCE_COLUMNS, failures, mark, overview, write_csv


def _scale_text(ys) -> str:
    if ys.regret:
        return captions.SCALE_REGRET.format(fstar=f"{ys.fstar:.10g}", floor=f"{ys.floor:.1g}")
    if ys.shifted:
        return captions.SCALE_SHIFTED.format(fstar=f"{ys.fstar:.8g}", delta=f"{ys.delta:.1g}")
    return captions.SCALE_LOG if ys.log else captions.SCALE_LINEAR


def _counts(series: pd.Series) -> str:
    c = series.fillna("(none)").astype(str).value_counts().sort_index()
    return ", ".join(f"{k} ({v} runs)" for k, v in c.items()) or "—"


def _ranges(values) -> str:
    v = sorted(int(x) for x in set(values))
    return ", ".join(map(str, v)) if v else "—"


def _minp_text(tables: list) -> str:
    ns = sorted({int(n) for t in tables for n in t["n_seeds"] if n > 0})
    if not ns:
        return ""
    m = max((int((t["n_seeds"] > 0).sum()) - 1 for t in tables), default=0)
    parts = [f"with {n} seeds per optimizer the smallest exact one-sided p-value is "
             f"1/C({2 * n},{n}) = {stats.min_exact_p(n, n, sides=1):.2g}" for n in ns]
    text = "Small samples: " + "; ".join(parts) + "."
    if m > 0:
        low = min(1.0, m * stats.min_exact_p(max(ns), max(ns), sides=1))
        text += (f" With up to {m} comparisons per env, Holm multiplies the smallest p by {m}: the "
                 f"smallest corrected p is then {low:.2g}")
        text += ", so no difference can reach α = 0.05: more seeds are needed." if low >= 0.05 \
            else "."
    text += (" With tied values scipy uses the normal approximation, whose p can be slightly "
             "smaller.")
    one_run = sorted({f"{r['optimizer']} on {r['env']}" for t in tables for _, r in t.iterrows()
                      if bool(r.get("seed_free", False))})
    if one_run:
        text += (" " + captions.ONE_RUN + " Here: " + ", ".join(one_run) + ".")
    return text


def _registry_text(registry) -> str:
    if registry is None:
        return ("none: no harness to ask (make_report.py --harness BIN, $DSB_HARNESS or "
                "build/bin/harness), so a claim's env without runs may not exist")
    return (f"`harness list` of {registry.source}: {len(registry.envs)} envs, "
            f"{len(registry.optimizers)} optimizers")


def _provenance(data, build_type, made, stored_episodes, registry=None) -> list:
    r = data.runs
    status = r["status"].value_counts()
    versions = (f"pandas {pd.__version__}, matplotlib {matplotlib.__version__}, "
                f"scipy {scipy.__version__}, Python {platform.python_version()}")
    return [
        ["database", os.path.abspath(data.db_path)],
        ["database size", f"{data.db_size} bytes ({data.db_size / 2 ** 20:.2f} MiB)"],
        ["schema_version", data.meta.get("schema_version", "(absent)")],
        ["harness version(s)", _counts(r["harness_version"])],
        ["git sha(s)", _counts(r["git_sha"])],
        ["build type", build_type],
        ["env registry", _registry_text(registry)],
        ["archive", "none (make_report.py --with DIR puts the published runs beside these)" if data.archive is None
         else f"{os.path.abspath(data.archive.folder)}: {data.archive.files} files, {data.archive.runs} runs"],
        ["host(s)", _counts(r["host"])],
        ["envs", f"{r['env'].nunique()}: " + ", ".join(sorted(r["env"].unique()))],
        ["optimizers", f"{len(data.optimizers)}: " + ", ".join(data.optimizers)],
        ["seeds present", _ranges(r["seed"])],
        ["budgets present", _ranges(r["budget"])],
        ["runs by status", ", ".join(f"{s} {int(status.get(s, 0))}"
                                     for s in ("done", "failed", "running")) +
         f" (total {len(r)})"],
        ["episodes analysed", str(stored_episodes)],
        ["report made", made],
        ["generator", f"reports/make_report.py ({versions})"],
        ["statistics", "final = runs.best_loss of done runs (NULL = +inf); 95% CI: Student t; "
                       "tests: Mann-Whitney U one-sided (worse than the env's best?), Holm, α = 0.05; ranks: "
                       "ties averaged; quantiles: linear interpolation; no random numbers"],
    ]


def build(data, out: str, landscape_dir, build_type: str, made: str, claim_list=(),
          gradient_quality=None, gradient_quality_path: str = "", render_dir=None,
          registry=None) -> list:
    charts.check(plots.CHARTS)
    style.setup()
    pal = style.palette(data.optimizers)
    marks = style.markers(data.optimizers)
    known = optima.load()
    written = []

    def path(name):
        written.append(name)
        return os.path.join(out, name)

    items, tables = [], []
    for pn in data.panels:
        fs = optima.f_star(pn.env, known)
        ys = style.yscale_for(pn.best, fs)
        t = stats.final_table(pn, data.runs)
        t["f_star"] = np.nan if fs is None else fs
        t["regret_median"] = t["median"] - fs if fs is not None else np.nan
        it = dict(panel=pn, table=t, scale_text=_scale_text(ys), f_star=fs,
                  final_csv=f"final_{pn.slug}.csv")
        it["figures"] = charts.draw(plots.CHARTS, charts.PER_ENV, charts.EnvView(pn, t, pal, ys, marks),
                                    path, slug=pn.slug, env=pn.env, scale=it["scale_text"])
        write_csv(t, path(it["final_csv"]), FINAL_COLUMNS)
        items.append(it)
        tables.append(t)

    mp = main_panels(data)
    # the claims judge the runs of this harness's results versions only, shown stale runs or not
    claim_panels, current_runs = current_view(data)
    verdicts, comparisons = claims.evaluate(list(claim_list), claim_panels, current_runs, registry)
    write_csv(verdicts, path("claims.csv"))
    write_csv(comparisons, path("claims_comparisons.csv"))
    reached = metric_counts.table(list(claim_list), claim_panels)
    if len(reached):
        write_csv(reached, path("claims_metric_counts.csv"))
    by_env = stats.ranks(mp)
    mr = stats.mean_ranks(by_env)
    write_csv(mr, path("ranks.csv"))
    write_csv(by_env, path("ranks_by_env.csv"))
    ecdf_table, tinfo = stats.ecdf(mp, data.optimizers)
    write_csv(ecdf_table, path("ecdf.csv"))
    write_csv(tinfo, path("ecdf_targets.csv"))
    across = charts.draw(plots.CHARTS, charts.ACROSS, charts.AcrossView(mr, ecdf_table, pal, len(mp)), path)

    sig = pd.concat(tables, ignore_index=True) if tables else pd.DataFrame(columns=FINAL_COLUMNS)
    sig["mark"] = [mark(r) for _, r in sig.iterrows()] if len(sig) else []
    best_of = {(r["env"], r["budget"]): r["optimizer"] for _, r in sig.iterrows() if r["is_best"]}
    sig["best_optimizer"] = [best_of.get((r["env"], r["budget"]), "") for _, r in sig.iterrows()]
    write_csv(sig, path("significance.csv"),
              SIGNIFICANCE_COLUMNS + ["budget", "is_best", "best_optimizer", "n_seeds", "seed_free", "mark"])

    if gradient_quality is not None:  # the survey's file as it is
        shutil.copyfile(gradient_quality_path, path("gradient_quality.csv"))

    missing = grid.missing_runs(current_runs)     # a stale run is no run to make
    stale_table = data.stale.table()
    if len(stale_table):
        write_csv(stale_table, path("stale_runs.csv"))
    write_csv(missing, path("missing.csv"))
    failed = grid.runs_with_status(data.runs, "failed")
    running = grid.runs_with_status(data.runs, "running")

    lands, lerrors = [], []
    if landscape_dir is not None:
        for env, i, j, src in landscape.find(landscape_dir):
            name = f"landscape_{slugify(env)}_{i}_{j}.png"
            try:
                desc = landscape.plot(env, i, j, src, os.path.join(out, name))
            except Exception as e:  # a malformed file is reported, not fatal
                lerrors.append(f"{os.path.basename(src)}: {e}")
                continue
            written.append(name)
            lands.append(dict(env=env, i=i, j=j, png=name, source=os.path.basename(src), desc=desc))

    rends = renders.collect(current_runs, render_dir, out, written)   # as render --best-of picks

    notes = [n for n in [data.archive.note() if data.archive else "", data.stale.note(len(data.runs))] if n]
    if data.archive is not None:
        write_csv(with_archive.sources(data.runs), path("sources.csv"))
    if not data.panels:
        notes.append("No run of this harness's results versions is done: there is nothing to compare yet."
                     if data.stale.count and not data.stale.shown else
                     "No run is done: there is nothing to compare yet.")
    if len(missing):
        notes.append(f"{len(missing)} expected run(s) are not done; see Missing runs.")
    if len(failed):
        notes.append(f"{len(failed)} run(s) failed; see Failed runs.")
    if len(running):
        notes.append(f"{len(running)} run(s) are still marked running; see Incomplete runs.")
    if len(data.ignored):
        notes.append(f"{len(data.ignored)} done run(s) of other config variants are not analysed; "
                     "see Ignored config variants.")
    multi = sorted({p.env for p in data.panels} - {p.env for p in data.panels
                                                    if [q.env for q in data.panels].count(p.env) == 1})
    if multi:
        notes.append("Several budgets for " + ", ".join(multi) + ": per-env sections are per budget; "
                     "ranks and the data profile use the largest budget of each env.")

    r = data.runs
    ctx = dict(
        headline=(f"{r['env'].nunique()} envs × {len(data.optimizers)} optimizers, {len(r)} runs "
                  f"({int((r['status'] == 'done').sum())} done), seeds {_ranges(r['seed'])}, "
                  f"budget(s) {_ranges(r['budget'])}; database {os.path.basename(data.db_path)}, "
                  f"made {made}."),
        notes=notes,
        provenance=_provenance(data, build_type, made, int(sum(p.best.size for p in data.panels)),
                               registry),
        claims=verdicts, metric_counts=reached, panels=items, mean_ranks=mr, across_figures=across,
        targets=tinfo, gradient_quality=gradient_quality,
        gradient_quality_path=gradient_quality_path,
        overview=overview(items, data.optimizers),
        failures=failures(items, data.runs, data.optimizers), optimizers=data.optimizers,
        significance=sig,
        minp_text=_minp_text(tables), landscapes=lands, landscape_errors=lerrors,
        landscape_dir=landscape_dir, missing=missing, failed=failed, running=running,
        ignored=data.ignored, max_seed=int(current_runs["seed"].max()) if len(current_runs) else 0,
        renders=rends,
        stale=stale_table, stale_shown=data.stale.shown)

    with open(path("summary.md"), "w", encoding="utf-8") as f:
        f.write(summary.render(ctx))
    if landscape_dir is not None:
        with open(path("gallery.html"), "w", encoding="utf-8") as f:
            f.write(html.render_gallery(ctx))
    ctx["files"] = sorted(written)
    with open(path("index.html"), "w", encoding="utf-8") as f:
        f.write(html.render(ctx))
    return written



