#!/usr/bin/env bash
# The published archive holds every published run's losses, each repeating its published final
# best loss bit for bit (fluid's curves may be missing until its rerun), and docs/results.md's
# archive table is this archive's; a table one byte off is caught.
set -euo pipefail
src=$1
cd "$src"
csvs=(data/study/runs.csv data/study/*/*.csv)
/usr/bin/python3 scripts/archive_runs.py check data/study --against "${csvs[@]}" --allow-missing --agree docs/results.md
work=$(mktemp -d); trap 'rm -rf "$work"' EXIT
sed 's/^| all | \([0-9]*\) |/| all | 1\1 |/' docs/results.md > "$work/results.md"
cmp -s docs/results.md "$work/results.md" && { echo "the table's total line was not found" >&2; exit 1; }
if /usr/bin/python3 scripts/archive_runs.py check data/study --against "${csvs[@]}" --allow-missing \
     --agree "$work/results.md" > "$work/out" 2>&1; then
  echo "a wrong archive table passed" >&2; exit 1
fi
grep -q "is not this archive's" "$work/out" || { cat "$work/out" >&2; exit 1; }
echo "archive table agrees; a wrong one is caught"
