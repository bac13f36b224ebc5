"""index.html: a self-contained page (relative links, images as files, no JavaScript, no network)."""
from __future__ import annotations

from html import escape

from . import captions, renders
from . import gradient_quality as gq
from .tables import final_md_rows, fmt, mark, rank_md_rows

CSS = """
body { font-family: sans-serif; max-width: 1100px; margin: 1.5em auto; padding: 0 1em;
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


def _claims(ctx) -> str:
    c = ctx["claims"]
    rows = [[r["id"], f"{r['env']} ({r['budget']})" if r["budget"] != "" else r["env"],
             f"{r['statement']} ({r['source']})", r["test"], r["n"],
             fmt(r["p_claim"], 3), fmt(r["a12_claim"], 2), r["verdict"], r["reason"]]
            for _, r in c.iterrows()]
    cls = ["best" if v == "holds" else "bad" if v == "does not hold" else "" for v in c["verdict"]]
    counts = ", ".join(f"{v} {n}" for v, n in c["verdict"].value_counts().sort_index().items())
    return ('<h2 id="claims">The paper\'s claims</h2>\n<p>' + escape(captions.CLAIMS) + "</p>\n"
            f"<p>{escape(counts or 'No claims.')} ({link('claims.csv')}; every comparison: "
            f"{link('claims_comparisons.csv')})</p>\n" +
            table(["claim", "env (budget)", "the paper says", "tested as", "seeds", "p (Holm)", "A12",
                   "verdict", "why"], rows, cls, numeric={5, 6}))


def _across(ctx) -> str:
    p = ['<h2 id="across">Across envs</h2>']
    p.append(figure(ctx["ranks_png"], "average ranks", captions.RANKS))
    h, rows = rank_md_rows(ctx["mean_ranks"])
    p.append(f"<p>Mean rank at each episode count ({link('ranks.csv')}; per env: "
             f"{link('ranks_by_env.csv')}):</p>" + table(h, rows, numeric=set(range(1, len(h)))))
    p.append(figure(ctx["ecdf_png"], "data profile", captions.ECDF))
    t = ctx["targets"]
    trow = [[r["env"], str(r["budget"]), fmt(r["f_star"], 8), fmt(r["f0"], 6)] +
            [fmt(r[f"target_1e-{k}"], 8) for k in (1, 2, 3, 4, 5)] for _, r in t.iterrows()]
    p.append(f"<p>Targets per env ({link('ecdf.csv')} holds the curves, "
             f"{link('ecdf_targets.csv')} these targets):</p>" +
             table(["env", "budget", "f*", "f0", "k=1", "k=2", "k=3", "k=4", "k=5"], trow,
                   numeric=set(range(1, 9))))
    p.append("<p>Overview: median final best loss per env and optimizer (mark versus the env's "
             "best; '—' = no done run).</p>" + table(*ctx["overview"]))
    return "\n".join(p)


def _panel(ctx, item) -> str:
    pn, t = item["panel"], item["table"]
    p = [f'<h3 id="env-{escape(pn.slug)}">{escape(pn.env)} (budget {pn.budget})</h3>']
    p.append(figure(item["curves_png"], f"curves {pn.env}",
                    captions.CURVES.format(scale=item["scale_text"])))
    p.append(figure(item["final_png"], f"final {pn.env}",
                    captions.FINALS.format(scale=item["scale_text"])))
    p.append(renders.figure(ctx, pn.env))
    h, rows = final_md_rows(t)
    cls = ["best" if r["is_best"] else "tie" if r["indistinguishable_from_best"] else
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
        p.append("<p>No landscape directory given (<code>--landscapes DIR</code>).</p>")
    elif not ls and not ctx["landscape_errors"]:
        p.append(f"<p>No <code>&lt;env&gt;_&lt;i&gt;_&lt;j&gt;.csv</code> files in "
                 f"<code>{escape(ctx['landscape_dir'])}</code>.</p>")
    for it in ls:
        p.append(f"<h3>{escape(it['env'])}, dims {it['i']} and {it['j']}</h3>")
        p.append(figure(it["png"], f"landscape {it['env']}",
                        captions.LANDSCAPE + f" Source: {it['source']} ({it['desc']})."))
    for e in ctx["landscape_errors"]:
        p.append(f'<p class="note">Skipped: {escape(e)}</p>')
    return "\n".join(p)


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
    return "\n".join(p)


def render(ctx) -> str:
    toc = [("claims", "The paper's claims"), ("provenance", "Provenance"),
           ("across", "Across envs: ranks and data profile")]
    toc += [(f"env-{it['panel'].slug}", f"{it['panel'].env} (budget {it['panel'].budget})")
            for it in ctx["panels"]]
    toc += [("significance", "Significance"), ("gradient-quality", "Gradient quality"),
            ("landscapes", "Landscapes"),
            ("missing", f"Missing runs ({len(ctx['missing'])})"),
            ("failed", f"Failed runs ({len(ctx['failed'])})"),
            ("incomplete", f"Incomplete runs ({len(ctx['running'])})"), ("files", "Files")]
    parts = ["<!DOCTYPE html>", '<html lang="en"><head><meta charset="utf-8">',
             "<title>diffsim-bench report</title>", f"<style>{CSS}</style></head><body>",
             "<h1>diffsim-bench comparison report</h1>", f"<p>{escape(ctx['headline'])}</p>"]
    for note in ctx["notes"]:
        parts.append(f'<p class="note">{escape(note)}</p>')
    parts.append("<ul>" + "".join(f'<li><a href="#{escape(a)}">{escape(t)}</a></li>'
                                  for a, t in toc) + "</ul>")
    parts.append(_claims(ctx))
    parts.append(_provenance(ctx))
    parts.append(_across(ctx))
    parts.append('<h2 id="envs">Per env</h2>')
    parts += [_panel(ctx, it) for it in ctx["panels"]]
    parts.append(_significance(ctx))
    parts.append(_gradient_quality(ctx))
    parts.append(_landscapes(ctx))
    parts.append(_problems(ctx))
    parts.append('<h2 id="files">Files</h2><ul>' +
                 "".join(f"<li>{link(f)}</li>" for f in ctx["files"]) + "</ul>")
    parts.append("</body></html>")
    return "\n".join(parts) + "\n"


__all__ = ["render", "mark"]
