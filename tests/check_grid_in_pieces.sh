#!/usr/bin/env bash
# scripts/grid-in-pieces.sh end to end on a cheap grid (sphere-10 x random, gd, cmaes x 3 seeds,
# 50 episodes, a knob of cmaes set): the pieces hold one run each (gd's seeds share episodes: one
# piece) and each lands with its archive file (per-episode losses: 9 of 9 runs), their runs CSV equals the one exported from the same grid run directly (every column
# but the wall time), a second run with the pieces landed runs nothing and writes the same file,
# a piece of other results versions is refused (one of another commit with the same versions is
# taken), and --split-groups-over cuts gd's group into one-run
# pieces (without sharing) that give the same runs.
set -euo pipefail
build=${1:?usage: check_grid_in_pieces.sh BUILD_DIR SOURCE_DIR}
src=${2:?usage: check_grid_in_pieces.sh BUILD_DIR SOURCE_DIR}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
grid=(--env sphere-10 --optimizer random,gd,cmaes --seeds 3 --budget 50 --set cmaes.sigma0=0.5)
mkdir "$work/dest"
"$src/scripts/grid-in-pieces.sh" "$work/out" "$work/dest" --jobs 2 "$build" -- "${grid[@]}" >"$work/log" 2>&1 ||
  { cat "$work/log" >&2; exit 1; }
"$build/bin/harness" "${grid[@]}" --jobs 2 --quiet --db "$work/direct.sqlite" 2>/dev/null
/usr/bin/python3 "$src/scripts/study_results.py" export "$work/direct.sqlite" "$work/direct.csv" >/dev/null
/usr/bin/python3 - "$work" <<'PY'
import csv, glob, json, os, sqlite3, sys
work = sys.argv[1]
pieces = sorted(os.path.basename(p) for p in glob.glob(f"{work}/dest/*.csv"))
by_opt = {}
for p in pieces:
    by_opt.setdefault(p.split("__")[1].split("@")[0].removesuffix(".csv"), []).append(p)
assert sorted(by_opt) == ["cmaes", "gd", "random"], pieces
assert by_opt["gd"] == ["sphere-10__gd.csv"], pieces  # shared episodes: whole
for opt in ("random", "cmaes"):
    assert len(by_opt[opt]) == 3 and all("@" in p for p in by_opt[opt]), pieces
    for p in by_opt[opt]:
        assert len(list(csv.DictReader(open(f"{work}/dest/{p}")))) == 1, p
drop = lambda rows: [{k: v for k, v in r.items() if k != "wall_s"} for r in rows]
mine = list(csv.DictReader(open(f"{work}/out/runs.csv")))
direct = list(csv.DictReader(open(f"{work}/direct.csv")))
assert len(mine) == 9, len(mine)
assert drop(mine) == drop(direct), (mine, direct)
# the knob reached cmaes's pieces, and only them
con = sqlite3.connect(f"file:{work}/direct.sqlite?mode=ro", uri=True)
cfg = {o: json.loads(j) for o, j in con.execute(
    "SELECT DISTINCT r.optimizer, c.json FROM runs r JOIN configs c ON c.hash = r.opt_config_hash")}
assert cfg["cmaes"]["sigma0"] == 0.5, cfg["cmaes"]
print("pieces: 3 + 3 one-run pieces and gd whole; the runs CSV equals the direct grid's but for wall time")
PY
# every piece landed with its archive file, which repeats the published runs bit for bit
for f in "$work"/dest/*.csv; do
  [[ -f ${f%.csv}.runs.jsonl.gz ]] || { echo "no archive file beside $f" >&2; exit 1; }
done
/usr/bin/python3 "$src/scripts/archive_runs.py" check "$work/dest" --against "$work"/dest/*.csv |
  grep -q "^archive_runs: 9 of 9 published runs archived$" || { echo "the pieces' archive does not hold the 9 runs" >&2; exit 1; }
# landed pieces are taken as done: nothing runs, the same runs CSV
"$src/scripts/grid-in-pieces.sh" "$work/again" "$work/dest" --jobs 2 "$build" -- "${grid[@]}" >"$work/again.log" 2>&1
grep -q "0 pieces to run" "$work/again.log" || { cat "$work/again.log" >&2; exit 1; }
if compgen -G "$work/again/pieces/*.sqlite" >/dev/null; then echo "a landed piece was run again" >&2; exit 1; fi
cmp "$work/out/runs.csv" "$work/again/runs.csv"
# --split-groups-over 0: gd's sharing group runs as one-run pieces without sharing, the same runs
mkdir "$work/split"
"$src/scripts/grid-in-pieces.sh" "$work/splitout" "$work/split" --jobs 2 --split-groups-over 0 "$build" -- "${grid[@]}" \
  >"$work/split.log" 2>&1 || { cat "$work/split.log" >&2; exit 1; }
grep -q "sphere-10 x gd: planned .* s over --split-groups-over 0: 3 one-run pieces, --no-sharing" "$work/split.log" ||
  { cat "$work/split.log" >&2; exit 1; }
[[ ! -e $work/split/sphere-10__gd.csv && $(compgen -G "$work/split/sphere-10__gd@*of*.csv" | wc -l) == 3 ]] ||
  { ls "$work/split" >&2; exit 1; }
/usr/bin/python3 - "$work/out/runs.csv" "$work/splitout/runs.csv" <<'PY'
import csv, sys
drop = lambda f: [{k: v for k, v in r.items() if k != "wall_s"} for r in csv.DictReader(open(f))]
a, b = drop(sys.argv[1]), drop(sys.argv[2])
assert len(a) == 9 and a == b, (a, b)
PY
"$src/scripts/grid-in-pieces.sh" "$work/split" "$work/split" --split-groups-over x "$build" -- "${grid[@]}" 2>"$work/bad.err" &&
  { echo "a bad --split-groups-over was taken" >&2; exit 1; }
grep -q "got 'x'" "$work/bad.err" || { cat "$work/bad.err" >&2; exit 1; }
echo "--split-groups-over 0: gd in 3 one-run pieces without sharing, the same runs CSV"
# pieces belong together by their results versions, not their commit: a piece of another commit
# with this binary's versions is taken; one of other versions, or one without versions from
# another commit, is refused, naming it
edit_piece() {  # FILE COLUMN VALUE: every row's COLUMN set to VALUE
  /usr/bin/python3 - "$@" <<'PY'
import csv, sys
with open(sys.argv[1], newline="") as f:
    rows = list(csv.DictReader(f))
for r in rows:
    r[sys.argv[2]] = sys.argv[3]   # by name: the columns grow at the end
with open(sys.argv[1], "w", newline="") as f:
    w = csv.DictWriter(f, fieldnames=list(rows[0]), lineterminator="\n")
    w.writeheader()
    w.writerows(rows)
PY
}
try_other() {  # NAME: runs the grid with DEST = a copy of the landed pieces as edited; its exit code
  set +e
  "$src/scripts/grid-in-pieces.sh" "$work/$1" "$work/other" "$build" -- "${grid[@]}" >/dev/null 2>"$work/$1.err"
  local code=$?
  set -e
  return $code
}
mkdir "$work/other"
cp "$work"/dest/*.csv "$work/other/"
edit_piece "$work/other/sphere-10__gd.csv" git_sha 000000000000
try_other carried || { echo "a piece of another commit with this binary's versions was refused" >&2; cat "$work/carried.err" >&2; exit 1; }
edit_piece "$work/other/sphere-10__gd.csv" results_versions "env 1, optimizer 99, run 1"
if try_other versions; then echo "a piece of other results versions was taken" >&2; exit 1; else code=$?; fi
[[ $code == 2 ]] || { echo "expected exit 2 for a piece of other versions, got $code" >&2; exit 1; }
grep -q "sphere-10__gd.csv was made by other results versions" "$work/versions.err" || { cat "$work/versions.err" >&2; exit 1; }
edit_piece "$work/other/sphere-10__gd.csv" results_versions ""
if try_other third; then echo "a piece without versions from another commit was taken" >&2; exit 1; else code=$?; fi
[[ $code == 2 ]] || { echo "expected exit 2 for another commit's piece without versions, got $code" >&2; exit 1; }
grep -q "sphere-10__gd.csv was made by other results versions" "$work/third.err" || { cat "$work/third.err" >&2; exit 1; }
echo "landed pieces: taken without running, the same runs CSV; another commit's of the same versions taken, other versions refused"
