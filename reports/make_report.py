#!/usr/bin/python3
"""diffsim-bench comparison report: reads a harness SQLite database (read-only) and writes a
self-contained folder with index.html, summary.md, PNG figures and CSV tables.

usage: /usr/bin/python3 reports/make_report.py --db FILE --out DIR [--landscapes DIR] [--build-type T]
                                              [--claims FILE] [--gradient-quality FILE] [--renders DIR]
                                              [--harness BIN] [--include-stale]

Needs pandas, matplotlib and scipy (Debian: python3-pandas python3-matplotlib python3-scipy, which
only Debian's /usr/bin/python3 sees). Exit codes: 0 written, 2 bad input or missing modules.
"""
from __future__ import annotations

import argparse
import datetime
import importlib
import os
import re
import stat
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
REQUIRED = ("pandas", "matplotlib", "scipy", "scipy.stats")
# the report's files that are not charts (charts.writes knows the charts' own, from plots.CHARTS)
OWN_FILES = re.compile(r"^(final_.+\.csv|landscape_.+\.png|render_.+\.png|"
                       r"gradient_quality\.csv|gallery\.html|stale_runs\.csv|sources\.csv)$")
DEFAULT_GRADIENT_QUALITY = os.path.join(os.path.dirname(HERE), "data", "gradient_quality.csv")


def missing_modules() -> list:
    missing = []
    for name in REQUIRED:
        if name.split(".")[0] in missing:
            continue
        try:
            importlib.import_module(name)
        except Exception:  # ImportError, or a broken install raising something else
            missing.append(name)
    if "matplotlib" not in missing:
        try:
            import matplotlib
            matplotlib.use("Agg")
            importlib.import_module("matplotlib.pyplot")
        except Exception:
            missing.append("matplotlib (Agg backend)")
    return missing


def fail(msg: str) -> int:
    print(f"make_report: {msg}", file=sys.stderr)
    return 2


def not_regular(option: str, path: str):
    """The refusal of a path that must name a regular file, in the harness's words (never opened:
    a FIFO would block the read forever), or None when it is one."""
    try:
        mode = os.stat(path).st_mode
    except OSError as e:
        return f"{option}: '{path}': cannot open: {e.strerror}"
    if stat.S_ISREG(mode):
        return None
    kind = ("a directory" if stat.S_ISDIR(mode) else "a FIFO (named pipe)" if stat.S_ISFIFO(mode)
            else "a character device" if stat.S_ISCHR(mode) else "a block device" if stat.S_ISBLK(mode)
            else "a socket" if stat.S_ISSOCK(mode) else None)
    return f"{option}: '{path}' is " + (f"{kind}, not a regular file" if kind else "not a regular file")


def parse_args(argv):
    p = argparse.ArgumentParser(prog="make_report.py", description=__doc__.splitlines()[0])
    p.add_argument("--db", required=True, help="harness SQLite database (opened read-only)")
    p.add_argument("--out", required=True, help="output folder (created; files overwritten)")
    p.add_argument("--landscapes", help="folder of <env>_<i>_<j>.csv from `harness landscape`")
    p.add_argument("--build-type", default="unknown", help="build type of the harness (provenance)")
    p.add_argument("--claims", default=os.path.join(HERE, "paper_claims.csv"),
                   help="the paper's claims to test (default: reports/paper_claims.csv)")
    p.add_argument("--gradient-quality",
                   help="CSV of scripts/gradient-quality.sh for the 'Gradient quality' section "
                        "(default: data/gradient_quality.csv, the section says so when it is absent)")
    p.add_argument("--renders", help="folder of render_<env>.png from scripts/render-best.sh, shown "
                                     "in each env's section")
    p.add_argument("--with", dest="with_archive", metavar="DIR",
                   help="a folder of the published archive (data/study): its runs join the database's, marked "
                        "archived, so yours are ranked and tested beside them (docs/results.md)")
    p.add_argument("--harness", help="harness binary whose `list` says which envs exist and which "
                                     "optimizers --all runs on each (default: $DSB_HARNESS, else "
                                     "build/bin/harness of this source tree if it exists); its "
                                     "results versions tell which runs are stale")
    p.add_argument("--include-stale", action="store_true",
                   help="show the runs made by other results versions than the harness's (stale), "
                        "each as an optimizer of its own (OPT-stale-eEoOrR), instead of leaving them "
                        "out; the claims still judge current runs only")
    return p.parse_args(argv)


def load_registry(registry, harness):
    """`harness list` of --harness (an error when it cannot be read) or of the default harness
    (None when there is none or it cannot be read: the claims then cannot tell a missing env, and
    no run can be judged stale)."""
    if harness:
        return registry.load(harness)
    default = registry.default_harness(os.path.dirname(HERE))
    try:
        return registry.load(default) if default else None
    except registry.RegistryError:
        return None


def main(argv=None) -> int:
    missing = missing_modules()
    if missing:
        return fail(f"{sys.executable} cannot import {', '.join(missing)}; run with Debian's "
                    "/usr/bin/python3 (apt-get install python3-pandas python3-matplotlib "
                    "python3-scipy)")
    args = parse_args(sys.argv[1:] if argv is None else argv)
    if HERE not in sys.path:
        sys.path.insert(0, HERE)
    from dsb_report import build, charts, claims, plots, registry
    from dsb_report import gradient_quality as gq
    from dsb_report.data import DataError, load

    t0 = time.monotonic()
    for option, path in (("--db", args.db), ("--claims", args.claims), ("--gradient-quality", args.gradient_quality)):
        problem = path is not None and not_regular(option, path)
        if problem:
            return fail(problem.encode("unicode_escape").decode("ascii") if not problem.isprintable() else problem)
    if args.with_archive is not None and not os.path.isdir(args.with_archive):
        return fail(f"--with: '{args.with_archive}' is not a folder of archive files (*.runs.jsonl.gz)")
    try:
        claim_list = claims.load(args.claims)
    except claims.ClaimsError as e:
        return fail(str(e))
    gq_path = args.gradient_quality or DEFAULT_GRADIENT_QUALITY
    gq_table = None
    if args.gradient_quality is not None or os.path.isfile(gq_path):
        try:
            gq_table = gq.load(gq_path)
        except gq.GradientQualityError as e:
            return fail(str(e))
    try:
        env_registry = load_registry(registry, args.harness)
    except registry.RegistryError as e:
        return fail(str(e))
    try:
        data = load(args.db, env_registry, args.include_stale, args.with_archive)   # stale runs judged by its versions
    except DataError as e:
        return fail(str(e))
    if args.landscapes is not None and not os.path.isdir(args.landscapes):
        return fail(f"--landscapes '{args.landscapes}' is not a directory")
    if args.renders is not None and not os.path.isdir(args.renders):
        return fail(f"--renders '{args.renders}' is not a directory")
    try:
        os.makedirs(args.out, exist_ok=True)
        probe = os.path.join(args.out, ".make_report_probe")
        with open(probe, "w"):
            pass
        os.remove(probe)
    except OSError as e:
        return fail(f"cannot write to --out '{args.out}': {e.strerror or e}")
    made = datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%dT%H:%M:%SZ")
    written = build.build(data, args.out, args.landscapes, args.build_type, made, claim_list,
                          gq_table, gq_path, args.renders, env_registry)
    for name in sorted(os.listdir(args.out)):        # stale figures/tables of an older report
        if (OWN_FILES.match(name) or charts.writes(plots.CHARTS, name)) and name not in written:
            os.remove(os.path.join(args.out, name))
    n_png = sum(f.endswith(".png") for f in written)
    print(f"make_report: wrote {os.path.join(args.out, 'index.html')} ({len(written)} files, "
          f"{n_png} figures) in {time.monotonic() - t0:.1f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
