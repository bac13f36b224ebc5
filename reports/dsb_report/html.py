"""index.html: a self-contained page (relative links, images as files, no JavaScript, no network)."""
from __future__ import annotations

from html import escape

from . import captions, metric_counts, renders
from .claim_runs import CLAIMS_SEEDS
from .registry import base_env
from . import gradient_quality as gq
from .tables import final_md_rows, fmt, mark, overview_text, rank_md_rows

CSS = """
body { font-family: sans-serif; max-width: 1250px; margin: 1.5em auto; padding: 0 1em;
       color: #222; line-height: 1.4; }
h1 { font-size: 1.6em; } h2 { border-bottom: 1px solid #ccc; margin-top: 2em; }
table { border-collapse: collapse; margin: 0.6em 0; font-size: 0.9em; }
th, td { border: 1px solid #ccc; padding: 2px 7px; text-align: left; vertical-align: top; }
th { background: #f0f0f0; } td.num { text-align: right; font-variant-numeric: tabular-nums; }
tr.best td { background: #e6f4e6; } tr.tie td { background: #f3f9f3; }
tr.bad td { background: #fdecea; }
figure { margin: 1em 0; } figure img { max-width: 100%; border: 1px solid #ddd; }
figcaption { font-size: 0.9em; color: #444; max-width: 900px; }
.note { background: #fff8e1; border-left: 4px solid #f0c000; padding: 0.4em 0.8em; }
code { background: #f4f4f4; padding: 0 3px; }
table.overview td.cell { text-align: center; min-width: 4em; }
table.overview td.win { font-weight: bold; outline: 2px solid #1a7f37; outline-offset: -2px; }
table.overview td.tie { font-weight: bold; }
table.overview small { display: block; font-weight: normal; color: #555; }
.gallery { display: flex; flex-wrap: wrap; gap: 0.6em; }
.gallery figure { flex: 0 1 32%; margin: 0; } .gallery figcaption { font-size: 0.8em; }
"""


def table(headers: list, rows: list, row_classes: list | None = None, numeric: set | None = None) -> str:
    numeric = numeric or set()
    out = ["<table>", "<tr>" + "".join(f"<th>{escape(str(h))}</th>" for h in headers) + "</tr>"]
    for k, r in enumerate(rows):
        cls = f' class="{row_classes[k]}"' if row_classes and row_classes[k] else ""
        cells = "".join(
            f'<td class="num">{escape(str(c))}</td>' if i in numeric else f"<td>{escape(str(c))}</td>"
            for i, c in enumerate(r))
        out.append(f"<tr{cls}>{cells}</tr>")
    out.append("</table>")
    return "\n".join(out)


def figure(png: str, alt: str, caption: str) -> str:
    return (f'<figure><img src="{escape(png)}" alt="{escape(alt)}">'
            f"<figcaption>{escape(caption)}</figcaption></figure>")


def link(path: str, text: str | None = None) -> str:
    return f'<a href="{escape(path)}">{escape(text or path)}</a>'


def _df_rows(df, cols):
    return [[fmt(v) if isinstance(v, float) else ("" if v is None else v) for v in r]
            for r in df[cols].itertuples(index=False, name=None)]


def _provenance(ctx) -> str:
    rows = [[k, v] for k, v in ctx["provenance"]]
    return "<h2 id=\"provenance\">Provenance</h2>\n" + table(["item", "value"], rows)


def claim_counts(c) -> str:
    """'env missing 1, holds 5, runs missing 3': rows per verdict, 'runs missing: k of n done'
    counted as 'runs missing'."""
    states = c["verdict"].str.split(":").str[0]
    return ", ".join(f"{v} {n}" for v, n in states.value_counts().sort_index().items())


def claim_row_classes(c) -> list:
    return ["best" if v == "holds" else "bad" if v == "does not hold" else "" for v in c["verdict"]]


def settle_text(r) -> str:
    """The command that settles an unsettled row, '—' where none can."""
    return r["settle"] or ("—" if r["verdict"] in ("holds", "does not hold") else "none")


def _env_budget(r) -> str:
    return f"{r['env']} ({r['budget']})" if r["budget"] != "" else r["env"]


def _claims_compact(ctx) -> str:
    """The verdicts, one line per claim and env, at the top of the page (the details further down)."""
    c = ctx["claims"]
    rows = [[r["id"], _env_budget(r), r["verdict"], fmt(r["p_claim"], 3), fmt(r["a12_claim"], 2),
             settle_text(r)] for _, r in c.iterrows()]
    return ('<h2 id="claims">The paper\'s claims</h2>\n'
            f"<p>{escape(claim_counts(c) or 'No claims.')}: each qualitative claim of Antonova et al. "
            "(CoRL 2022) tested on the final best losses over seeds (what the paper says, the test "
            f"and why: {link('#claims-detail', 'the claims in detail')}; {link('claims.csv')}). "
            f"{escape(captions.CLAIMS_SETTLE.format(seeds=CLAIMS_SEEDS))}</p>\n" +
            table(["claim", "env (budget)", "verdict", "p (Holm)", "A12", "to settle, run"], rows,
                  claim_row_classes(c), numeric={3, 4}))


def _claims(ctx) -> str:
    c = ctx["claims"]
    rows = [[r["id"], _env_budget(r), f"{r['statement']} ({r['source']})", r["test"], r["n"],
             fmt(r["p_claim"], 3), fmt(r["a12_claim"], 2), r["verdict"], r["reason"],
             settle_text(r)] for _, r in c.iterrows()]
    cls = claim_row_classes(c)
    counts = claim_counts(c)
    return ('<h2 id="claims-detail">The paper\'s claims in detail</h2>\n<p>' +
            escape(captions.CLAIMS) + "</p>\n"
            f"<p>{escape(counts or 'No claims.')} ({link('claims.csv')}; every comparison: "
            f"{link('claims_comparisons.csv')})</p>\n" +
            table(["claim", "env (budget)", "the paper says", "tested as", "seeds", "p (Holm)", "A12",
                   "verdict", "why", "to settle, run"], rows, cls, numeric={5, 6}) + _metric_counts(ctx))


def _metric_counts(ctx) -> str:
    """Per optimizer, the seeds whose metric at their best episode reaches a metric claim's
    threshold (the cube over the rim), every optimizer with a done run of the env."""
    t = ctx["metric_counts"]
    if t.empty:
        return ""
    headers, rows = metric_counts.wide(t)
    return ('\n<h3 id="claims-metric">Seeds that reach the metric claims\' thresholds</h3>\n<p>' +
            escape(captions.METRIC_COUNTS) + f" ({link('claims_metric_counts.csv')})</p>\n" +
            table(headers, rows))


def heat(score: float) -> str:
    """Background colour of an overview cell: green at 0 (the winner), white at 0.5, red at 1."""
    s = min(max(score, 0.0), 1.0)
    lo, mid, hi = (170, 222, 170), (255, 255, 255), (244, 170, 160)
    a, b, f = (lo, mid, s * 2) if s <= 0.5 else (mid, hi, s * 2 - 1)
    return "#" + "".join(f"{round(x + (y - x) * f):02x}" for x, y in zip(a, b))


def _overview(ctx) -> str:
    rows, opts = ctx["overview"], ctx["optimizers"]
    p = ['<h2 id="overview">Overview: final results per env and optimizer</h2>',
         "<p>" + escape(captions.OVERVIEW) + "</p>"]
    if not rows:
        p.append("<p>No done run yet.</p>")
        return "\n".join(p)
    out = ['<table class="overview">',
           "<tr><th>env (budget)</th>" + "".join(f"<th>{escape(o)}</th>" for o in opts) + "</tr>"]
    for r in rows:
        scale = "<small>log colour scale</small>" if r["log"] else ""
        tds = [f'<td><a href="#env-{escape(r["slug"])}">{escape(r["env"])}</a> ({r["budget"]})'
               f"{scale}</td>"]
        for o in opts:
            c = r["cells"][o]
            if c is None:
                tds.append('<td class="cell">—</td>')
                continue
            cls = {"best": "cell win", "≈ best": "cell tie"}.get(c["mark"], "cell")
            mk = {"best": "★ best", "≈ best": "≈ best"}.get(c["mark"], c["mark"])
            tds.append(f'<td class="{cls}" style="background:{heat(c["score"])}" '
                       f'title="median {escape(fmt(c["median"]))}, {c["n"]} seeds">'
                       f'{c["score"]:.2f}' + (f"<small>{escape(mk)}</small>" if mk else "") +
                       "</td>")
        out.append("<tr>" + "".join(tds) + "</tr>")
    out.append("</table>")
    p.append("\n".join(out))
    return "\n".join(p)


def _failures(ctx) -> str:
    rows, opts = ctx["failures"], ctx["optimizers"]
    tot_e = sum(c[0] for r in rows for c in r["cells"].values() if c)
    tot_r = sum(c[1] for r in rows for c in r["cells"].values() if c)
    p = ['<h2 id="failures">Failed episodes and failed runs</h2>',
         "<p>" + escape(captions.FAILURES) + f" In all: {tot_e} failed episode(s), {tot_r} failed "
         "run(s).</p>"]
    body = [[f"{r['env']} ({r['budget']})"] +
            ["—" if r["cells"][o] is None else f"{r['cells'][o][0]} / {r['cells'][o][1]}"
             for o in opts] for r in rows]
    cls = ["bad" if any(c and (c[0] or c[1]) for c in r["cells"].values()) else "" for r in rows]
    p.append(table(["env (budget)"] + list(opts), body, cls, numeric=set(range(1, len(opts) + 1))))
    return "\n".join(p)


def _figure_of(f) -> str:
    """A drawn chart (charts.Figure) as a <figure>."""
    return figure(f.png, f.alt, f.caption)


def _ranks_table(ctx) -> str:
    h, rows = rank_md_rows(ctx["mean_ranks"])
    return (f"<p>Mean rank at each episode count ({link('ranks.csv')}; per env: "
            f"{link('ranks_by_env.csv')}):</p>" + table(h, rows, numeric=set(range(1, len(h)))))


def _targets_table(ctx) -> str:
    t = ctx["targets"]
    trow = [[r["env"], str(r["budget"]), fmt(r["f_star"], 8), fmt(r["f0"], 6)] +
            [fmt(r[f"target_1e-{k}"], 8) for k in (1, 2, 3, 4, 5)] for _, r in t.iterrows()]
    return (f"<p>Targets per env ({link('ecdf.csv')} holds the curves, "
            f"{link('ecdf_targets.csv')} these targets):</p>" +
            table(["env", "budget", "f*", "f0", "k=1", "k=2", "k=3", "k=4", "k=5"], trow,
                  numeric=set(range(1, 9))))


# the table under an "Across envs" chart, by the chart's name (a chart without one stands alone)
TABLE_UNDER = {"ranks": _ranks_table, "ecdf": _targets_table}


def _across(ctx) -> str:
    p = ['<h2 id="across">Across envs</h2>']
    for f in ctx["across_figures"]:
        p.append(_figure_of(f))
        if f.name in TABLE_UNDER:
            p.append(TABLE_UNDER[f.name](ctx))
    return "\n".join(p)


def _panel(ctx, item) -> str:
    pn, t = item["panel"], item["table"]
    p = [f'<h3 id="env-{escape(pn.slug)}">{escape(pn.env)} (budget {pn.budget})</h3>']
    p += [_figure_of(f) for f in item["figures"]]
    p.append(renders.figure(ctx, pn.env))
    h, rows = final_md_rows(t)
    cls = ["best" if r["is_best"] else "tie" if mark(r) == "≈ best" else
           ("bad" if r["n_seeds"] == 0 else "") for _, r in t.iterrows()]
    p.append(f"<p>Final best loss at {pn.budget} episodes over seeds ({link(item['final_csv'])}):"
             "</p>" + table(h, rows, cls, numeric=set(range(1, 10))))
    return "\n".join(p)


def _significance(ctx) -> str:
    s = ctx["significance"]
    rows = [[r["env"], r["optimizer"], fmt(r["p_raw"], 4), fmt(r["p_holm"], 4), r["mark"]]
            for _, r in s.iterrows()]
    return ('<h2 id="significance">Significance</h2>\n<p>' +
            escape(captions.SIGNIFICANCE.format(minp=ctx["minp_text"])) + "</p>\n"
            f"<p>{link('significance.csv')}</p>\n" +
            table(["env", "optimizer", "p raw", "p Holm", "vs best"], rows, numeric={2, 3}))


def _gradient_quality(ctx) -> str:
    df = ctx["gradient_quality"]
    p = ['<h2 id="gradient-quality">Gradient quality</h2>']
    if df is None:
        p.append(f"<p>No gradient survey: <code>{escape(ctx['gradient_quality_path'])}</code> does "
                 "not exist (make it with <code>scripts/gradient-quality.sh BUILD_DIR FILE</code>, "
                 "or pass <code>--gradient-quality FILE</code>).</p>")
        return "\n".join(p)
    p.append("<p>" + escape(captions.GRADIENT_QUALITY.format(settings=gq.settings(df))) + "</p>")
    p.append(f"<p>{len(df)} envs ({link('gradient_quality.csv')}, a copy of "
             f"<code>{escape(ctx['gradient_quality_path'])}</code>):</p>")
    p.append(table(gq.HEADERS, gq.rows(df), gq.row_classes(df), numeric=set(range(1, 10))))
    return "\n".join(p)


def _landscapes(ctx) -> str:
    ls = ctx["landscapes"]
    p = ['<h2 id="landscapes">Landscapes</h2>']
    if ctx["landscape_dir"] is None:
        p.append("<p>No landscape directory given (<code>--landscapes DIR</code>; "
                 "<code>scripts/landscape-gallery.sh DIR</code> makes one for every env).</p>")
    elif not ls and not ctx["landscape_errors"]:
        p.append(f"<p>No <code>&lt;env&gt;_&lt;i&gt;_&lt;j&gt;.csv</code> files in "
                 f"<code>{escape(ctx['landscape_dir'])}</code>.</p>")
    if ctx["landscape_dir"] is not None:
        p.append(f"<p>All of them side by side, with the gradient quality of each env: "
                 f"{link('gallery.html', 'the landscape gallery')}.</p>")
    for it in ls:
        p.append(f"<h3>{escape(it['env'])}, dims {it['i']} and {it['j']}</h3>")
        p.append(figure(it["png"], f"landscape {it['env']}",
                        captions.LANDSCAPE + f" Source: {it['source']} ({it['desc']})."))
    for e in ctx["landscape_errors"]:
        p.append(f'<p class="note">Skipped: {escape(e)}</p>')
    return "\n".join(p)


def gallery_groups(landscapes: list, gq_df) -> list:
    """(env, [landscape items]) in the order of the gradient survey's rows (harness list's order),
    then the other envs by name."""
    groups = {}
    for it in landscapes:
        groups.setdefault(base_env(it["env"]), []).append(it)
    order = [e for e in (list(gq_df["env"]) if gq_df is not None else []) if e in groups]
    order += sorted(e for e in groups if e not in order)
    return [(e, groups[e]) for e in order]


def render_gallery(ctx) -> str:
    """gallery.html: every landscape of --landscapes, grouped by env and side by side, under the
    gradient quality table (each env's survey row repeated above its slices)."""
    df = ctx["gradient_quality"]
    parts = ["<!DOCTYPE html>", '<html lang="en"><head><meta charset="utf-8">',
             "<title>diffsim-bench landscape gallery</title>",
             f"<style>{CSS}</style></head><body>",
             "<h1>Landscape gallery</h1>",
             f"<p>{escape(captions.GALLERY)} Back to the {link('index.html', 'report')}.</p>"]
    if df is None:
        parts.append(f"<p>No gradient survey: <code>{escape(ctx['gradient_quality_path'])}</code> "
                     "does not exist.</p>")
    else:
        parts.append('<h2 id="gradient-quality">Gradient quality</h2>')
        parts.append("<p>" + escape(captions.GRADIENT_QUALITY.format(settings=gq.settings(df))) +
                     "</p>")
        parts.append(table(gq.HEADERS, gq.rows(df), gq.row_classes(df), numeric=set(range(1, 10))))
    by_env = {} if df is None else {e: k for k, e in enumerate(df["env"])}
    if not ctx["landscapes"]:
        parts.append("<p>No landscapes in <code>" + escape(str(ctx["landscape_dir"])) + "</code>.</p>")
    for env, items in gallery_groups(ctx["landscapes"], df):
        parts.append(f'<h2 id="gallery-{escape(env)}">{escape(env)}</h2>')
        if env in by_env:
            k = by_env[env]
            parts.append(table(gq.HEADERS, [gq.rows(df)[k]], [gq.row_classes(df)[k]],
                               numeric=set(range(1, 10))))
        else:
            parts.append("<p>Not in the gradient survey.</p>")
        figs = [figure(it["png"], f"landscape {it['env']} dims {it['i']} and {it['j']}",
                       f"{it['env']}, dims {it['i']} and {it['j']}: {it['desc']} "
                       f"({it['source']}).") for it in items]
        parts.append('<div class="gallery">' + "".join(figs) + "</div>")
    for e in ctx["landscape_errors"]:
        parts.append(f'<p class="note">Skipped: {escape(e)}</p>')
    parts.append("</body></html>")
    return "\n".join(parts) + "\n"


def _problems(ctx) -> str:
    p = ['<h2 id="missing">Missing runs</h2>',
         "<p>" + escape(captions.MISSING.format(max_seed=ctx["max_seed"])) + "</p>"]
    m = ctx["missing"]
    if m.empty:
        p.append("<p>None: every expected run is done.</p>")
    else:
        p.append(f"<p><b>{len(m)} expected run(s) without a 'done' run</b> "
                 f"({link('missing.csv')}):</p>")
        p.append(table(["env", "optimizer", "seed", "budget", "reason", "error"],
                       _df_rows(m, ["env", "optimizer", "seed", "budget", "reason", "error"])))
    p.append('<h2 id="failed">Failed runs</h2>')
    f = ctx["failed"]
    p.append("<p>None.</p>" if f.empty else
             f"<p>{len(f)} failed run(s), excluded from every statistic:</p>" +
             table(["env", "optimizer", "seed", "budget", "run_id", "error", "started", "finished",
                    "host"], _df_rows(f, list(f.columns)), ["bad"] * len(f)))
    p.append('<h2 id="incomplete">Incomplete runs (status running)</h2>')
    r = ctx["running"]
    p.append("<p>None.</p>" if r.empty else
             f"<p>{len(r)} run(s) still marked 'running' (in progress, or a killed harness): "
             "excluded from every statistic.</p>" +
             table(["env", "optimizer", "seed", "budget", "run_id", "error", "started", "finished",
                    "host"], _df_rows(r, list(r.columns))))
    ig = ctx["ignored"]
    if not ig.empty:
        p.append('<h2 id="variants">Ignored config variants</h2>')
        p.append("<p>These 'done' runs belong to a different env or optimizer config than the "
                 "variant analysed for the same (env, optimizer, budget) (the one with the most done "
                 "runs); they are not mixed into the statistics.</p>")
        p.append(table(["env", "optimizer", "seed", "budget", "run_id", "env config",
                        "optimizer config", "best loss"],
                       _df_rows(ig, ["env", "optimizer", "seed", "budget", "run_id",
                                     "env_config_hash", "opt_config_hash", "best_loss"])))
    st = ctx.get("stale")
    if st is not None and not st.empty:
        p.append('<h2 id="stale">Stale runs</h2>')
        p.append("<p>" + escape(captions.STALE_SHOWN if ctx["stale_shown"] else captions.STALE_LEFT_OUT) +
                 f" ({link('stale_runs.csv')})</p>")
        p.append(table(["env", "optimizer", "stored results versions", "why stale", "done", "unfinished",
                        "shown as"],
                       [[r["env"], r["optimizer"], r["results_versions"] or "(none)", r["reason"], r["done"],
                         r["unfinished"], r["shown_as"] or "—"] for _, r in st.iterrows()],
                       numeric={4, 5}))
    return "\n".join(p)


def render(ctx) -> str:
    toc = [("claims", "The paper's claims"), ("overview", "Overview: final results"),
           ("failures", "Failed episodes and failed runs"),
           ("claims-detail", "The paper's claims in detail"),
           ("across", "Across envs: ranks and data profile")]
    toc += [(f"env-{it['panel'].slug}", f"{it['panel'].env} (budget {it['panel'].budget})")
            for it in ctx["panels"]]
    toc += [("significance", "Significance"), ("gradient-quality", "Gradient quality"),
            ("landscapes", "Landscapes"),
            ("missing", f"Missing runs ({len(ctx['missing'])})"),
            ("failed", f"Failed runs ({len(ctx['failed'])})"),
            ("incomplete", f"Incomplete runs ({len(ctx['running'])})")]
    if ctx.get("stale") is not None and not ctx["stale"].empty:
        toc.append(("stale", f"Stale runs ({int(ctx['stale']['done'].sum() + ctx['stale']['unfinished'].sum())})"))
    toc += [("provenance", "Provenance"), ("files", "Files")]
    parts = ["<!DOCTYPE html>", '<html lang="en"><head><meta charset="utf-8">',
             "<title>diffsim-bench report</title>", f"<style>{CSS}</style></head><body>",
             "<h1>diffsim-bench comparison report</h1>", f"<p>{escape(ctx['headline'])}</p>"]
    # the answer: the claims' verdicts, then the overview at the page's full width (every
    # optimizer's column in view at 1,400 px: tests/report_screenshot_test.py measures it)
    parts.append(_claims_compact(ctx))
    parts.append(_overview(ctx))
    parts.append(_failures(ctx))
    for note in ctx["notes"]:
        parts.append(f'<p class="note">{escape(note)}</p>')
    parts.append('<h2 id="contents">Contents</h2>')
    parts.append("<ul>" + "".join(f'<li><a href="#{escape(a)}">{escape(t)}</a></li>'
                                  for a, t in toc) + "</ul>")
    parts.append(_claims(ctx))
    parts.append(_across(ctx))
    parts.append('<h2 id="envs">Per env</h2>')
    parts += [_panel(ctx, it) for it in ctx["panels"]]
    parts.append(_significance(ctx))
    parts.append(_gradient_quality(ctx))
    parts.append(_landscapes(ctx))
    parts.append(_problems(ctx))
    parts.append(_provenance(ctx))
    parts.append('<h2 id="files">Files</h2><ul>' +
                 "".join(f"<li>{link(f)}</li>" for f in ctx["files"]) + "</ul>")
    parts.append("</body></html>")
    return "\n".join(parts) + "\n"


__all__ = ["render", "mark"]
