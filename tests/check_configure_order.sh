#!/usr/bin/env bash
# The README's two quick-start commands configure one build folder: the main job's without tests,
# then the test command's with them. Run in that order in one clone, the second must give the
# tests what they need (DSB_FAULT_INJECTION, which an option cached OFF by the first would keep
# off: the interruption tests then fail). Configures a scratch folder with the README's own cmake
# configure steps, in order, and checks the cache. Exit 1 naming what is wrong.
set -euo pipefail
root=$(cd "${1:?usage: check_configure_order.sh SOURCE_DIR}" && pwd)
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
# the `cmake -S . -B build ...` step of a README command, with the scratch folder for build/
configure_step() {
  local line
  line=$(grep -m1 -E "$1" "$root/README.md" || true)
  [[ -n $line ]] || { echo "README has no command matching '$1'"; exit 1; }
  sed -n 's/.*&& \(cmake -S \. -B build [^&]*\) &&.*/\1/p' <<<"$line" | sed 's/ *$//'
}
main_step=$(configure_step '^scripts/install-deps.sh .*harness --all --seeds 5')
test_step=$(configure_step '^scripts/install-deps.sh .*ctest')
for step in "$main_step" "$test_step"; do
  [[ $step == "cmake -S . -B build"* ]] || { echo "cannot find the cmake configure step in: $step"; exit 1; }
  echo "+ $step"
  read -r -a args <<<"${step#cmake -S . -B build}"
  (cd "$root" && cmake -S . -B "$tmp/build" "${args[@]}" >"$tmp/log" 2>&1) || { cat "$tmp/log"; echo "configure failed: $step"; exit 1; }
done
bad=0
for want in DSB_BUILD_TESTS:BOOL=ON DSB_FAULT_INJECTION:BOOL=ON; do
  grep -qx "$want" "$tmp/build/CMakeCache.txt" || { echo "after both configure steps, the cache lacks $want: $(grep "^${want%%:*}:" "$tmp/build/CMakeCache.txt")"; bad=1; }
done
((bad == 0)) || { echo "1 failed: the README's test command, after its main job, builds tests without what they need"; exit 1; }
echo "the README's configure steps in order give a build with tests and fault injection"
