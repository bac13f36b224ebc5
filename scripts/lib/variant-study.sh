# shellcheck shell=bash
# The runner of the optimizer-variant studies (scripts/knob-study.sh, scripts/boleap-study.sh), sourced
# by them after they set:
#   study        the study's name (its database: OUTDIR/$study.sqlite, table OUTDIR/${study//-/_}.csv)
#   envs         default env list (comma-separated; --envs overrides)
#   variants     array of "label|optimizer list|--set flags" (label "reference" for plain optimizers)
#   budget_of    function ENV -> budget
#   cost_rank    function ENV LABEL -> a number; parts run cheapest first
# and then call `variant_study "$@"` with the script's arguments:
#   OUTDIR [--envs E1,E2] [--seeds N] [--only REGEX] [--jobs J] [BUILD_DIR]
# Each (env, variant) runs into OUTDIR/parts/ENV__LABEL.sqlite (one writer per file, J at once),
# then `harness merge` joins them into OUTDIR/$study.sqlite (variants differ by opt_config_hash;
# OUTDIR/variants.csv names each hash by its label) and scripts/knob_study_table.py writes the
# table. Variants see the same random numbers: a run's seed depends on env, optimizer and seed index
# only. Interrupted? Run the same command again: every part resumes.
variant_study() {
  local root out seeds=5 only='.' jobs=2 build
  root=$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)
  out=${1:?usage: $study OUTDIR [--envs E1,E2] [--seeds N] [--only REGEX] [--jobs J] [BUILD_DIR]}
  shift
  build=$root/build
  while (($#)); do
    case $1 in
      --envs) envs=$2; shift 2 ;;
      --seeds) seeds=$2; shift 2 ;;
      --only) only=$2; shift 2 ;;
      --jobs) jobs=$2; shift 2 ;;
      -*) echo "$study: unknown option '$1'" >&2; return 2 ;;
      *) build=$1; shift ;;
    esac
  done
  harness=$build/bin/harness
  [[ -x $harness ]] || { echo "$study: no harness at $harness" >&2; return 2; }
  mkdir -p "$out/parts"

  local parts=() env v label opt flags env_list
  IFS=, read -ra env_list <<<"$envs"
  for env in "${env_list[@]}"; do
    for v in "${variants[@]}"; do
      IFS='|' read -r label opt flags <<<"$v"
      [[ $label =~ $only ]] || continue
      parts+=("$(cost_rank "$env" "$label")|$env|$label|$opt|$flags")
    done
  done
  mapfile -t parts < <(printf '%s\n' "${parts[@]}" | sort -t'|' -k1,1n -s)
  echo "$study: ${#parts[@]} parts (env x variant), $seeds seeds, $jobs at once, into $out"

  export -f run_study_part budget_of
  export harness seeds out
  printf '%s\n' "${parts[@]}" | xargs -d '\n' -P "$jobs" -I{} bash -c 'run_study_part "$@"' _ {}

  rm -f "$out/$study.sqlite"
  "$harness" merge --into "$out/$study.sqlite" "$out"/parts/*.sqlite
  { echo "opt_config_hash,variant"; study_labels; } >"$out/variants.csv"
  /usr/bin/python3 "$root/scripts/knob_study_table.py" "$out/$study.sqlite" --variants "$out/variants.csv" \
    --reference cmaes --out "$out/${study//-/_}.csv"
}

run_study_part() {
  local env label opt flags
  IFS='|' read -r _ env label opt flags <<<"$1"
  # shellcheck disable=SC2086
  # exit 3: some runs failed, which are results (stored with their errors), not a crash
  "$harness" --env "$env" --optimizer "$opt" $flags --seeds "$seeds" --budget "$(budget_of "$env")" \
    --jobs 1 --quiet --db "$out/parts/${env}__${label}.sqlite" || (($? == 3)) && echo "  done: $env $label"
}

# the variants' labels by config hash, for the table
study_labels() {
  local v label opt f
  for v in "${variants[@]}"; do
    IFS='|' read -r label opt _ <<<"$v"
    [[ $label == reference ]] && continue
    for f in "$out"/parts/*__"$label".sqlite; do
      [[ -e $f ]] || continue
      sqlite3 -readonly "$f" "SELECT DISTINCT opt_config_hash FROM runs" | sed "s/\$/,$label/"
    done
  done | sort -u
}
