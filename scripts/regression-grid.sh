#!/usr/bin/env bash
# The frozen regression grid of CI, covering every env of `harness --all` and every optimizer
# (docs/reports.md, "Regression CI on result tables"): 4 cheap envs x every registry optimizer x 2
# seeds x 30 episodes; the MPM engine's `fluid` at a 10-env-step horizon (fluid-h10, 80
# substeps) x random, gd, cmaes x 2 seeds x 5 episodes; two PlasticineLab tasks at 5 env steps
# (plb-pinch-h5, plb-writer-h5) x random, gd x 2 seeds x 3 episodes; two cloth tasks
# (swing-stiffness-corner, flip) x random, gd, cmaes, nlopt-lbfgs x 2 seeds x 10 episodes; the RL
# optimizers on cartpole1 (ppo x 2 seeds x 25 episodes: 2,500 decisions, one PPO update; sac x 2
# seeds x 3 episodes: 300 decisions, 200 gradient steps after its 100 random ones) and on
# cartpole3 (x 2 seeds x 3 episodes); every other env of --all (the particle ones at 5 env steps)
# x random, gd x 2 seeds x 3 episodes; and an external optimizer (tests/ext/test_optimizer.py
# random, run from the repository's root so that its command, in its config, names no absolute
# path) on sphere-10 and branin x 2 seeds x 6 episodes.
#   scripts/regression-grid.sh check [BUILD_DIR]       run the grid, compare with the baseline (exit 1 on any difference),
#                                                      then check that it covers every env and optimizer
#   scripts/regression-grid.sh regenerate [BUILD_DIR]  run the grid, rewrite data/baselines/small-grid.csv
#   scripts/regression-grid.sh coverage [BUILD_DIR]    only the coverage check of the stored baseline
# A change that alters results on purpose bumps the results version of what it changed and
# regenerates the baseline in the same commit, saying why.
set -euo pipefail
mode=${1:?usage: regression-grid.sh check|regenerate [BUILD_DIR]}
root=$(cd "$(dirname "$0")/.." && pwd)
build=$(cd "${2:-$root/build}" && pwd)
baseline=$root/data/baselines/small-grid.csv
# every env of `harness list` (a particle env as any NAME-hN) and every optimizer on at least two
# envs, ext: included, in the baseline; exit 1 naming what is missing
coverage() {
  "$build/bin/harness" list | /usr/bin/python3 "$root/scripts/regression_coverage.py" "$baseline"
}
case $mode in
  check | regenerate) ;;
  coverage) coverage; exit ;;
  *) echo "regression-grid.sh: unknown mode '$mode' (check, regenerate or coverage)" >&2; exit 2 ;;
esac
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
grid "$build/bin/harness" --env cartpole3 --optimizer ppo,sac --seeds 2 --budget 3 --jobs 2 --quiet --db "$work/grid.sqlite"
grid "$build/bin/harness" \
  --env cartpole3,pinball-1x2,pinball-4x4,bounce,swing-stiffness-single,swing-stiffness-mesh,swing-velocity-single,swing-velocity-corner,swing-velocity-mesh,plb-assembly-h5,plb-rollingpin-h5,plb-rope-h5,plb-table-h5,plb-torus-h5,plb-triplemove-h5,sphere-10,rastrigin-10,ackley-10,styblinski-10 \
  --optimizer random,gd --seeds 2 --budget 3 --jobs 2 --quiet --db "$work/grid.sqlite"
(cd "$root" && grid "$build/bin/harness" --env sphere-10,branin --optimizer ext:random \
  --ext "random=/usr/bin/python3 tests/ext/test_optimizer.py random" --seeds 2 --budget 6 --jobs 2 --quiet \
  --db "$work/grid.sqlite")

case $mode in
  check)
    "$build/bin/harness" check --db "$work/grid.sqlite" --baseline "$baseline"
    coverage ;;
  regenerate) exec "$build/bin/harness" export --db "$work/grid.sqlite" --force --out "$baseline" ;;
esac
