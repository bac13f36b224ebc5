# shellcheck shell=bash
# The runner of the optimizer-variant studies (scripts/knob-study.sh, scripts/boleap-study.sh), sourced
# by them after they set:
#   study        the study's name (its database: OUTDIR/$study.sqlite, table OUTDIR/${study//-/_}.csv)
#   envs         default env list (comma-separated; --envs overrides)
#   variants     array of "label|optimizer list|--set flags" (label "reference" for plain optimizers)
#   budget_of    function ENV -> budget
#   cost_rank    function ENV LABEL -> a number; parts run cheapest first
# and then call `variant_study "$@"` with the script's arguments:
#   OUTDIR [--envs E1,E2] [--seeds N] [--only REGEX] [--jobs J] [--table] [BUILD_DIR]
# Each (env, variant) runs into OUTDIR/parts/ENV__LABEL.sqlite (one writer per file, J at once),
# then `harness merge` joins them into OUTDIR/$study.sqlite (variants differ by opt_config_hash;
# OUTDIR/variants.csv names each hash by its label) and scripts/knob_study_table.py writes the
# table. Variants see the same random numbers: a run's seed depends on env, optimizer and seed index
# only. Interrupted? Run the same command again: every part resumes.
#
# A study longer than a machine's life goes on from landed data: each finished part also leaves
# its runs as OUTDIR/parts/ENV__LABEL.csv (env, optimizer, seed, budget, status, best_loss,
# opt_config_hash, config, diagnostics, wall_s, harness: the binary's --version line). Commit those
# into data/$study/ (or point $STUDY_LANDED at them) and a later run of the study, on a machine that
# lost OUTDIR, takes those parts from there instead of running them, provided its binary is the one
# that made them (it refuses, naming the file, otherwise: build that commit). The table is made from
# the parts' CSVs, landed or not. --table runs nothing: it makes the table from the landed parts
# alone (a study still running elsewhere, published as far as it has come; the table's seeds
# column says how many runs each row has) and names what it left out.
#
# A part whose runs take hours would still be lost whole with its machine, so a part runs in
# pieces: the harness's deterministic slices of its runs that hold one run each
# (scripts/lib/run-pieces.sh; a part whose seeds share episodes runs whole). Each piece is a part
# of one run, OUTDIR/parts/ENV__LABEL@IofN.{sqlite,csv}, landed as it finishes; two pieces of a
# part run at once. A part begun whole (its ENV__LABEL.sqlite in OUTDIR) finishes whole.
# shellcheck source=scripts/lib/run-pieces.sh
source "$(dirname "${BASH_SOURCE[0]}")/run-pieces.sh"

variant_study() {
  local root out seeds=5 only='.' jobs=2 build table_only=0
  root=$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)
  out=${1:?usage: $study OUTDIR [--envs E1,E2] [--seeds N] [--only REGEX] [--jobs J] [--table] [BUILD_DIR]}
  shift
  build=$root/build
  while (($#)); do
    case $1 in
      --envs) envs=$2; shift 2 ;;
      --seeds) seeds=$2; shift 2 ;;
      --only) only=$2; shift 2 ;;
      --jobs) jobs=$2; shift 2 ;;
      --table) table_only=1; shift ;;
      -*) echo "$study: unknown option '$1'" >&2; return 2 ;;
      *) build=$1; shift ;;
    esac
  done
  harness=$build/bin/harness
  [[ -x $harness ]] || { echo "$study: no harness at $harness" >&2; return 2; }
  mkdir -p "$out/parts"
  version=$("$harness" --version)
  landed=${STUDY_LANDED:-$root/data/$study}

  local parts=() env v label opt flags env_list
  IFS=, read -ra env_list <<<"$envs"
  for env in "${env_list[@]}"; do
    for v in "${variants[@]}"; do
      IFS='|' read -r label opt flags <<<"$v"
      [[ $label =~ $only ]] || continue
      if [[ -f $landed/${env}__$label.csv ]]; then
        # a landed part: this binary's, or the study would mix binaries
        check_made_by "$landed/${env}__$label.csv" || return 2
        cp "$landed/${env}__$label.csv" "$out/parts/${env}__$label.csv"
        echo "  landed: $env $label"
        continue
      fi
      local rank piece pieces
      rank=$(cost_rank "$env" "$label")
      if [[ -e $out/parts/${env}__$label.sqlite ]]; then
        parts+=("$rank|$env|$label|$opt|$flags|")
        continue
      fi
      mapfile -t pieces < <(part_pieces "$env" "$opt" "$flags")
      ((${#pieces[@]})) || { parts+=("$rank|$env|$label|$opt|$flags|"); continue; }
      for piece in "${pieces[@]}"; do
        local name=${env}__$label@${piece/\//of}
        if [[ -f $landed/$name.csv ]]; then
          check_made_by "$landed/$name.csv" || return 2
          cp "$landed/$name.csv" "$out/parts/$name.csv"
          echo "  landed: $env $label piece $piece"
          continue
        fi
        parts+=("$rank|$env|$label|$opt|$flags|$piece")
      done
    done
  done
  mapfile -t parts < <(printf '%s\n' "${parts[@]}" | sort -t'|' -k1,1n -s)
  if ((table_only)); then
    local p
    for p in "${parts[@]}"; do
      [[ -n $p ]] || continue
      IFS='|' read -r _ env label _ _ piece <<<"$p"
      echo "  not landed, left out: $env $label${piece:+ piece $piece}"
    done
    parts=()
  fi
  echo "$study: ${#parts[@]} parts or pieces of parts (env x variant), $seeds seeds, $jobs at once, into $out"

  export -f run_study_part budget_of
  export harness seeds out version
  ((${#parts[@]} == 0)) || printf '%s\n' "${parts[@]}" | xargs -d '\n' -P "$jobs" -I{} bash -c 'run_study_part "$@"' _ {}

  # the merged database (not with --table: a part running in OUTDIR is not a result yet)
  ((table_only)) || rm -f "$out/$study.sqlite"
  if ((!table_only)) && compgen -G "$out/parts/*.sqlite" >/dev/null; then
    "$harness" merge --into "$out/$study.sqlite" "$out"/parts/*.sqlite
  fi
  { echo "opt_config_hash,variant"; study_labels; } >"$out/variants.csv"
  /usr/bin/python3 "$root/scripts/knob_study_table.py" "$out"/parts/*.csv --variants "$out/variants.csv" \
    --reference cmaes --out "$out/${study//-/_}.csv"
}

# a landed part's CSV was made by this binary, or the study would mix binaries
check_made_by() {
  local made_by
  made_by=$(/usr/bin/python3 -c 'import csv, sys; print(*sorted({r["harness"] for r in csv.DictReader(open(sys.argv[1]))}), sep=" | ")' "$1")
  [[ $made_by == "$version" ]] && return 0
  echo "$study: $1 was made by '$made_by', not by this binary ('$version'): build that commit, or move the file away" >&2
  return 1
}

# the pieces of a part (ENV OPT FLAGS): scripts/lib/run-pieces.sh
part_pieces() {
  local env=$1 opt=$2 flags=$3
  # shellcheck disable=SC2086
  grid_pieces "$harness" "$out/parts/.plan-nothing.sqlite" --env "$env" --optimizer "$opt" $flags \
    --seeds "$seeds" --budget "$(budget_of "$env")"
}

run_study_part() {
  local env label opt flags shard
  IFS='|' read -r _ env label opt flags shard <<<"$1"
  # shellcheck disable=SC2086
  # exit 3: some runs failed, which are results (stored with their errors), not a crash
  local db=$out/parts/${env}__${label}${shard:+@${shard/\//of}}.sqlite
  "$harness" --env "$env" --optimizer "$opt" $flags --seeds "$seeds" --budget "$(budget_of "$env")" \
    ${shard:+--shard "$shard"} --jobs 1 --quiet --db "$db" || (($? == 3)) || return 0
  # the finished part's runs, to land as data (the binary's version line in every row; floats as
  # Python writes them, which read back to the same bits)
  /usr/bin/python3 - "$db" "$version" "${db%.sqlite}.csv" <<'PY'
import csv, os, sqlite3, sys
db, version, out = sys.argv[1:]
con = sqlite3.connect(f"file:{db}?mode=ro", uri=True)
rows = con.execute("SELECT r.env, r.optimizer, r.seed, r.budget, r.status, r.best_loss, r.opt_config_hash, "
                   "c.json, r.diagnostics, r.wall_s FROM runs r JOIN configs c ON c.hash = r.opt_config_hash "
                   "ORDER BY r.optimizer, r.seed").fetchall()
with open(out + ".tmp", "w", newline="") as f:
    w = csv.writer(f, lineterminator="\n")
    w.writerow(["env", "optimizer", "seed", "budget", "status", "best_loss", "opt_config_hash", "config",
                "diagnostics", "wall_s", "harness"])
    for r in rows:
        w.writerow([("" if v is None else repr(v) if isinstance(v, float) else v) for v in r] + [version])
os.replace(out + ".tmp", out)
PY
  echo "  done: $env $label${shard:+ piece $shard}"
}

# the variants' labels by config hash, for the table; a reference optimizer's config is labelled
# with its name (its default), so that a variant of it (rand-descents.leap_descents) does not leave
# the plain one unnamed; where one hash has two labels the variant's (printed after) is kept
study_labels() {
  local v label opt f
  for f in "$out"/parts/*__reference.csv "$out"/parts/*__reference@*.csv; do
    [[ -e $f ]] || continue
    /usr/bin/python3 -c 'import csv, sys; print(*sorted({r["opt_config_hash"] + "," + r["optimizer"] for r in csv.DictReader(open(sys.argv[1]))}), sep="\n")' "$f"
  done
  for v in "${variants[@]}"; do
    IFS='|' read -r label opt _ <<<"$v"
    [[ $label == reference ]] && continue
    for f in "$out"/parts/*__"$label".csv "$out"/parts/*__"$label"@*.csv; do
      [[ -e $f ]] || continue
      /usr/bin/python3 -c 'import csv, sys; print(*sorted({r["opt_config_hash"] for r in csv.DictReader(open(sys.argv[1]))}), sep="\n")' \
        "$f" | sed "s/\$/,$label/"
    done
  done | sort -u
}
