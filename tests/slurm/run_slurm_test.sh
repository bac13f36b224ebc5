#!/usr/bin/env bash
# The Slurm route for real (ctest label `slurm`): a single-node Slurm cluster in a scratch folder
# (slurm_cluster.sh), `harness slurm` for a small grid in 4 shards submitted with its submit.sh; the
# merged database's result table must equal a single-process run's byte for byte. Then the TERM
# case: a task stopped mid-grid by TERM (as at a time limit) copies back what it committed, its
# merge never runs, a second submit resumes it, and the result again equals a single-process run.
# Then a user's database: a --dir holding one is refused, and one put there later survives the
# array and its merge byte for byte.
# Usage: run_slurm_test.sh BUILD_DIR. Exit 77 (skipped) when not root: the daemons run as root.
set -euo pipefail

build=${1:?usage: run_slurm_test.sh BUILD_DIR}
harness=$(cd "$build/bin" && pwd)/harness
here=$(cd "$(dirname "$0")" && pwd)
if [[ $(id -u) -ne 0 ]]; then
  echo "skipped: a test Slurm cluster needs root"
  exit 77
fi
for tool in slurmctld slurmd sbatch squeue scontrol scancel munged mungekey sqlite3; do
  command -v "$tool" >/dev/null || { echo "FAIL: $tool missing (scripts/install-deps.sh installs it)"; exit 1; }
done

# shellcheck source=slurm_cluster.sh
source "$here/slurm_cluster.sh"
work=$(mktemp -d /tmp/dsb-slurm-test.XXXXXX)
chmod 755 "$work"

# tear everything down on any exit (nothing in here may stop it: no -e); on failure show the logs
cleanup() {
  local rc=$?
  set +e
  trap - EXIT
  if ((rc != 0)); then
    for f in "$work"/*/logs/* "$work"/cluster/log/*.log; do
      [[ -f $f ]] && { echo "--- $f"; tail -n 20 "$f"; }
    done
  fi
  slurm_cluster_stop
  rm -rf "$work"
  exit "$rc"
}
trap cleanup EXIT
trap 'exit 143' TERM INT  # a signal ends the script through cleanup too

now() { date +%s.%N; }
since() { awk -v a="$1" -v b="$(now)" 'BEGIN { printf "%.1f", b - a }'; }
fail() { echo "FAIL: $*" >&2; exit 1; }

# wait (at most $1 s) until none of the jobs $2 (comma-separated ids) is pending, running or completing
wait_jobs() {
  timeout "$1" bash -c 'while [[ -n $(squeue -h -t PD,R,CG -j "$1" -o %i 2>/dev/null) ]]; do sleep 0.3; done' _ "$2" ||
    fail "jobs $2 still queued after $1 s"
}

# the states of job $1's tasks (an array: one line per task), e.g. "COMPLETED"
job_states() { scontrol show job "$1" -o 2>/dev/null | grep -o 'JobState=[A-Z_]*' | cut -d= -f2 | sort | uniq -c | xargs; }

# submit DIR: runs DIR/submit.sh, sets array_id and merge_id from what it prints
submit() {
  local out
  out=$(bash "$1/submit.sh")
  echo "$out" | sed 's/^/  submit.sh: /'
  array_id=$(echo "$out" | sed -n 's/^array job \([0-9]*\):.*/\1/p')
  merge_id=$(echo "$out" | sed -n 's/^merge job \([0-9]*\):.*/\1/p')
  [[ -n $array_id && -n $merge_id ]] || fail "submit.sh printed no job ids"
}

# export_digest DB CSV: the result table as CSV, prints its sha256
export_digest() {
  local out
  out=$("$harness" export --db "$1" --out "$2" 2>&1) || fail "harness export --db $1: $out"
  sha256sum "$2" | cut -d' ' -f1
}

# show_log FILE: a task's log, indented
show_log() { grep -v '^\[' "$1" | sed 's/^/    log: /'; }

# 1. the cluster; tasks' node-local scratch goes under $work/node (sbatch passes TMPDIR on)
t=$(now)
slurm_cluster_start "$work/cluster"
mkdir -p "$work/node"
export TMPDIR=$work/node
echo "slurm: single-node cluster up in $(since "$t") s ($(sinfo -h -N -o '%N %c CPUs %t'))"

# 2. the grid as a 4-task array, 1 CPU each, and its merge
grid=(--env sphere-10,branin --optimizer random,cmaes --seeds 2 --budget 20)
t=$(now)
"$harness" slurm "${grid[@]}" --shards 4 --cpus-per-task 1 --dir "$work/array" | sed 's/^/  /'
submit "$work/array"
wait_jobs 180 "$array_id,$merge_id"
echo "slurm: array $array_id [$(job_states "$array_id")], merge $merge_id [$(job_states "$merge_id")] in $(since "$t") s"
[[ $(job_states "$array_id") == "4 COMPLETED" ]] || fail "not every array task completed"
[[ $(job_states "$merge_id") == "1 COMPLETED" ]] || fail "the merge job did not complete"
for i in 0 1 2 3; do
  [[ -f $work/array/shards/shard-$i.sqlite ]] || fail "no database for shard $i"
done
[[ -f $work/array/results.sqlite ]] || fail "no merged database $work/array/results.sqlite"

# the grid "${grid[@]}" in one process: `harness export` of database $1 must equal its export byte
# for byte ($2 names the case in files and messages)
expect_single_process_result() {
  local db=$1 label=$2 t merged single
  t=$(now)
  "$harness" "${grid[@]}" --jobs 1 --quiet --db "$work/$label-single.sqlite" 2>/dev/null
  echo "slurm: single-process run in $(since "$t") s"
  merged=$(export_digest "$db" "$work/$label.csv")
  single=$(export_digest "$work/$label-single.sqlite" "$work/$label-single.csv")
  echo "  sha256 $label: $merged ($(($(wc -l <"$work/$label.csv") - 1)) rows)"
  echo "  sha256 single process: $single"
  cmp -s "$work/$label.csv" "$work/$label-single.csv" || fail "the $label export differs from the single-process export"
}

# 3. the same grid in one process: the result tables must be byte-identical
expect_single_process_result "$work/array/results.sqlite" "merged-shards"

# 4. TERM mid-grid: one task, a grid of two quick runs and two slow ones (sac, a few s each)
grid=(--env cartpole1 --optimizer random,sac --seeds 2 --budget 6)
t=$(now)
"$harness" slurm "${grid[@]}" --shards 1 --cpus-per-task 1 --dir "$work/term" >/dev/null
submit "$work/term"
# wait until the task's node-local database holds 3 finished runs, then TERM the batch shell alone,
# as `#SBATCH --signal=B:TERM@120` does before a time limit
timeout 120 bash -c 'until [[ $(sqlite3 -readonly "$1"/dsb-shard-0.*/shard-0.sqlite "SELECT count(*) FROM runs WHERE status='"'done'"'" 2>/dev/null) == 3 ]]; do sleep 0.2; done' _ "$work/node" ||
  fail "the TERM case's task did not reach 3 finished runs"
scancel --signal=TERM --batch "$array_id"
wait_jobs 60 "$array_id,$merge_id"
echo "slurm: TERM sent after 3 runs: array $array_id [$(job_states "$array_id")], merge $merge_id [$(job_states "$merge_id")] in $(since "$t") s"
copied=$(sqlite3 "$work/term/shards/shard-0.sqlite" "SELECT count(*) FROM runs WHERE status='done'")
[[ $copied == 3 ]] || fail "after TERM the copied-back shard holds $copied finished runs, not 3"
[[ ! -f $work/term/results.sqlite ]] || fail "the merge ran although the array failed"
show_log "$work"/term/logs/shard-0-job-"$array_id".out
grep -q "TERM received" "$work"/term/logs/shard-0-job-"$array_id".out || fail "the task's log shows no TERM"

# 5. submit again: the shard resumes (3 runs done, the fourth from its committed episodes) and the
#    merge follows
t=$(now)
submit "$work/term"
wait_jobs 120 "$array_id,$merge_id"
echo "slurm: resubmitted: array $array_id [$(job_states "$array_id")], merge $merge_id [$(job_states "$merge_id")] in $(since "$t") s"
show_log "$work"/term/logs/shard-0-job-"$array_id".out
grep -q "resuming: 3 runs already done" "$work"/term/logs/shard-0-job-"$array_id".out || fail "the second attempt did not resume"
grep -q "resumed 1 interrupted run" "$work"/term/logs/shard-0-job-"$array_id".out || fail "the run in progress was not resumed"
[[ -f $work/term/results.sqlite ]] || fail "no merged database after the resubmission"
expect_single_process_result "$work/term/results.sqlite" "after-TERM-and-resume"

# 6. a user's database is never at risk: `harness slurm` refuses a --dir that holds one (exit 2,
#    nothing created), and one put there after the scripts were written survives the array and its
#    merge byte for byte (the merge fails and says so); the folders have a '%' in their names, which
#    the #SBATCH lines must carry as '%%' for the logs to land there (%j is Slurm's job id)
user_db=$work/merged-shards-single.sqlite
user_sum=$(sha256sum "$user_db" | cut -d' ' -f1)
grid=(--env sphere-10,branin --optimizer random --seeds 2 --budget 20)
mkdir "$work/user%db"
cp "$user_db" "$work/user%db/results.sqlite"
before=$(cd "$work/user%db" && ls -A)
status=0
out=$(cd "$work/user%db" && "$harness" slurm "${grid[@]}" --shards 2 --dir . 2>&1) || status=$?
echo "  $out"
((status == 2)) || fail "slurm --dir . beside a user's results.sqlite exited $status, not 2"
[[ $(cd "$work/user%db" && ls -A) == "$before" ]] || fail "the refused slurm created files in the user's folder"
[[ $(sha256sum "$work/user%db/results.sqlite" | cut -d' ' -f1) == "$user_sum" ]] || fail "the user's database changed"
echo "slurm: --dir holding a user's database refused (exit 2), nothing created, the database unchanged"

t=$(now)
"$harness" slurm "${grid[@]}" --shards 2 --cpus-per-task 1 --dir "$work/late%j" >/dev/null
cp "$user_db" "$work/late%j/results.sqlite"
submit "$work/late%j"
wait_jobs 180 "$array_id,$merge_id"
echo "slurm: user's database put in --dir after the scripts: array $array_id [$(job_states "$array_id")], merge $merge_id [$(job_states "$merge_id")] in $(since "$t") s"
[[ $(job_states "$array_id") == "2 COMPLETED" ]] || fail "not every array task completed"
[[ $(job_states "$merge_id") == "1 FAILED" ]] || fail "the merge did not fail beside the user's results.sqlite"
[[ $(sha256sum "$work/late%j/results.sqlite" | cut -d' ' -f1) == "$user_sum" ]] ||
  fail "the merge changed the user's results.sqlite"
merge_log=$work/late%j/logs/merge-job-$merge_id.out
[[ -f $merge_log ]] || fail "no merge log at $merge_log (a '%' in the folder not carried as '%%')"
show_log "$merge_log"
grep -q "results.sqlite exists: a merge never writes over a file" "$merge_log" || fail "the merge's log does not say why"
# moved away, the merge runs on the next submit, and its result is the single process's
mv "$work/late%j/results.sqlite" "$work/user-moved.sqlite"
submit "$work/late%j"
wait_jobs 180 "$array_id,$merge_id"
[[ $(job_states "$merge_id") == "1 COMPLETED" ]] || fail "the merge did not complete once results.sqlite was moved"
expect_single_process_result "$work/late%j/results.sqlite" "merged-in-percent-j"
[[ $(sha256sum "$work/user-moved.sqlite" | cut -d' ' -f1) == "$user_sum" ]] || fail "the user's database changed"

echo "slurm: passed"
