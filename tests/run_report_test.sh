#!/usr/bin/env bash
# The report generator on a small real database made by the harness (Debian's system Python).
set -euo pipefail
build=${1:?usage: run_report_test.sh BUILD_DIR SOURCE_DIR}
src=${2:?usage: run_report_test.sh BUILD_DIR SOURCE_DIR}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
export DSB_HARNESS="$build/bin/harness"   # the generator's --harness in the test: `harness list`
"$build/bin/harness" --env sphere-2,branin --optimizer random,cmaes,gd --seeds 3 --budget 20 --quiet --db "$work/small.sqlite"
/usr/bin/python3 "$src/reports/test_make_report.py" "$work/small.sqlite"
