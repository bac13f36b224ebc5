#!/usr/bin/env bash
# scripts/check-format.sh shown working: a file in the repository's style passes, one that
# clang-format would change fails naming it (exit 1), and the two together fail with one named.
#   tests/check_format_test.sh SOURCE_DIR
set -uo pipefail
root=${1:?usage: check_format_test.sh SOURCE_DIR}
command -v "${CLANG_FORMAT:-clang-format}" >/dev/null || { echo "no clang-format: skipped"; exit 77; }
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
printf '// one line\nint twice(int x) { return 2 * x; }\n' >"$work/good.cpp"
printf 'int  twice(int x){\n      return 2*x;}\n' >"$work/bad.cpp"
failures=0
expect() {  # expect CODE WORDS FILE...: the exit code, and words the output must hold
  local code=$1 words=$2
  shift 2
  out=$("$root/scripts/check-format.sh" "$@" 2>&1)
  got=$?
  if [[ $got -eq $code && "$out" == *"$words"* ]]; then
    echo "ok   $* -> exit $got"
  else
    echo "FAIL $* -> exit $got (want $code and '$words'):"
    echo "$out"
    failures=$((failures + 1))
  fi
}
expect 0 "1 files formatted" "$work/good.cpp"
expect 1 "bad.cpp: not formatted" "$work/bad.cpp"
expect 1 "1 of 2 files not formatted" "$work/good.cpp" "$work/bad.cpp"
((failures == 0)) && echo "check_format_test: all passed" || echo "check_format_test: $failures failed"
exit $((failures > 0))
