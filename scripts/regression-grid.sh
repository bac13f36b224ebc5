#!/usr/bin/env bash
# The frozen regression grid of CI: 4 cheap envs x every optimizer x 2 seeds x 30 episodes; the
# MPM engine's `fluid` at a 10-env-step horizon (fluid-h10, 80 substeps) x random, gd, cmaes x 2
# seeds x 5 episodes; and two PlasticineLab tasks at 5 env steps (plb-pinch-h5, plb-writer-h5) x
# random, gd x 2 seeds x 3 episodes; and two cloth tasks (swing-stiffness-corner, flip) x random,
# gd, cmaes, nlopt-lbfgs x 2 seeds x 10 episodes; and the RL optimizers on cartpole1 (ppo x 2
# seeds x 25 episodes: 2,500 decisions, one PPO update; sac x 2 seeds x 3 episodes: 300
# decisions, 200 gradient steps after its 100 random ones).
#   scripts/regression-grid.sh check [BUILD_DIR]       run the grid, compare with the baseline (exit 1 on any difference)
#   scripts/regression-grid.sh regenerate [BUILD_DIR]  run the grid, rewrite data/baselines/small-grid.csv
# A change that alters results on purpose regenerates the baseline in the same commit and says why.
set -euo pipefail
mode=${1:?usage: regression-grid.sh check|regenerate [BUILD_DIR]}
root=$(cd "$(dirname "$0")/.." && pwd)
build=$(cd "${2:-$root/build}" && pwd)
baseline=$root/data/baselines/small-grid.csv
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
# a grid exits 3 when some of its runs failed: they are results (rows of the table), not a crash
grid() { "$@" || (($? == 3)); }

grid "$build/bin/harness" \
  --env cartpole1,rosenbrock-10,branin,hartmann6 \
  --optimizer random,gd,rand-descents,cmaes,bo,boleap,nlopt-lbfgs,nlopt-bobyqa,nlopt-direct-l,nlopt-crs2 \
  --seeds 2 --budget 30 --jobs 2 --quiet --db "$work/grid.sqlite"
grid "$build/bin/harness" --env fluid-h10 --optimizer random,gd,cmaes \
  --seeds 2 --budget 5 --jobs 2 --quiet --db "$work/grid.sqlite"
grid "$build/bin/harness" --env plb-pinch-h5,plb-writer-h5 --optimizer random,gd \
  --seeds 2 --budget 3 --jobs 2 --quiet --db "$work/grid.sqlite"
grid "$build/bin/harness" --env swing-stiffness-corner,flip --optimizer random,gd,cmaes,nlopt-lbfgs \
  --seeds 2 --budget 10 --jobs 2 --quiet --db "$work/grid.sqlite"
grid "$build/bin/harness" --env cartpole1 --optimizer ppo --seeds 2 --budget 25 --jobs 2 --quiet --db "$work/grid.sqlite"
grid "$build/bin/harness" --env cartpole1 --optimizer sac --seeds 2 --budget 3 --jobs 2 --quiet --db "$work/grid.sqlite"

case $mode in
  check) exec "$build/bin/harness" check --db "$work/grid.sqlite" --baseline "$baseline" ;;
  regenerate) exec "$build/bin/harness" export --db "$work/grid.sqlite" --force --out "$baseline" ;;
  *) echo "regression-grid.sh: unknown mode '$mode' (check or regenerate)" >&2; exit 2 ;;
esac
