#!/usr/bin/env bash
# A harness grid run in pieces of one run that land as they finish, for a grid longer than one
# machine's life (issue 29's fluid grid: about 16 core-hours, several sessions of this machine).
#
#   scripts/grid-in-pieces.sh OUTDIR DEST [--jobs J] [--split-groups-over S] BUILD_DIR -- GRID_FLAGS...
#   e.g. scripts/grid-in-pieces.sh /scratch/fluid data/study/fluid --jobs 2 build -- --all --env fluid --seeds 5
#
# Each (env, optimizer) of the grid, cheapest first as `harness plan GRID_FLAGS` orders them, is
# cut into pieces of one run each (scripts/lib/run-pieces.sh: the harness's own deterministic
# slices, --shard I/N; a group whose seeds share episodes is one piece, run whole so that its later
# seeds replay the first). --split-groups-over S cuts such a group into one-run pieces too when
# the plan gives it more than S seconds (a group longer than the machine's life would never land):
# its pieces run with --no-sharing, each seed simulating the episodes it would have replayed, with
# the same results bit for bit (docs/determinism.md; a harness older than this option keeps the
# group whole, and says so). A piece runs into OUTDIR/pieces/ENV__OPT@IofN.sqlite (ENV__OPT.sqlite
# when whole) and resumes there when interrupted; once its runs are done (or failed, which are
# results) they are written in the runs CSV format (scripts/study_results.py export,
# reports/dsb_report/runs_csv.py), and with their per-episode losses as NAME.runs.jsonl.gz (the
# published archive: scripts/archive_runs.py), and copied into DEST under the same names, never
# over a file there. A piece DEST already holds is taken as done without running if its runs carry this
# binary's results versions (its results_versions column: pieces belong together when their
# versions agree, whatever commit made them), or, for a piece written before versions, if this
# very binary made it (its git_sha column); any other is refused (exit 2, naming the file). At the end
# OUTDIR/runs.csv holds the runs of every piece of the grid, DEST's and new, sorted, for
# `scripts/study_results.py tables`. Interrupted? Run the same command again.
set -euo pipefail
usage="usage: grid-in-pieces.sh OUTDIR DEST [--jobs J] [--split-groups-over S] BUILD_DIR -- GRID_FLAGS..."
out=${1:?$usage}
dest=${2:?$usage}
shift 2
jobs=2
split_over=
build=
while (($#)); do
  case $1 in
    --jobs) jobs=${2:?$usage}; shift 2 ;;
    --split-groups-over) split_over=${2:?$usage}; shift 2 ;;
    --) shift; break ;;
    -*) echo "grid-in-pieces: unknown option '$1'" >&2; exit 2 ;;
    *) build=$1; shift ;;
  esac
done
(($#)) || { echo "grid-in-pieces: no grid flags after '--' ($usage)" >&2; exit 2; }
[[ $jobs =~ ^[1-9][0-9]*$ ]] || { echo "grid-in-pieces: --jobs must be a whole number from 1, got '$jobs'" >&2; exit 2; }
[[ -z $split_over || $split_over =~ ^[0-9]+$ ]] ||
  { echo "grid-in-pieces: --split-groups-over must be a whole number of seconds, got '$split_over'" >&2; exit 2; }
root=$(cd "$(dirname "$0")/.." && pwd)
harness=${build:?$usage}/bin/harness
[[ -x $harness ]] || { echo "grid-in-pieces: no harness at $harness" >&2; exit 2; }
[[ -d $dest ]] || { echo "grid-in-pieces: no folder '$dest'" >&2; exit 2; }
grid=("$@")
# shellcheck source=scripts/lib/run-pieces.sh
source "$root/scripts/lib/run-pieces.sh"
mkdir -p "$out/pieces"
plan_db=$out/pieces/.plan-nothing.sqlite
# the commit as the harness stamps its runs (git_sha), "-dirty" included for a build of uncommitted
# changes: such pieces name no commit, fine for a try, not for data to publish
sha=$("$harness" --version | sed -n 's/.*(git \([0-9a-f]*\(-dirty\)\{0,1\}\).*/\1/p')
[[ -n $sha ]] || { echo "grid-in-pieces: cannot read the commit from '$harness --version'" >&2; exit 2; }
[[ $sha != *-dirty ]] || echo "grid-in-pieces: warning: $harness is built from uncommitted changes ($sha)" >&2

# the grid's (env, optimizer) pairs, cheapest first (the plan's start ranks), each with the flags
# of its own grid: --env ENV --optimizer OPT --seeds --budget as the plan has them, and the grid's
# --set, --ext and --ext-timeout flags that concern the pair (the harness refuses a --set naming
# neither an env nor an optimizer of its grid). A line: ENV OPT PLANNED_S base64(NUL-separated
# flags), PLANNED_S the plan's seconds for the pair's runs (rounded up).
"$harness" plan "${grid[@]}" --db "$plan_db" --runs-csv "$out/pieces/.plan.csv.tmp" >/dev/null
mv "$out/pieces/.plan.csv.tmp" "$out/pieces/plan.csv"
mapfile -t pairs < <(/usr/bin/python3 - "$out/pieces/plan.csv" "${grid[@]}" <<'PY'
import base64, csv, math, sys
plan, flags = sys.argv[1], sys.argv[2:]
# the grid's flags that may concern one pair: (flag, value)
kept = []
i = 0
while i < len(flags):
    f = flags[i]
    name, eq, val = f.partition("=")
    if name in ("--set", "--ext", "--ext-timeout"):
        if not eq:
            i += 1
            val = flags[i] if i < len(flags) else ""
        kept.append((name, val))
    i += 1
pairs = {}
for r in csv.DictReader(open(plan)):
    p = pairs.setdefault((r["env"], r["optimizer"]), {"rank": 1 << 62, "seeds": 0, "budgets": set(), "s": 0.0})
    p["s"] += float(r["planned_s"])
    p["rank"] = min(p["rank"], int(r["start_rank"]))
    p["seeds"] = max(p["seeds"], int(r["seed"]) + 1)
    p["budgets"].add(r["budget"])
for (env, opt), p in sorted(pairs.items(), key=lambda kv: (kv[1]["rank"], kv[0])):
    if len(p["budgets"]) != 1:
        sys.exit(f"grid-in-pieces: {env} x {opt} has runs of several budgets")
    own = ["--env", env, "--optimizer", opt, "--seeds", str(p["seeds"]), "--budget", p["budgets"].pop()]
    for name, val in kept:
        if name == "--set" and val.split(".", 1)[0] not in (env, opt):
            continue
        if name == "--ext" and "ext:" + val.split("=", 1)[0] != opt:
            continue
        own += [name, val]
    print(env, opt, math.ceil(p["s"]), base64.b64encode("\0".join(own).encode() + b"\0").decode())
PY
)
((${#pairs[@]})) || { echo "grid-in-pieces: the grid has no runs" >&2; exit 2; }

# a DEST piece that belongs to this grid: its runs carry this binary's results versions for their
# env and optimizer (docs/database.md "Results versions": a later commit that changes no result
# carries a grid on), or, for a piece written before versions, this binary's very commit
listing=$("$harness" list)
made_here() {
  /usr/bin/python3 - "$1" "$sha" "$root/reports" "$listing" <<'PY' || { echo "grid-in-pieces: $1 was made by other results versions than this binary's (or, without versions, another commit than $sha): build code of those versions, or move the file away" >&2; return 1; }
import csv, sys
sys.path.insert(0, sys.argv[3])
from dsb_report import registry
reg = registry.parse(sys.argv[4])
rows = list(csv.DictReader(open(sys.argv[1])))
def ours(r):
    v = r.get("results_versions") or ""
    if not v:
        return r["git_sha"] == sys.argv[2]
    now = reg.current_versions(r["env"], r["optimizer"])
    return now is not None and v == "env {}, optimizer {}, run {}".format(*now)
sys.exit(0 if rows and all(ours(r) for r in rows) else 1)
PY
}

todo=()
for pair in "${pairs[@]}"; do
  read -r env opt planned flags64 <<<"$pair"
  mapfile -d '' -t flags < <(base64 -d <<<"$flags64")
  mapfile -t slices < <(grid_pieces "$harness" "$plan_db" "${flags[@]}")
  if ((${#slices[@]} == 0)) && [[ -n $split_over ]] && ((planned > split_over)) && [[ ! -f $dest/${env}__$opt.csv ]]; then
    # a sharing group over the limit (and not landed whole): one-run pieces without sharing, if
    # this harness cuts them. Give the same option when resuming, or the group runs whole again.
    mapfile -t slices < <(grid_pieces "$harness" "$plan_db" "${flags[@]}" --no-sharing)
    if ((${#slices[@]})); then
      echo "  $env x $opt: planned ${planned} s over --split-groups-over $split_over: ${#slices[@]} one-run pieces, --no-sharing"
      flags64=$(printf '%s\0' "${flags[@]}" --no-sharing | base64 -w0)
    else
      echo "  $env x $opt: planned ${planned} s over --split-groups-over $split_over, but this harness keeps a sharing group's seeds in one slice even with --no-sharing: whole"
    fi
  fi
  ((${#slices[@]})) || slices=("")
  for slice in "${slices[@]}"; do
    name=${env}__$opt${slice:+@${slice/\//of}}
    if [[ -f $dest/$name.csv ]]; then
      made_here "$dest/$name.csv" || exit 2
      echo "  landed: $name"
      continue
    fi
    todo+=("$flags64|$slice|$name")
  done
done
echo "grid-in-pieces: ${#pairs[@]} (env, optimizer) pairs, ${#todo[@]} pieces to run, $jobs at once, into $out"

run_piece() {
  local flags64 slice name db code=0 flags
  IFS='|' read -r flags64 slice name <<<"$1"
  mapfile -d '' -t flags < <(base64 -d <<<"$flags64")
  db=$out/pieces/$name.sqlite
  "$harness" "${flags[@]}" ${slice:+--shard "$slice"} --jobs 1 --quiet --db "$db" || code=$?
  # exit 3: some runs failed, which are results; anything else (an interruption) leaves it to resume
  ((code == 0 || code == 3)) || return 0
  rm -f "$out/pieces/$name.csv.tmp"
  /usr/bin/python3 "$root/scripts/study_results.py" export "$db" "$out/pieces/$name.csv.tmp" >/dev/null
  mv "$out/pieces/$name.csv.tmp" "$out/pieces/$name.csv"
  # the piece's runs with their per-episode losses, for the published archive (archive_runs.py)
  rm -f "$out/pieces/$name.runs.jsonl.gz"
  /usr/bin/python3 "$root/scripts/archive_runs.py" write "$db" "$out/pieces/$name.runs.jsonl.gz" >/dev/null
  [[ -e $dest/$name.runs.jsonl.gz ]] ||
    { cp "$out/pieces/$name.runs.jsonl.gz" "$dest/.$name.runs.jsonl.gz.tmp" && mv "$dest/.$name.runs.jsonl.gz.tmp" "$dest/$name.runs.jsonl.gz"; }
  [[ -e $dest/$name.csv ]] || { cp "$out/pieces/$name.csv" "$dest/$name.csv.tmp" && mv "$dest/$name.csv.tmp" "$dest/$name.csv"; }
  echo "  done: $name"
}
export -f run_piece
export harness out dest root
((${#todo[@]} == 0)) || printf '%s\n' "${todo[@]}" | xargs -d '\n' -P "$jobs" -I{} bash -c 'run_piece "$1"' _ {}

# every piece of the grid, landed or new, in one runs CSV
/usr/bin/python3 - "$out/runs.csv" "$dest" "${pairs[@]}" <<'PY'
import csv, glob, os, sys
out, dest, pairs = sys.argv[1], sys.argv[2], [p.split(" ")[:2] for p in sys.argv[3:]]
rows, header = [], None
for env, opt in pairs:
    for f in sorted(glob.glob(os.path.join(dest, f"{env}__{opt}.csv")) + glob.glob(os.path.join(dest, f"{env}__{opt}@*of*.csv"))):
        with open(f, newline="") as fh:
            r = csv.reader(fh)
            h = next(r)
            # a piece from before a column was added (seed_free_episodes) has a prefix of the columns
            short, long_ = sorted([h, header or h], key=len)
            if long_[:len(short)] != short:
                sys.exit(f"grid-in-pieces: {f} has other columns than the other pieces")
            header = long_
            rows.extend(r)
rows = [r + [""] * (len(header) - len(r)) for r in rows] if header else rows
key = {c: i for i, c in enumerate(header or [])}
rows.sort(key=lambda r: (r[key["env"]], r[key["optimizer"]], int(r[key["budget"]]), int(r[key["seed"]])))
with open(out + ".tmp", "w", newline="") as fh:
    w = csv.writer(fh, lineterminator="\n")
    if header:
        w.writerow(header)
    w.writerows(rows)
os.replace(out + ".tmp", out)
print(f"grid-in-pieces: {len(rows)} runs in {out}")
PY
