#!/usr/bin/env bash
# The PlasticineLab tasks' targets (data/targets/plb-*.txt.gz): each task's scripted reference
# motion (envs/mpm/plb_tasks.cpp) simulated by our engine, its final grid mass stored.
#   scripts/plb-targets.sh regenerate [BUILD_DIR]   rewrite data/targets (prints each target's bounding
#                                                   box and centre of mass beside PlasticineLab's)
#   scripts/plb-targets.sh check [BUILD_DIR]        generate afresh and compare with the stored files
#                                                   (decoded values, bit for bit; exit 1 on a difference)
# A change to the engine or a task that moves a target regenerates them in the same commit.
set -euo pipefail
mode=${1:?usage: plb-targets.sh regenerate|check [BUILD_DIR]}
root=$(cd "$(dirname "$0")/.." && pwd)
build=$(cd "${2:-$root/build}" && pwd)
case $mode in
  regenerate) mkdir -p "$root/data/targets" && exec "$build/bin/plb_targets" --out "$root/data/targets" ;;
  check) exec "$build/bin/plb_targets" --check "$root/data/targets" ;;
  *) echo "plb-targets.sh: unknown mode '$mode' (regenerate or check)" >&2; exit 2 ;;
esac
