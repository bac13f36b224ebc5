#!/usr/bin/env bash
# Landscape gallery: `harness landscape` over every env of `harness list`, one CSV per 2-D slice,
# named OUTDIR/<variant>_<i>_<j>.csv for `harness report --landscapes OUTDIR` (its gallery.html shows
# them side by side with the gradient quality table; docs/gradient-quality.md "Landscape gallery").
#   scripts/landscape-gallery.sh OUTDIR [--build BUILD_DIR] [--envs NAME,NAME] [--res N] [--list]
# --build: the build folder (default: build/ of this source tree); --envs: only these envs of
# `harness list`; --res: N x N points for every slice instead of the table's (a quick look, the test);
# --list: print the plan (env, variant, res, dims) and run nothing.
# The slice goes through the box centre (the other coordinates 0) over [-1, 1]^2 in the two dims;
# one process at a time, one thread; the time of each slice goes to stderr.
#
# Which slices (dims as the seed's Figures 8-15 where it gives them, else the first two dims) and
# at which resolution (the particle envs at their 5-env-step variants and a coarse grid, so that the
# whole gallery takes 12 to 18 minutes on one core: 706 s of CPU measured; docs/gradient-quality.md "Landscape gallery"):
#
#   env                     variant            dims (i,j)          res   why
#   pinball-1x2             pinball-1x2        0,1                 61    seed Fig. 9 left
#   pinball-4x4             pinball-4x4        13,14               61    seed Fig. 9 right (the two centre paddles of the bottom row)
#   bounce                  bounce             0,1                 61    seed Fig. 8: X and Y initial speeds
#   fluid                   fluid-h5           0,1  6,8  8,9       9     seed Fig. 10; 0.4 s per point
#   plb-assembly            plb-assembly-h5    0,1  1,2  4,5       6     seed Fig. 11; about 1.5 s per point
#   plb-table               plb-table-h5       0,2  2,5  12,13     6     seed Fig. 12 (its 30-D is our 15-D: dims 12, 13 exist)
#   plb-triplemove          plb-triplemove-h5  0,1  1,2  3,5       6     seed Fig. 13
#   plb-writer              plb-writer-h5      0,3  1,4  2,5       6     seed Fig. 14
#   plb-pinch, -rollingpin, plb-NAME-h5        0,1                 6     not in the seed: the first two dims
#     -rope, -torus
#   flip                    flip               0,1  0,2  1,2       21    seed Fig. 15; 0.03 s per point
#   swing-* (six)           swing-*            0,1                 21    not in the seed; 0.02 s per point
#   cartpole1, cartpole3    cartpole*          0,1                 41    not in the seed (cart speed and torque of step 0)
#   synthetic (seven)       NAME               0,1                 61    not in the seed; analytic, instant
set -euo pipefail
usage="usage: landscape-gallery.sh OUTDIR [--build BUILD_DIR] [--envs NAME,NAME] [--res N] [--list]"
out=${1:?$usage}
shift
root=$(cd "$(dirname "$0")/.." && pwd)
build=$root/build only="" res_all="" list=0
while (($#)); do
  case $1 in
    --build) build=${2:?$usage}; shift 2 ;;
    --envs) only=${2:?$usage}; shift 2 ;;
    --res) res_all=${2:?$usage}; shift 2 ;;
    --list) list=1; shift ;;
    *) echo "landscape-gallery.sh: unknown argument '$1'" >&2; echo "$usage" >&2; exit 2 ;;
  esac
done
harness=$build/bin/harness
[[ -x $harness ]] || { echo "landscape-gallery.sh: no harness at '$harness' (--build DIR)" >&2; exit 2; }
((list)) || mkdir -p "$out"

# the env table of `harness list`: the rows between the header and the first blank line
# (awk reads to the end: an early exit would leave the harness writing into a closed pipe)
mapfile -t envs < <("$harness" list | awk 'NR == 1 || done { next } /^$/ { done = 1; next } { print $1 }')
((${#envs[@]} > 0)) || { echo "landscape-gallery.sh: '$harness list' printed no env" >&2; exit 2; }
if [[ -n $only ]]; then
  IFS=, read -ra wanted <<< "$only"
  for w in "${wanted[@]}"; do
    # a loop, not `printf | grep -q`: grep -q exits at the first match and, under pipefail, the
    # printf it leaves writing into a closed pipe (SIGPIPE) failed the check now and then
    known=0
    for e in "${envs[@]}"; do [[ $e == "$w" ]] && known=1; done
    ((known)) || { echo "landscape-gallery.sh: --envs: '$w' is not an env of 'harness list'" >&2; exit 2; }
  done
  envs=("${wanted[@]}")
fi

# the table above, as "variant res dims..." for one env
plan() {
  case $1 in
    pinball-1x2) echo "$1 61 0,1" ;;
    pinball-4x4) echo "$1 61 13,14" ;;
    bounce) echo "$1 61 0,1" ;;
    fluid) echo "fluid-h5 9 0,1 6,8 8,9" ;;
    plb-assembly) echo "$1-h5 6 0,1 1,2 4,5" ;;
    plb-table) echo "$1-h5 6 0,2 2,5 12,13" ;;
    plb-triplemove) echo "$1-h5 6 0,1 1,2 3,5" ;;
    plb-writer) echo "$1-h5 6 0,3 1,4 2,5" ;;
    plb-*) echo "$1-h5 6 0,1" ;;
    flip) echo "$1 21 0,1 0,2 1,2" ;;
    swing-*) echo "$1 21 0,1" ;;
    cartpole*) echo "$1 41 0,1" ;;
    *) echo "$1 61 0,1" ;;
  esac
}

start=$(date +%s)
slices=0
((list)) && echo "env variant res dims..."
for env in "${envs[@]}"; do
  read -r variant res dims <<< "$(plan "$env")"
  [[ -n $res_all ]] && res=$res_all
  if ((list)); then
    echo "$env $variant $res $dims"
    continue
  fi
  for d in $dims; do
    t0=$(date +%s.%N)
    file=$out/${variant}_${d/,/_}.csv
    "$harness" landscape --env "$variant" --dims "$d" --res "$res" --force --out "$file" 2>/dev/null ||
      { echo "landscape-gallery.sh: harness landscape --env $variant --dims $d failed" >&2; exit 1; }
    printf 'landscape-gallery: %-24s %-20s dims %-6s %3d x %-3d %8.1f s\n' "$env" "$variant" "$d" \
      "$res" "$res" "$(echo "$(date +%s.%N) - $t0" | bc)" >&2
    slices=$((slices + 1))
  done
done
((list)) && exit 0
echo "landscape-gallery: $slices slices of ${#envs[@]} envs in $(($(date +%s) - start)) s -> $out" \
  "(show them: harness report --db FILE --landscapes $out, then open gallery.html)" >&2
