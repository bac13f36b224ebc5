#!/usr/bin/python3
"""The published archive's files (reports/dsb_report/archive.py): a study's runs with their
per-episode losses, checked against the runs the study published.

    /usr/bin/python3 scripts/archive_runs.py write DB OUT.runs.jsonl.gz [--against RUNS.csv ...]
    /usr/bin/python3 scripts/archive_runs.py check ARCHIVE [ARCHIVE ...] --against RUNS.csv [...]
        [--allow-missing] [--harness BIN] [--update FILE | --agree FILE]
    /usr/bin/python3 scripts/archive_runs.py land PIECES STUDY
    /usr/bin/python3 scripts/archive_runs.py runs-csv ARCHIVE [ARCHIVE ...] OUT.csv

`write` archives every 'done' run of DB (a new file only). With --against, DB must hold exactly
the published runs of those CSVs that it has keys for, each with its final best loss the same
bits as published (a rerun on other code that gives other results is refused, exit 2, naming the
runs), and the runs it has that no CSV publishes are left out; it says how many of the CSVs'
runs it archived. `check` compares archive files (or folders of them) with the runs CSVs: every
published run archived once, with the same final best loss bits, rebuilt from its losses; exit 1
naming each difference. With --allow-missing, a published run not archived (a study whose
databases are gone and not yet rerun) is counted, not an error. --update FILE writes the table of
what the archive holds, per study, between FILE's `<!-- archive: begin -->` and
`<!-- archive: end -->` lines; --agree FILE exits 1 when that block is not the table this check
makes. `land` archives a rerun's pieces (PIECES/*.sqlite, what scripts/grid-in-pieces.sh leaves
in OUTDIR/pieces) into the study folder that publishes them (STUDY/*.csv): a piece whose runs are
all done, all published in one runs CSV NAME.csv and none archived yet, each with its published
final best loss bit for bit, becomes STUDY/NAME.runs.jsonl.gz (named after the CSV, whatever the
piece's own name); pieces still running, archived already or publishing none are counted and left;
a piece that differs, or is published across CSVs, is named and not archived (exit 1). Run it
again as pieces finish. --harness BIN adds the table's column of archived runs made by BIN's results versions
(`BIN list`; reports/dsb_report/staleness.py) and names why the others are stale: a version
bumped without a rerun changes the table, so the docs say it (a stale run is no error here; a
report leaves it out). `runs-csv` writes archive files' runs (or folders of them) as one runs CSV (a new file,
reports/dsb_report/runs_csv.py): the rows `scripts/study_results.py export` gives the database they
were archived from, byte for byte, so a study whose databases are gone still has its runs CSV with
results versions (and a rerun's scratch folder its landed pieces: data/study/fluid/README.md).
Exit 2: bad input, one line.
"""
from __future__ import annotations

import argparse
import os
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(os.path.dirname(HERE), "reports"))
sys.path.insert(0, HERE)
from python_modules import cannot_import  # noqa: E402

RUN_KEY = ["env", "optimizer", "seed", "budget", "env_config_hash", "opt_config_hash"]


def fail(msg: str) -> int:
    print(f"archive_runs: {msg}", file=sys.stderr)
    return 2


def published(paths):
    """key -> (row, file) of the runs CSVs' runs, their best_loss as a float (NaN when empty)."""
    import csv
    out = {}
    for path in paths:
        try:
            with open(path, newline="", encoding="utf-8") as f:
                for row in csv.DictReader(f):
                    key = tuple(str(row[c]) for c in RUN_KEY)
                    if key in out:
                        raise ValueError(f"run {'/'.join(key[:4])} is in both '{out[key][1]}' and '{path}'")
                    out[key] = (row, path)
        except OSError as e:
            raise ValueError(f"cannot read '{path}': {e.strerror}") from None
    return out


def final_best(run) -> float:
    from dsb_report import archive
    return archive.final_best(run["loss"])[0]


def same_bits(a: float, b: float) -> bool:
    return (a != a and b != b) or (a == b and a.hex() == b.hex())


def key_of(run) -> tuple:
    return tuple(str(run[c]) for c in RUN_KEY)


def write(a) -> int:
    from dsb_report import archive, data as data_mod
    try:
        con = data_mod.connect_ro(a.db)
        try:
            runs = archive.runs_of_db(con)
        finally:
            con.close()
    except (data_mod.DataError, archive.ArchiveError) as e:
        return fail(str(e))
    if a.against:
        try:
            pub = published(a.against)
        except ValueError as e:
            return fail(str(e))
        kept, differ = [], []
        for r in runs:
            p = pub.get(key_of(r))
            if p is None:
                continue
            want, got = pub_best(pub, r), final_best(r)
            if not same_bits(want, got):
                differ.append(f"{'/'.join(key_of(r)[:4])}: published {want!r}, here {got!r}")
            kept.append(r)
        if differ:
            return fail(f"{len(differ)} runs differ from the published ones, nothing written: " + "; ".join(differ))
        print(f"archive_runs: {len(kept)} of the {len(pub)} published runs found in {a.db}, each the same final "
              f"best loss bit for bit")
        runs = kept
    try:
        n = archive.write(runs, a.out)
    except archive.ArchiveError as e:
        return fail(str(e))
    print(f"archive_runs: {n} runs -> {a.out} ({os.path.getsize(a.out)} bytes)")
    return 0


def land(a) -> int:
    """Archives each finished piece database of a rerun (PIECES/*.sqlite) whose runs a study
    publishes (STUDY/*.csv), checked bit for bit, into STUDY/NAME.runs.jsonl.gz, NAME the runs CSV
    that publishes them; pieces archived already, still running or publishing nothing are skipped."""
    import glob
    from dsb_report import archive, data as data_mod
    if not os.path.isdir(a.pieces):
        return fail(f"'{a.pieces}': not a folder of piece databases")
    csvs = sorted(glob.glob(os.path.join(a.study, "*.csv")))
    if not csvs:
        return fail(f"'{a.study}': no runs CSV in it")
    try:
        pub = published(csvs)
        archived = {key_of(r) for f in archive.files_under(a.study) for r in archive.read(f)}
    except (ValueError, archive.ArchiveError) as e:
        return fail(str(e))
    counts, problems = {"landed": 0, "archived already": 0, "running": 0, "publishing none": 0}, []
    for db in sorted(glob.glob(os.path.join(a.pieces, "*.sqlite"))):
        try:
            con = data_mod.connect_ro(db)
            try:
                unfinished = con.execute("SELECT count(*) FROM runs WHERE status <> 'done'").fetchone()[0]
                runs = archive.runs_of_db(con)
            finally:
                con.close()
        except (data_mod.DataError, archive.ArchiveError) as e:
            problems.append(str(e))
            continue
        mine = [r for r in runs if key_of(r) in pub]
        if unfinished:
            counts["running"] += 1
            continue
        if not mine:
            counts["publishing none"] += 1
            continue
        new = [r for r in mine if key_of(r) not in archived]
        if not new:
            counts["archived already"] += 1
            continue
        if len(new) != len(mine):
            problems.append(f"{db}: {len(mine) - len(new)} of its {len(mine)} published runs are archived already, "
                            "the others not: archive it by hand (write --against)")
            continue
        sources = sorted({pub[key_of(r)][1] for r in mine})
        if len(sources) != 1:
            problems.append(f"{db}: its runs are published in {len(sources)} runs CSVs ({', '.join(sources)})")
            continue
        differ = [f"{'/'.join(key_of(r)[:4])}: published {pub_best(pub, r)!r}, here {final_best(r)!r}"
                  for r in mine if not same_bits(pub_best(pub, r), final_best(r))]
        if differ:
            problems.append(f"{db}: {len(differ)} runs differ from the published ones, not archived: " + "; ".join(differ))
            continue
        out = os.path.splitext(sources[0])[0] + archive.SUFFIX
        try:
            archive.write(mine, out)
        except archive.ArchiveError as e:
            problems.append(str(e))
            continue
        archived.update(key_of(r) for r in mine)
        counts["landed"] += 1
        print(f"archive_runs: {db}: {len(mine)} runs, each its published final best loss bit for bit -> {out}")
    print("archive_runs: pieces " + ", ".join(f"{n} {what}" for what, n in counts.items())
          + (f"; {len(problems)} problems" if problems else ""))
    for p in problems:
        print(f"archive_runs: {p}")
    return 1 if problems else 0


def pub_best(pub, run) -> float:
    row = pub[key_of(run)][0]
    return float(row["best_loss"]) if row["best_loss"] else float("nan")


def to_runs_csv(a) -> int:
    from dsb_report import archive, runs_csv
    try:
        runs = [r for path in a.archives for f in archive.files_under(path) for r in archive.read(f)]
        n = runs_csv.write_archived(runs, a.out)
    except OSError as e:
        return fail(f"cannot read '{e.filename}': {e.strerror}")
    except (archive.ArchiveError, runs_csv.RunsCsvError) as e:
        return fail(str(e))
    print(f"archive_runs: {n} runs -> {a.out}")
    return 0


BEGIN, END = "<!-- archive: begin -->", "<!-- archive: end -->"


def study_of(csv_path: str) -> str:
    """The study a runs CSV publishes: its folder when it is one of a grid's pieces, else the file."""
    d = os.path.dirname(os.path.normpath(csv_path))
    return d + "/" if os.path.basename(d) != "study" else os.path.normpath(csv_path)


def table(pub, seen, sizes, stale=None) -> str:
    """Markdown: per study, its published runs, those archived with their losses, the bytes; with
    `stale` (archived run key -> why it is stale for the harness asked, '' when current) also how
    many archived runs are of that harness's results versions, and why the others are not."""
    rows = {}
    for k, (_, path) in pub.items():
        r = rows.setdefault(study_of(path), {"runs": 0, "archived": 0, "files": set(), "current": 0, "why": []})
        r["runs"] += 1
        if k in seen:
            r["archived"] += 1
            r["files"].add(seen[k])
            why = stale.get(k, "") if stale is not None else ""
            if not why:
                r["current"] += 1
            elif why not in r["why"]:
                r["why"].append(why)
    judged = stale is not None
    lines = ["| study (runs CSV) | published runs | archived with losses |"
             + (" of this code's results versions |" if judged else "") + " archive files | bytes |",
             "|---|---:|---:|" + ("---:|" if judged else "") + "---:|---:|"]
    total = 0
    for study in sorted(rows):
        r = rows[study]
        b = sum(sizes[f] for f in r["files"])
        total += b
        note = "" if r["archived"] == r["runs"] else " (curves missing: not rerun yet)"
        current = (f" {r['current']}" + (f" (stale: {'; '.join(sorted(r['why']))})" if r["why"] else "") + " |"
                   if judged else "")
        lines.append(f"| `{study}` | {r['runs']} | {r['archived']}{note} |{current} {len(r['files'])} | {b:,} |")
    current_all = f" {sum(r['current'] for r in rows.values())} |" if judged else ""
    lines.append(f"| all | {len(pub)} | {len(seen)} |{current_all} {len(sizes)} | {total:,} ({total / 1e6:.2f} MB) |")
    return "\n".join(lines)


def staleness_of(runs, harness: str) -> dict:
    """Archived run key -> why the run is stale for `harness` (reports/dsb_report/staleness.py:
    its results versions against `harness list`'s), '' when current."""
    from dsb_report import registry as registry_mod, staleness
    registry = registry_mod.load(harness)
    if not staleness.judgeable(registry):
        raise ValueError(f"--harness {harness}: its `list` gives no results versions")
    return {key_of(r): staleness.reason(registry, r["env"], r["optimizer"], r["results_versions"]) for r, _ in runs}


def with_block(text: str, block: str, path: str) -> str:
    if text.count(BEGIN) != 1 or text.count(END) != 1 or text.index(BEGIN) > text.index(END):
        raise ValueError(f"'{path}' has no single '{BEGIN}' ... '{END}' block")
    head, rest = text.split(BEGIN)
    return head + BEGIN + "\n" + block + "\n" + END + rest.split(END, 1)[1]


def check(a) -> int:
    from dsb_report import archive
    try:
        pub = published(a.against)
        runs, sizes = [], {}
        for path in a.archives:
            for f in archive.files_under(path):
                runs += [(r, f) for r in archive.read(f)]
                sizes[f] = os.path.getsize(f)
        doc = a.update or a.agree
        text = open(doc, encoding="utf-8").read() if doc else None
    except OSError as e:
        return fail(f"cannot read '{e.filename}': {e.strerror}")
    except (ValueError, archive.ArchiveError) as e:
        return fail(str(e))
    stale = None
    if a.harness:
        from dsb_report import registry as registry_mod
        try:
            stale = staleness_of(runs, a.harness)
        except (ValueError, registry_mod.RegistryError) as e:
            return fail(str(e))
    problems, seen = [], {}
    for r, f in runs:
        k = key_of(r)
        if k in seen:
            problems.append(f"{'/'.join(k[:4])} archived twice ('{seen[k]}', '{f}')")
            continue
        seen[k] = f
        p = pub.get(k)
        if p is None:
            continue
        want = pub_best(pub, r)
        if not same_bits(want, final_best(r)):
            problems.append(f"{'/'.join(k[:4])}: published {want!r}, archived {final_best(r)!r}")
    missing = [k for k in pub if k not in seen]
    if not a.allow_missing:
        for k in missing:
            problems.append(f"{'/'.join(k[:4])} published in '{pub[k][1]}' but not archived")
    print(f"archive_runs: {len(pub) - len(missing)} of {len(pub)} published runs archived"
          f"{'' if not problems else f'; {len(problems)} problems'}")
    for p in problems:
        print(f"archive_runs: {p}")
    if stale is not None:
        n = sum(1 for k in seen if k in pub and stale.get(k))
        print(f"archive_runs: {n} of the archived published runs are stale for {a.harness}"
              + ("" if not n else " (other results versions: the table says why)"))
    if text is not None:
        try:
            want = with_block(text, table(pub, {k: f for k, f in seen.items() if k in pub}, sizes, stale), doc)
        except ValueError as e:
            return fail(str(e))
        if a.update and want != text:
            with open(doc, "w", encoding="utf-8") as f:
                f.write(want)
            print(f"archive_runs: updated the archive table in '{doc}'")
        if a.agree and want != text:
            problems.append(f"the archive table in '{doc}' is not this archive's; run with --update {doc}")
            print(f"archive_runs: {problems[-1]}")
    return 1 if problems else 0


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    sub = ap.add_subparsers(dest="command", required=True)
    w = sub.add_parser("write", help="archive a database's done runs")
    w.add_argument("db")
    w.add_argument("out")
    w.add_argument("--against", nargs="+", help="the runs CSVs the archive must repeat")
    c = sub.add_parser("check", help="compare archive files with the published runs")
    c.add_argument("archives", nargs="+")
    c.add_argument("--against", nargs="+", required=True)
    c.add_argument("--allow-missing", action="store_true",
                   help="count published runs not archived instead of failing on them")
    c.add_argument("--harness", metavar="BIN",
                   help="also count the archived runs of BIN's results versions (the table's column)")
    doc = c.add_mutually_exclusive_group()
    doc.add_argument("--update", metavar="FILE", help="write the archive table into FILE's block")
    doc.add_argument("--agree", metavar="FILE", help="fail when FILE's archive table is not this one")
    ld = sub.add_parser("land", help="archive a rerun's finished pieces that a study publishes")
    ld.add_argument("pieces")
    ld.add_argument("study")
    r = sub.add_parser("runs-csv", help="archive files' runs as one runs CSV (a new file)")
    r.add_argument("archives", nargs="+")
    r.add_argument("out")
    a = ap.parse_args(argv)
    why = cannot_import("numpy", "pandas")
    if why:
        return fail(why)
    return {"write": write, "check": check, "land": land, "runs-csv": to_runs_csv}[a.command](a)


if __name__ == "__main__":
    sys.exit(main())
