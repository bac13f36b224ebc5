#!/usr/bin/env python3
"""Summarises a knob-study database (scripts/knob-study.sh): one row per env and optimizer variant.

A variant is named by --variants (CSV opt_config_hash,variant as knob-study.sh writes it: "boleap"
is the default, "boleap.sigma0=0.3" a variant), else by what its resolved config changes from the
optimizer's centre config (the one every other config of that optimizer differs from in exactly
one field); the reference optimizers keep their names. Columns: env, optimizer, variant, budget,
seeds, median, q25, q75 of the runs' final best loss (runs.best_loss; none finite = inf), ratio
(median / the default variant's median), p (two-sided Mann-Whitney U against the default
variant's runs), wins (seeds where the variant ends below the default on the same seed index);
with --reference OPT, p_ref (the same test against OPT's default runs on that env); for boleap, the
medians over its runs of its diagnostics: leaps, descents, descent steps and stale stops per run.

    /usr/bin/python3 scripts/knob_study_table.py knob-study.sqlite --out knob_study.csv [--markdown]
    /usr/bin/python3 scripts/knob_study_table.py OUTDIR/parts/*.csv --out knob_study.csv
"""
import argparse
import json
import math
import sqlite3
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "reports"))
from dsb_report import read_only_db  # noqa: E402

try:
    import pandas as pd
    from scipy.stats import mannwhitneyu
except ImportError as e:  # pragma: no cover
    sys.stderr.write(f"knob_study_table: {sys.executable} cannot import {e.name}; use /usr/bin/python3\n")
    sys.exit(2)


def flatten(obj, prefix=""):
    """{"adam": {"lr": 0.1}} -> {"adam.lr": 0.1}"""
    out = {}
    for k, v in obj.items():
        key = f"{prefix}{k}"
        if isinstance(v, dict):
            out.update(flatten(v, key + "."))
        else:
            out[key] = v
    return out


def short(key):
    return key.split(".")[-1] if key.startswith("adam.") else key


def variant_names(configs):
    """hash -> name, for the configs of one optimizer"""
    flat = {h: flatten(c) for h, c in configs.items()}
    if len(flat) == 1:
        return {h: "default" for h in flat}

    def diff(a, b):
        return [k for k in sorted(set(a) | set(b)) if a.get(k) != b.get(k)]

    centre = None
    for h, c in flat.items():
        if all(len(diff(c, o)) == 1 for g, o in flat.items() if g != h):
            centre = h
            break
    if centre is None:
        return {h: h[:8] for h in flat}
    names = {}
    for h, c in flat.items():
        if h == centre:
            names[h] = "default"
        else:
            names[h] = ", ".join(f"{short(k)}={c[k]}" for k in diff(flat[centre], c))
    return names


def read_runs(path):
    """a study database's done runs, or those of a part's CSV (scripts/lib/variant-study.sh)"""
    columns = ["env", "optimizer", "seed", "budget", "best_loss", "opt_config_hash", "config", "diagnostics"]
    if path.endswith(".csv"):
        runs = pd.read_csv(path, dtype={"opt_config_hash": str, "config": str, "diagnostics": str},
                           keep_default_na=False, na_values={"best_loss": [""]}, float_precision="round_trip")
        return runs[runs.status == "done"][columns]
    con = read_only_db.connect(path)
    runs = pd.read_sql_query(
        "SELECT r.env, r.optimizer, r.seed, r.budget, r.best_loss, r.opt_config_hash, c.json AS config, "
        "r.diagnostics "
        "FROM runs r JOIN configs c ON c.hash = r.opt_config_hash WHERE r.status = 'done'", con)
    con.close()
    return runs


def load(paths, labels=None):
    runs = pd.concat([read_runs(p) for p in paths], ignore_index=True)
    runs["best_loss"] = pd.to_numeric(runs["best_loss"]).fillna(math.inf)
    names = {}
    for opt, g in runs.groupby("optimizer"):
        cfgs = {h: json.loads(c) for h, c in zip(g["opt_config_hash"], g["config"])}
        for h, n in variant_names(cfgs).items():
            names[(opt, h)] = n
    if labels:
        # "boleap" -> default, "boleap.sigma0=0.3" -> sigma0=0.3
        for (o, h) in names:
            if h in labels:
                names[(o, h)] = labels[h].split(".", 1)[1] if "." in labels[h] else "default"
    runs["variant"] = [names[(o, h)] for o, h in zip(runs["optimizer"], runs["opt_config_hash"])]
    return runs


def boleap_diagnostics(text):
    """leaps, descents, descent steps (total) and stale stops of one boleap run's diagnostics"""
    d = json.loads(text or "{}").get("optimizer", {})
    steps = sum(leap.get("descent_steps", 0) for leap in d.get("leap_list", []))
    return {"leaps": d.get("leaps", math.nan), "descents": d.get("descents", math.nan),
            "descent_steps": steps if not d.get("leap_list_truncated") else math.nan,
            "stale_stops": d.get("stale_stops", math.nan)}


def summarise(runs, reference=None):
    rows = []
    for (env, opt, variant, budget), g in runs.groupby(["env", "optimizer", "variant", "budget"], sort=True):
        base = runs[(runs.env == env) & (runs.optimizer == opt) & (runs.variant == "default") &
                    (runs.budget == budget)]
        loss = g.set_index("seed")["best_loss"]
        row = {"env": env, "optimizer": opt, "variant": variant, "budget": budget, "seeds": len(g),
               "median": loss.median(), "q25": loss.quantile(0.25), "q75": loss.quantile(0.75),
               "ratio": math.nan, "p": math.nan, "wins": ""}
        if variant != "default" and len(base) > 0:
            b = base.set_index("seed")["best_loss"]
            row["ratio"] = loss.median() / b.median() if b.median() > 0 else math.nan
            row["p"] = mannwhitneyu(loss, b, alternative="two-sided").pvalue
            common = loss.index.intersection(b.index)
            row["wins"] = f"{int((loss[common] < b[common]).sum())}/{len(common)}"
        if reference:
            ref = runs[(runs.env == env) & (runs.optimizer == reference) & (runs.variant == "default") &
                       (runs.budget == budget)]
            row["p_ref"] = (mannwhitneyu(loss, ref["best_loss"], alternative="two-sided").pvalue
                            if len(ref) > 0 and not (opt == reference and variant == "default") else math.nan)
        if opt == "boleap":
            diag = pd.DataFrame([boleap_diagnostics(t) for t in g["diagnostics"]])
            for k in diag.columns:
                row[k] = diag[k].median()
        rows.append(row)
    return pd.DataFrame(rows)


def markdown(table, reference=None):
    def num(v, fmt):
        return "" if v is None or (isinstance(v, float) and math.isnan(v)) else format(v, fmt)

    diag = "leaps" in table.columns
    head = "| env | optimizer | variant | seeds | median | q25 - q75 | / default | p | wins |"
    if reference:
        head += f" p vs {reference} |"
    if diag:
        head += " leaps | descents | descent steps | stale stops |"
    lines = [head, "|" + "---|" * (head.count("|") - 1)]
    for r in table.to_dict("records"):
        line = (f"| {r['env']} | {r['optimizer']} | {r['variant']} | {r['seeds']} | {r['median']:.4g} | "
                f"{r['q25']:.3g} - {r['q75']:.3g} | {num(r['ratio'], '.2f')} | {num(r['p'], '.3f')} | {r['wins']} |")
        if reference:
            line += f" {num(r.get('p_ref'), '.3f')} |"
        if diag:
            line += "".join(f" {num(r.get(k), '.0f')} |" for k in ("leaps", "descents", "descent_steps", "stale_stops"))
        lines.append(line)
    return "\n".join(lines)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("inputs", nargs="+", metavar="DB_OR_CSV",
                    help="a study database, or the parts' CSVs (variant-study.sh)")
    ap.add_argument("--out", help="CSV to write")
    ap.add_argument("--variants", help="CSV opt_config_hash,variant naming the configs")
    ap.add_argument("--reference", help="optimizer whose default runs each row is also tested against (p_ref)")
    ap.add_argument("--markdown", action="store_true", help="also print a Markdown table")
    a = ap.parse_args()
    try:
        labels = None
        if a.variants:
            labels = dict(pd.read_csv(a.variants, dtype=str)[["opt_config_hash", "variant"]].values)
        runs = load(a.inputs, labels)
    except (sqlite3.Error, pd.errors.DatabaseError, OSError, KeyError, AttributeError, ValueError) as e:
        sys.stderr.write(f"knob_study_table: cannot read '{' '.join(a.inputs)}': {e}\n")
        sys.exit(2)
    table = summarise(runs, a.reference)
    if a.out:
        table.to_csv(a.out, index=False, float_format="%.17g")
    if a.markdown or not a.out:
        print(markdown(table, a.reference))


if __name__ == "__main__":
    main()
