#!/usr/bin/env bash
# BO-Leap's local search read the ways the paper allows (issue 28): one knob at a time around the
# defaults, on the envs where the paper makes BO-Leap claims and a 1,000-episode grid is affordable
# here (cartpole1, cartpole3) plus rastrigin-10, 5 seeds each, with cmaes, rand-descents, gd and
# random beside them, and an ablation that isolates the leap.
#
#   scripts/boleap-study.sh OUTDIR [--envs E1,E2] [--seeds N] [--only REGEX] [--jobs J] [BUILD_DIR]
#
# Runs part by part (scripts/lib/variant-study.sh), merged into OUTDIR/boleap-study.sqlite; the table
# OUTDIR/boleap_study.csv gives each variant's median, quartiles, Mann-Whitney p against the
# default and against cmaes, and BO-Leap's diagnostics (leaps, descents, steps, stale stops per run).
# Interrupted? Run the same command again: every part resumes.
#
# Variants, each moving one knob from the base (the defaults at the study's start, set explicitly so
# the study means the same whatever a later binary's defaults are): sigma0 0.3 in the normalized
# box, J (max_descent_steps) 10, patience 3 (more than 3 non-improving steps stop a descent), Adam
# lr 0.03 with a fresh state per descent, K 10, a leap of 100 episodes.
#   sigma0 0.03, 0.1           the paper's sigma_1 = 1.0 in physical units would be 0.033-0.2 here
#   J 30, 100                  the paper does not give J
#   leap_iterations=100        the leap as 100 local iterations (one leap in 1,000 episodes)
#   plain_steps                the paper's plain clipped gradient step, at gd's lr (0.1)
#   adam_per_leap              one Adam state across a leap's descents
#   ablation                   K = 1 (no search distribution: each leap is one descent from the
#                              LCB point), against rand-descents (the same descents from uniform
#                              random starts)
#   rand-descents.leap_descents  the ablation's control (added 2026-12-02, after the ablation ran on
#                              rastrigin-10 and cartpole1): rand-descents with the leap's descents,
#                              at most 10 Adam steps, stopped after more than 3 non-improving steps
#                              (max_steps 10, patience 4, min_improvement 0), so that the ablation and
#                              it differ only in where a descent starts: BO's LCB point or a uniform
#                              random one. Plain rand-descents' descents are up to 100 steps with
#                              patience 10, so against it the ablation also differs in descent length.
# and, once the single moves are in, "pair": the two single moves on different knobs with the best
# mean rank combined (set by PAIR_FLAGS in the environment; without it the pair is not run).
#
# The rule that picks BO-Leap's defaults, stated before the study ran: among the default, the
# single moves and the pair (not the ablation), the variant with the best mean rank of its median
# final best loss over cartpole1, cartpole3 and rastrigin-10 (rank 1 = lowest median per env);
# a tie goes to the paper's reading (plain steps over Adam, a leap in episodes over iterations,
# the smaller change from the base). scripts/boleap_study_choice.py applies it to the table, and
# names PAIR_FLAGS from the single moves:
#   python3 scripts/boleap_study_choice.py OUTDIR/boleap_study.csv
set -euo pipefail
study=boleap-study
envs="rastrigin-10,cartpole1,cartpole3"

budget_of() { echo 1000; }

# the base's --set flags with KEY=VALUE pairs replacing or adding to them (the harness refuses a
# knob set twice)
declare -A base=([sigma0]=0.3 [max_descent_steps]=10 [patience]=3 [lr]=0.03)
with() {
  declare -A knobs
  local k kv
  for k in "${!base[@]}"; do knobs[$k]=${base[$k]}; done
  for kv in "$@"; do knobs[${kv%%=*}]=${kv#*=}; done
  for k in $(printf '%s\n' "${!knobs[@]}" | sort); do printf -- '--set boleap.%s=%s ' "$k" "${knobs[$k]}"; done
}
variants=(
  "reference|random,gd,cmaes,rand-descents|"
  "boleap|boleap|$(with)"
  "boleap.sigma0=0.03|boleap|$(with sigma0=0.03)"
  "boleap.sigma0=0.1|boleap|$(with sigma0=0.1)"
  "boleap.max_descent_steps=30|boleap|$(with max_descent_steps=30)"
  "boleap.max_descent_steps=100|boleap|$(with max_descent_steps=100)"
  "boleap.leap_iterations=100|boleap|$(with leap_iterations=100)"
  "boleap.plain_steps|boleap|$(with plain_steps=true step_size=0.1)"
  "boleap.adam_per_leap|boleap|$(with adam_per_leap=true)"
  "boleap.ablation|boleap|$(with population=1)"
  "rand-descents.leap_descents|rand-descents|--set rand-descents.max_steps=10 --set rand-descents.patience=4 --set rand-descents.min_improvement=0"
)
# PAIR_FLAGS: KEY=VALUE pairs, e.g. PAIR_FLAGS="sigma0=0.1 max_descent_steps=30"
# shellcheck disable=SC2086
[[ -n ${PAIR_FLAGS:-} ]] && variants+=("boleap.pair|boleap|$(with $PAIR_FLAGS)")

# cheapest first: rastrigin-10, then the 200-D cartpole1, then the 400-D cartpole3; the ablation
# last (a GP refit after each of its ~10-episode leaps, about 100 a run, is most of the study's time)
cost_rank() {
  case $2:$1 in
    *ablation:*) echo 3 ;;
    *:rastrigin-10) echo 0 ;;
    *:cartpole1) echo 1 ;;
    *) echo 2 ;;
  esac
}

# shellcheck source=scripts/lib/variant-study.sh
source "$(dirname "$0")/lib/variant-study.sh"
variant_study "$@"
