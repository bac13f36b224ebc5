#!/usr/bin/env bash
# Gradient quality per env: `harness gradcheck` over every env of `harness list`, one CSV row each
# (scripts/gradient_quality_csv.py writes the rows; definitions in docs/gradient-quality.md "Gradient quality").
#   scripts/gradient-quality.sh BUILD_DIR OUT.csv [--points N] [--particle-points M] [--seed S]
# Points uniform in [-0.5, 0.5]^d from --seed (default 0); N points per env (default 50), M per
# particle env (default 3). The particle envs (fluid, plb-NAME: minutes per gradient at 50 env
# steps) are surveyed at their short-horizon variants fluid-h5 and plb-NAME-h5 (5 env steps of 50);
# cloth, rigid and synthetic envs at their full horizon. Central differences at the default step
# (1e-6, tolerance 1e-4) and the large-step check along the gradient at H = 0.05. One process at a
# time, one thread; the CSV is the same bits on any x86-64 (the project's determinism rules); the
# time per env goes to stderr.
set -euo pipefail
usage="usage: gradient-quality.sh BUILD_DIR OUT.csv [--points N] [--particle-points M] [--seed S]"
build=$(cd "${1:?$usage}" && pwd)
out=${2:?$usage}
shift 2
points=50 particle_points=3 seed=0
while (($#)); do
  case $1 in
    --points) points=${2:?$usage}; shift 2 ;;
    --particle-points) particle_points=${2:?$usage}; shift 2 ;;
    --seed) seed=${2:?$usage}; shift 2 ;;
    *) echo "gradient-quality.sh: unknown argument '$1'" >&2; echo "$usage" >&2; exit 2 ;;
  esac
done
root=$(cd "$(dirname "$0")/.." && pwd)
harness=$build/bin/harness
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

# the env table of `harness list`: the rows between the header and the first blank line
# (awk reads to the end: an early exit would leave the harness writing into a closed pipe)
mapfile -t envs < <("$harness" list | awk 'NR == 1 || done { next } /^$/ { done = 1; next } { print $1 }')
((${#envs[@]} > 0)) || { echo "gradient-quality.sh: '$harness list' printed no env" >&2; exit 2; }

start=$(date +%s)
jsons=()
for env in "${envs[@]}"; do
  surveyed=$env n=$points
  case $env in
    fluid | plb-*) surveyed=$env-h5 n=$particle_points ;;
  esac
  t0=$(date +%s.%N)
  # exit 1 (some point disagrees) is a result here, not an error
  rc=0
  "$harness" gradcheck --env "$surveyed" --points "$n" --seed "$seed" --large-step 0.05 --json \
    > "$work/$env.json" || rc=$?
  ((rc <= 1)) || { echo "gradient-quality.sh: gradcheck of $surveyed exited $rc" >&2; exit 1; }
  printf 'gradient-quality: %-24s %-26s %4d points %8.1f s\n' "$env" "$surveyed" "$n" \
    "$(echo "$(date +%s.%N) - $t0" | bc)" >&2
  jsons+=("$env=$work/$env.json")
done
/usr/bin/python3 "$root/scripts/gradient_quality_csv.py" "$out" "${jsons[@]}"
echo "gradient-quality: ${#envs[@]} envs in $(($(date +%s) - start)) s -> $out" >&2
