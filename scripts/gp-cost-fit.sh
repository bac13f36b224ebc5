#!/usr/bin/env bash
# The GP cost model's constants (optimizers/bo/gp_cost.hpp: kBoSecondsPerN3, kBoSecondsPerN2D,
# kBoSecondsPerLcbTerm) refitted to what this binary's GP optimizers spend on this machine.
#   scripts/gp-cost-fit.sh BUILD_DIR DB OUT.csv
# Runs bo and boleap on sphere-10, rastrigin-10 and cartpole1, seed 0, at 1,000 and at 200
# episodes, into DB, one run at a time (resumable: the same command goes on where it stopped).
# A run's own time is its wall seconds less its episodes' (evals.wall_s: the simulation alone);
# what the plan's model must give is the own time of the 1,000-episode run beyond the 200-episode
# run's (a plan carries a probe's 200 measured episodes to the budget by the model's growth:
# harness/plan/cost_model.cpp). scripts/gp_cost_fit.py fits the three constants to those six numbers
# (least squares in log, the model's schedules of optimizers/bo/gp_cost.cpp) and writes
# OUT.csv: env,optimizer,dim,fits (the 1,000-episode run's GP fits, its diagnostics),model_fits (the
# model's schedule),own_200_s,own_1000_s,growth_s,model_s,ratio.
set -euo pipefail
usage="usage: gp-cost-fit.sh BUILD_DIR DB OUT.csv"
build=$(cd "${1:?$usage}" && pwd)
db=${2:?$usage}
out=${3:?$usage}
harness=$build/bin/harness
[[ -x $harness ]] || { echo "gp-cost-fit: no harness at $harness" >&2; exit 2; }
# a grid exits 3 when some of its runs failed: they are results, not a crash
grid() { "$@" || (($? == 3)); }
for budget in 200 1000; do
  grid "$harness" --env sphere-10,rastrigin-10,cartpole1 --optimizer bo,boleap --seeds 1 --budget "$budget" \
    --jobs 1 --quiet --db "$db"
done
/usr/bin/python3 "$(dirname "$0")/gp_cost_fit.py" "$db" "$out"
