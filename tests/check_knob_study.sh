#!/usr/bin/env bash
# scripts/knob-study.sh end to end on a cheap env: two rand-descents variants x 3 seeds, merged,
# tabled; the table's medians are recomputed from SQLite and the variants' configs checked (the
# study's base point, lr 0.1, is set explicitly whatever the binary's default).
set -euo pipefail
build=${1:?usage: check_knob_study.sh BUILD_DIR SOURCE_DIR}
src=${2:?usage: check_knob_study.sh BUILD_DIR SOURCE_DIR}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
"$src/scripts/knob-study.sh" "$work" --envs sphere-10 --seeds 3 --only '^(reference|rand-descents(\.start_scale=0\.1)?)$' "$build" >/dev/null
/usr/bin/python3 - "$work" <<'PY'
import csv, json, sqlite3, statistics, sys
work = sys.argv[1]
rows = {(r["optimizer"], r["variant"]): r for r in csv.DictReader(open(f"{work}/knob_study.csv"))}
assert set(rows) == {("random", "default"), ("gd", "default"), ("cmaes", "default"),
                     ("rand-descents", "default"), ("rand-descents", "start_scale=0.1")}, sorted(rows)
con = sqlite3.connect(f"file:{work}/knob-study.sqlite?mode=ro", uri=True)
for (opt, variant), r in rows.items():
    want_scale = 0.1 if variant == "start_scale=0.1" else 1.0
    losses = []
    for best, cfg in con.execute("SELECT r.best_loss, c.json FROM runs r JOIN configs c ON c.hash = r.opt_config_hash "
                                 "WHERE r.optimizer = ? AND r.status = 'done'", (opt,)):
        if opt == "rand-descents" and json.loads(cfg)["start_scale"] != want_scale:
            continue
        # the study's base point is set explicitly (lr 0.1), not the binary's default (0.03)
        assert opt != "rand-descents" or json.loads(cfg)["adam"]["lr"] == 0.1, (opt, variant, cfg)
        losses.append(best)
    assert int(r["seeds"]) == len(losses) == 3, (opt, variant, r["seeds"], losses)
    assert float(r["median"]) == statistics.median(losses), (opt, variant, r["median"], losses)
v = rows[("rand-descents", "start_scale=0.1")]
base = rows[("rand-descents", "default")]
assert abs(float(v["ratio"]) - float(v["median"]) / float(base["median"])) < 1e-12
assert v["wins"].endswith("/3") and 0.0 <= float(v["p"]) <= 1.0
print("knob study table: 5 rows, medians equal SQLite's, ratio", v["ratio"])
PY
# a part without shared episodes ran in pieces of one run each (--shard I/N), each leaving its own
# CSV; gd's seeds share episodes, so the reference part (random, gd, cmaes) ran whole
/usr/bin/python3 - "$work" <<'PY'
import csv, glob, sqlite3, sys
work = sys.argv[1]
pieces = sorted(glob.glob(f"{work}/parts/sphere-10__rand-descents@*of*.csv"))
assert len(pieces) == 3, pieces
seeds = sorted(int(r["seed"]) for p in pieces for r in csv.DictReader(open(p)))
assert seeds == [0, 1, 2], (pieces, seeds)
for p in pieces:
    assert len(list(csv.DictReader(open(p)))) == 1, p
whole = list(csv.DictReader(open(f"{work}/parts/sphere-10__reference.csv")))
assert sorted((r["optimizer"], int(r["seed"])) for r in whole) == sorted(
    (o, s) for o in ("cmaes", "gd", "random") for s in range(3)), whole
print("pieces: rand-descents in 3 one-run pieces, the reference part whole")
PY
# every finished part left its runs as CSV; a study whose OUTDIR was lost takes them as landed
# data (STUDY_LANDED) and runs nothing, with the same table
ls "$work"/parts/*.csv >/dev/null
STUDY_LANDED=$work/parts "$src/scripts/knob-study.sh" "$work/again" --envs sphere-10 --seeds 3 \
  --only '^(reference|rand-descents(\.start_scale=0\.1)?)$' "$build" >"$work/again.log"
grep -q "landed: sphere-10 reference" "$work/again.log"
if compgen -G "$work/again/parts/*.sqlite" >/dev/null; then echo "a landed part was run again" >&2; exit 1; fi
cmp "$work/knob_study.csv" "$work/again/knob_study.csv"
# a landed part made by another binary is refused, naming the file
mkdir "$work/other"
sed '2,$s/git [0-9a-f]*/git 000000000000/' "$work/parts/sphere-10__reference.csv" >"$work/other/sphere-10__reference.csv"
set +e
STUDY_LANDED=$work/other "$src/scripts/knob-study.sh" "$work/third" --envs sphere-10 --seeds 3 --only '^reference$' \
  "$build" >/dev/null 2>"$work/third.err"
code=$?
set -e
[[ $code == 2 ]] || { echo "expected exit 2 for another binary's part, got $code" >&2; exit 1; }
grep -q "sphere-10__reference.csv was made by" "$work/third.err" || { cat "$work/third.err" >&2; exit 1; }
echo "landed parts: taken without running, the same table; another binary's refused"
# landing: new parts are copied, landed ones left alone, a differing one refused without copying
mkdir "$work/landed"
"$src/scripts/land-study-parts.sh" "$work" "$work/landed" >"$work/land.log"
for f in "$work"/parts/*.csv; do cmp "$f" "$work/landed/$(basename "$f")"; done
"$src/scripts/land-study-parts.sh" "$work" "$work/landed" | grep -q "0 new part(s)"
echo "changed" >>"$work/landed/sphere-10__reference.csv"
piece=$(basename "$(ls "$work"/landed/sphere-10__rand-descents@*.csv | head -1)")
rm "$work/landed/$piece"
set +e
"$src/scripts/land-study-parts.sh" "$work" "$work/landed" >/dev/null 2>"$work/land.err"
code=$?
set -e
[[ $code == 2 ]] || { echo "expected exit 2 for a differing landed part, got $code" >&2; exit 1; }
grep -q "sphere-10__reference.csv differs" "$work/land.err" || { cat "$work/land.err" >&2; exit 1; }
[[ ! -e $work/landed/$piece ]] || { echo "copied despite the refusal" >&2; exit 1; }
echo "landing: new parts copied, a differing landed part refused"
# --table runs nothing: the table from the landed parts alone, naming the parts it left out
STUDY_LANDED=$work/parts "$src/scripts/knob-study.sh" "$work/table" --envs sphere-10 --seeds 3 \
  --only '^(reference|rand-descents(\.start_scale=0\.(1|5))?)$' --table "$build" >"$work/table.log"
grep -q "not landed, left out: sphere-10 rand-descents.start_scale=0.5 piece" "$work/table.log" ||
  { cat "$work/table.log" >&2; exit 1; }
if compgen -G "$work/table/parts/*.sqlite" >/dev/null || [[ -e $work/table/knob-study.sqlite ]]; then
  echo "--table ran a part or merged" >&2; exit 1
fi
cmp "$work/knob_study.csv" "$work/table/knob_study.csv"
echo "--table: nothing run, the same table, the part not landed named"
# a variant of a reference optimizer (boleap-study's rand-descents.leap_descents) leaves the plain
# one named "default", not by its hash
"$src/scripts/boleap-study.sh" "$work/bl" --envs sphere-10 --seeds 2 --only '^(reference|rand-descents\.leap_descents)$' \
  "$build" >/dev/null
/usr/bin/python3 - "$work/bl/boleap_study.csv" <<'PY'
import csv, sys
rows = {(r["optimizer"], r["variant"]): r for r in csv.DictReader(open(sys.argv[1]))}
assert set(rows) == {(o, "default") for o in ("random", "gd", "cmaes", "rand-descents")} | {
    ("rand-descents", "leap_descents")}, sorted(rows)
v, base = rows[("rand-descents", "leap_descents")], rows[("rand-descents", "default")]
assert abs(float(v["ratio"]) - float(v["median"]) / float(base["median"])) < 1e-12, v
print("a reference optimizer's variant: rows", sorted(rows))
PY
