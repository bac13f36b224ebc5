#!/usr/bin/env bash
# The README's quick-start test command and the command in .ci/run must be the same line, so CI
# proves the set-up a user follows. Exit 1 with both lines shown when they differ.
set -euo pipefail
root=${1:?usage: check_readme_ci.sh SOURCE_DIR}
readme_cmd=$(grep -m1 -E '^scripts/install-deps.sh .*ctest' "$root/README.md" || true)
ci_cmd=$(grep -m1 -E '^scripts/install-deps.sh .*ctest' "$root/.ci/run" || true)
if [[ -z "$readme_cmd" || "$readme_cmd" != "$ci_cmd" ]]; then
  echo "README test command: ${readme_cmd:-<missing>}"
  echo ".ci/run command:     ${ci_cmd:-<missing>}"
  echo "1 failed: README and .ci/run disagree"
  exit 1
fi
main_cmd=$(grep -m1 -E '^scripts/install-deps.sh .*harness --all --seeds 5' "$root/README.md" || true)
if [[ -z "$main_cmd" ]]; then
  echo "README has no main-job command ending in 'harness --all --seeds 5'"
  exit 1
fi
echo "README and .ci/run agree: $ci_cmd"
