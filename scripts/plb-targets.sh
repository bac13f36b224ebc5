#!/usr/bin/env bash
# The PlasticineLab tasks' targets (data/targets/plb-*.txt.gz): each task's scripted reference
# motion (envs/mpm/plb_tasks.cpp) simulated by our engine, its final grid mass stored (scaled to the
# mass of 10,000 particles, as PlasticineLab's targets hold).
#   scripts/plb-targets.sh regenerate [BUILD_DIR]   rewrite data/targets (prints each target's bounding
#                                                   box and centre of mass beside PlasticineLab's)
#   scripts/plb-targets.sh check [BUILD_DIR]        generate afresh and compare with the stored files
#                                                   (decoded values, bit for bit; exit 1 on a difference)
#   scripts/plb-targets.sh figures [BUILD_DIR]      the stored targets against PlasticineLab's figures (centre
#                                                   of mass, box of the cells above 1% of the max, mass) as
#                                                   the Markdown table of docs/plasticinelab.md
#   scripts/plb-targets.sh pictures [BUILD_DIR]     draw each stored target (harness render --target) as
#                                                   docs/img/plb-targets/plb-NAME.png (rewrites them)
#   scripts/plb-targets.sh compare DIR [BUILD_DIR]  our stored targets beside PlasticineLab's own .npy
#                                                   files, task by task: bounding box and centre of mass,
#                                                   mass, overlap (IoU of nodes above 1e-4); DIR is a
#                                                   PlasticineLab checkout (its plb/envs/assets is read)
#                                                   or a folder holding its files (Pinch3D-v1.npy etc.)
# A change to the engine or a task that moves a target regenerates them in the same commit.
set -euo pipefail
mode=${1:?usage: plb-targets.sh regenerate|check|figures|pictures [BUILD_DIR] | compare DIR [BUILD_DIR]}
root=$(cd "$(dirname "$0")/.." && pwd)
if [ "$mode" = compare ]; then
  dir=${2:?usage: plb-targets.sh compare DIR [BUILD_DIR]}
  build=$(cd "${3:-$root/build}" && pwd)
  [ -d "$dir" ] || { echo "plb-targets.sh: $dir is not a folder" >&2; exit 2; }
  assets=$dir
  [ -d "$dir/plb/envs/assets" ] && assets=$dir/plb/envs/assets
  exec "$build/bin/plb_targets" --compare "$assets"
fi
build=$(cd "${2:-$root/build}" && pwd)
case $mode in
  regenerate) mkdir -p "$root/data/targets" && exec "$build/bin/plb_targets" --out "$root/data/targets" ;;
  check) exec "$build/bin/plb_targets" --check "$root/data/targets" ;;
  figures) exec "$build/bin/plb_targets" --figures "$root/data/targets" ;;
  pictures)
    mkdir -p "$root/docs/img/plb-targets"
    for task in assembly pinch rollingpin rope table torus triplemove writer; do
      "$build/bin/harness" render --env "plb-$task" --target --width 240 --force \
        --out "$root/docs/img/plb-targets/plb-$task.png"
    done ;;
  *) echo "plb-targets.sh: unknown mode '$mode' (regenerate, check, figures, pictures or compare)" >&2; exit 2 ;;
esac
