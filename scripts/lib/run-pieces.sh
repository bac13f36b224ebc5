# shellcheck shell=bash
# Pieces of a grid that land one run at a time, for computations longer than a machine's life
# (sourced by scripts/lib/variant-study.sh and scripts/grid-in-pieces.sh).
#
# A piece is one of the harness's deterministic slices of a grid (`--shard I/N`, by run key: the
# same slice whatever else runs) that holds exactly one run. For a small grid (one env x one
# optimizer x a few seeds) the smallest N from its run count up to 64 that gives every run a
# slice of its own is found with `harness plan`, which builds no env and writes nothing (about
# 40 ms a call). A grid whose seeds share episodes (gd, the NLopt methods: a group's seeds fall in
# one slice, so that later seeds replay the first) has no such N and runs whole.

# grid_run_counts HARNESS PLAN_DB FLAGS...: "RUNS SHARING", the runs of the grid and how many of
# them take episodes from an earlier seed's run. PLAN_DB is a path the plan may read and never
# writes (a file that does not exist).
grid_run_counts() {
  local harness=$1 db=$2 plan
  shift 2
  plan=$("$harness" plan "$@" --db "$db")
  echo "$(sed -n 's/^plan: \([0-9]*\) runs in the grid.*/\1/p' <<<"$plan") $(sed -n 's/^ *sharing across seeds: \([0-9]*\) runs.*/\1/p' <<<"$plan")"
}

# grid_pieces HARNESS PLAN_DB FLAGS...: the slices "I/N" that hold one run each of the grid, one a
# line, or nothing when its seeds share episodes or no N up to 64 separates its runs
grid_pieces() {
  local harness=$1 db=$2 total sharing n i k pieces
  shift 2
  read -r total sharing < <(grid_run_counts "$harness" "$db" "$@")
  ((total > 1 && ${sharing:-0} == 0)) || return 0
  for ((n = total; n <= 64; n++)); do
    pieces=()
    for ((i = 0; i < n; i++)); do
      read -r k _ < <(grid_run_counts "$harness" "$db" "$@" --shard "$i/$n")
      ((k <= 1)) || continue 2
      ((k == 0)) || pieces+=("$i/$n")
    done
    printf '%s\n' "${pieces[@]}"
    return 0
  done
}
