#!/usr/bin/env bash
# The published archive holds every published run's losses, each repeating its published final
# best loss bit for bit (a published run missing from it fails), and docs/results.md's
# archive table is this archive's, with how many of its runs this harness's results versions made;
# a table one byte off is caught, and so is a run whose versions are not this harness's: the table
# then counts it apart and names why.
set -euo pipefail
src=$1
harness=$2
cd "$src"
csvs=(data/study/runs.csv data/study/*/*.csv)
/usr/bin/python3 scripts/archive_runs.py check data/study --against "${csvs[@]}" \
  --harness "$harness" --agree docs/results.md
work=$(mktemp -d); trap 'rm -rf "$work"' EXIT

# an archive that lost one published run's file
cp -r data/study "$work/lost"
lost_file=$(ls "$work"/lost/fluid/*.runs.jsonl.gz | tail -n 1)
rm "$lost_file"
if (cd "$work" && /usr/bin/python3 "$src/scripts/archive_runs.py" check lost \
      --against "$src"/data/study/runs.csv "$src"/data/study/*/*.csv) > "$work/out" 2>&1; then
  echo "an archive missing '$(basename "$lost_file")' passed" >&2; exit 1
fi
grep -q "published in '.*' but not archived" "$work/out" || { cat "$work/out" >&2; exit 1; }
rm -rf "$work/lost"

sed 's/^| all | \([0-9]*\) |/| all | 1\1 |/' docs/results.md > "$work/results.md"
cmp -s docs/results.md "$work/results.md" && { echo "the table's total line was not found" >&2; exit 1; }
if /usr/bin/python3 scripts/archive_runs.py check data/study --against "${csvs[@]}" \
     --harness "$harness" --agree "$work/results.md" > "$work/out" 2>&1; then
  echo "a wrong archive table passed" >&2; exit 1
fi
grep -q "is not this archive's" "$work/out" || { cat "$work/out" >&2; exit 1; }

# an archive whose plb-pinch runs of one file name an older env version than this harness's
cp -r data/study "$work/study"
stale_file=$(ls "$work"/study/plb-pinch/*.runs.jsonl.gz | head -n 1)
/usr/bin/python3 - "$stale_file" <<'PY'
import gzip, json, re, sys
path = sys.argv[1]
with gzip.open(path, "rt", encoding="utf-8") as f:
    runs = [json.loads(line) for line in f.read().splitlines()]
for r in runs:
    e = int(re.match(r"env ([0-9]+),", r["results_versions"]).group(1))
    r["results_versions"] = re.sub(r"^env [0-9]+,", f"env {e - 1},", r["results_versions"])
with gzip.open(path, "wt", encoding="utf-8") as f:
    f.write("".join(json.dumps(r) + "\n" for r in runs))
PY
stale_runs=$(/usr/bin/python3 -c "import gzip,sys; print(len(gzip.open(sys.argv[1]).read().splitlines()))" "$stale_file")
cp docs/results.md "$work/stale.md"
(cd "$work" && /usr/bin/python3 "$src/scripts/archive_runs.py" check study \
   --against "$src"/data/study/runs.csv "$src"/data/study/*/*.csv --harness "$harness" \
   --update stale.md) > "$work/out" 2>&1 || { cat "$work/out" >&2; exit 1; }
grep -q "^archive_runs: $stale_runs of the archived published runs are stale" "$work/out" || { cat "$work/out" >&2; exit 1; }
row=$(grep '^| `[^|]*plb-pinch/` |' "$work/stale.md")
archived=$(echo "$row" | awk -F'|' '{gsub(/ /, "", $4); print $4}')
[[ $(echo "$row" | awk -F'|' '{print $5}') == " $((archived - stale_runs)) (stale: env plb-pinch version "*", this binary's "*")"* ]] || {
  echo "the stale plb-pinch runs are not counted apart with their reason: $row (want $archived - $stale_runs current)" >&2
  exit 1; }
echo "archive table agrees; a missing run and a wrong table are caught; a stale archived run is counted apart with its reason"
