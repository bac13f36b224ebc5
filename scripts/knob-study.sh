#!/usr/bin/env bash
# BO-Leap's and RandDescents' unstated knobs (issue 14 item 2): one knob at a time around the
# defaults, every variant over the same seeds (the per-run seed depends on env, optimizer and seed
# index only, so variants see the same random numbers), with random, gd and cmaes beside them.
#
#   scripts/knob-study.sh OUTDIR [--envs E1,E2] [--seeds N] [--only REGEX] [--jobs J] [BUILD_DIR]
#
# Each (env, variant) runs into OUTDIR/parts/ENV__VARIANT.sqlite (scripts/lib/variant-study.sh: one
# writer per file, J at once, cheapest first), merged into OUTDIR/knob-study.sqlite, and
# scripts/knob_study_table.py writes OUTDIR/knob_study.csv (median, quartiles, wins against the
# default per env and variant). Interrupted? Run the same command again: every part resumes.
#
# Envs and budgets (chosen here): cartpole1, cartpole3, rastrigin-10 at 1,000 episodes; the
# particle task is fluid-h10 (fluid at 10 env steps, 80 substeps, all 10 parameters active) at
# 200 episodes, because a 1,000-episode fluid run costs 45 min of a core.
#
# Variants (one knob moved from the study's base point; the base first). The base point is the
# defaults before this study, set explicitly so the study means the same whatever the binary's
# defaults are (the study moved them; the "default" rows of the table are this base):
#   boleap         sigma0 1 (sigma_1 relative to the normalized box, half-width 1), J
#                  (max_descent_steps) 10, Adam lr 0.1, elite K/2 = 5 of K = 10, 100 episodes per
#                  leap, patience 3
#   rand-descents  max_steps 100 episodes per descent, Adam lr 0.1, starts uniform in the box
#                  (start_scale 1), patience 10
# plus the pair the study chose as BO-Leap's default (sigma0 0.3 and lr 0.03; RandDescents' chosen
# default is its lr=0.03 variant).
set -euo pipefail
study=knob-study
envs="rastrigin-10,cartpole1,cartpole3,fluid-h10"

budget_of() { case $1 in fluid-h*) echo 200 ;; *) echo 1000 ;; esac; }

# label|optimizer|--set flags (every knob the study moves is set: base values unless varied)
bo_base="--set boleap.sigma0=1 --set boleap.lr=0.1"
rd_base="--set rand-descents.lr=0.1"
variants=(
  "reference|random,gd,cmaes|"
  "rand-descents|rand-descents|$rd_base"
  "rand-descents.max_steps=30|rand-descents|$rd_base --set rand-descents.max_steps=30"
  "rand-descents.max_steps=300|rand-descents|$rd_base --set rand-descents.max_steps=300"
  "rand-descents.lr=0.03|rand-descents|--set rand-descents.lr=0.03"
  "rand-descents.lr=0.3|rand-descents|--set rand-descents.lr=0.3"
  "rand-descents.start_scale=0.5|rand-descents|$rd_base --set rand-descents.start_scale=0.5"
  "rand-descents.start_scale=0.1|rand-descents|$rd_base --set rand-descents.start_scale=0.1"
  "boleap|boleap|$bo_base"
  "boleap.sigma0=0.3|boleap|--set boleap.sigma0=0.3 --set boleap.lr=0.1"
  "boleap.sigma0=0.1|boleap|--set boleap.sigma0=0.1 --set boleap.lr=0.1"
  "boleap.max_descent_steps=30|boleap|$bo_base --set boleap.max_descent_steps=30"
  "boleap.max_descent_steps=3|boleap|$bo_base --set boleap.max_descent_steps=3"
  "boleap.lr=0.03|boleap|--set boleap.sigma0=1 --set boleap.lr=0.03"
  "boleap.lr=0.3|boleap|--set boleap.sigma0=1 --set boleap.lr=0.3"
  "boleap.elite=2|boleap|$bo_base --set boleap.elite=2"
  "boleap.episodes_per_leap=300|boleap|$bo_base --set boleap.episodes_per_leap=300"
  "boleap.sigma0=0.3+lr=0.03|boleap|--set boleap.sigma0=0.3 --set boleap.lr=0.03"
)

# cheapest first: the cheap envs, then the particle task, then the 400-D and 200-D cartpoles'
# BO-Leap variants (their GP refits are most of the study's time)
cost_rank() {
  case $1:$2 in
    rastrigin-10:*) echo 0 ;;
    cartpole*:boleap*) echo 3 ;;
    cartpole*:*) echo 1 ;;
    *) echo 2 ;;
  esac
}

# shellcheck source=scripts/lib/variant-study.sh
source "$(dirname "$0")/lib/variant-study.sh"
variant_study "$@"
