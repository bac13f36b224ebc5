#!/usr/bin/env bash
# What resuming an interrupted run costs (docs/performance.md "Resuming a GP optimizer"): one
# run of OPTIMIZER on ENV at BUDGET episodes, uninterrupted and stopped by SIGTERM after episode
# AT (the fault injection of a build with DSB_FAULT_INJECTION, harness/run/fault_injection.hpp),
# then resumed three ways from copies of the stopped database:
#   resume     the resume as it is (the journal's episodes and the optimizer's own work recalled),
#   replay     the same resume stopped after episode AT + 1: the replay alone,
#   old        the journal without its own-work rows, as a binary that did not keep them left it
#              (the GP fits and acquisitions computed again), to the end.
# Each is timed REPEATS times (wall, user + sys seconds; the median is printed), and each
# finished database's digest is compared with the uninterrupted run's: SHA-256 of every episode's
# env, optimizer, seed, episode, loss, metric (%.17g), used_grad and failed (docs/determinism.md),
# and of the run's status, episodes, best_loss, best_x and diagnostics (timings left out).
#   scripts/gp-resume-timing.sh BUILD_DIR WORK_DIR [--optimizer boleap] [--env cartpole1]
#                               [--budget 1000] [--at 900] [--repeats 3]
# WORK_DIR must be new or empty; the databases stay there.
set -euo pipefail
usage="usage: gp-resume-timing.sh BUILD_DIR WORK_DIR [--optimizer O] [--env E] [--budget N] [--at K] [--repeats R]"
build=$(cd "${1:?$usage}" && pwd)
work=${2:?$usage}
shift 2
opt=boleap env=cartpole1 budget=1000 at=900 repeats=3
while (($#)); do
  case $1 in
    --optimizer) opt=${2:?--optimizer needs a name}; shift 2 ;;
    --env) env=${2:?--env needs a name}; shift 2 ;;
    --budget) budget=${2:?--budget needs a number}; shift 2 ;;
    --at) at=${2:?--at needs a number}; shift 2 ;;
    --repeats) repeats=${2:?--repeats needs a number}; shift 2 ;;
    *) echo "gp-resume-timing: unknown option '$1'" >&2; exit 2 ;;
  esac
done
harness=$build/bin/harness
[[ -x $harness ]] || { echo "gp-resume-timing: no harness at $harness" >&2; exit 2; }
mkdir -p "$work"
[[ -z $(ls -A "$work") ]] || { echo "gp-resume-timing: '$work' is not empty" >&2; exit 2; }
work=$(cd "$work" && pwd)
grid=(--env "$env" --optimizer "$opt" --seeds 1 --budget "$budget" --jobs 1 --quiet)
stop_after() { echo "DSB_FAULT_INJECTION=signal-in-run DSB_FAULT_AT_EPISODE=$1 DSB_FAULT_SIGNAL=15"; }

# timed NAME DB [VARS...]: runs the grid on DB, appends "NAME wall cpu" to times.txt; exit 0 or 143
timed() {
  local name=$1 db=$2 code=0
  shift 2
  env "$@" /usr/bin/time -f "%e %U %S" -o "$work/time.txt" "$harness" "${grid[@]}" --db "$db" \
    2> "$work/$name.stderr" || code=$?
  ((code == 0 || code == 143)) || { cat "$work/$name.stderr" >&2; exit 1; }
  tail -n 1 "$work/time.txt" | awk -v n="$name" '{ printf "%s %.2f %.2f\n", n, $1, $2 + $3 }' >> "$work/times.txt"
}

digest() {
  sqlite3 "$1" "SELECT r.env, r.optimizer, r.seed, e.episode, printf('%.17g', e.loss), printf('%.17g', e.metric),
                e.used_grad, e.failed FROM evals e JOIN runs r USING(run_id)
                ORDER BY r.env, r.optimizer, r.seed, e.episode;
                SELECT status, episodes, printf('%.17g', best_loss), best_x, diagnostics FROM runs ORDER BY run_id;" |
    sha256sum | cut -c1-16
}

for ((i = 0; i < repeats; ++i)); do timed full "$work/full-$i.sqlite"; done
timed stopped "$work/stopped.sqlite" $(stop_after "$at")
for ((i = 0; i < repeats; ++i)); do
  cp "$work/stopped.sqlite" "$work/resume-$i.sqlite"
  timed resume "$work/resume-$i.sqlite"
  cp "$work/stopped.sqlite" "$work/replay-$i.sqlite"
  timed replay "$work/replay-$i.sqlite" $(stop_after $((at + 1)))
  cp "$work/stopped.sqlite" "$work/old-$i.sqlite"
  # the journal without own work, numbered without gaps (tests/test_harness_cli.cpp does the same)
  sqlite3 "$work/old-$i.sqlite" "BEGIN; DELETE FROM replay WHERE kind=4;
    CREATE TEMP TABLE renumbered AS SELECT run_id, (SELECT count(*) FROM replay b WHERE b.run_id=a.run_id
      AND b.seq<a.seq) AS seq, kind, input_hash, payload FROM replay a;
    DELETE FROM replay; INSERT INTO replay SELECT * FROM renumbered; COMMIT;"
  timed old "$work/old-$i.sqlite"
done

echo "$opt on $env, $budget episodes, stopped after episode $at; $(nproc) CPUs, $(uptime | sed 's/.*load/load/')"
grep -h "own work" "$work/resume.stderr" "$work/old.stderr" | sed 's/^/  /'
full_digest=$(digest "$work/full-0.sqlite")
for f in "$work"/full-*.sqlite "$work"/resume-*.sqlite "$work"/old-*.sqlite; do
  d=$(digest "$f")
  echo "  digest $(basename "$f"): $d$([[ $d == "$full_digest" ]] && echo ' (equal)' || echo ' DIFFERS')"
done
# median wall and CPU per kind, and their share of the uninterrupted run's
python3 - "$work/times.txt" <<'PY'
import statistics, sys
times = {}
for line in open(sys.argv[1]):
    name, wall, cpu = line.split()
    times.setdefault(name, []).append((float(wall), float(cpu)))
med = {k: (statistics.median(w for w, _ in v), statistics.median(c for _, c in v)) for k, v in times.items()}
fw, fc = med["full"]
print(f"  {'':8} {'wall s':>9} {'cpu s':>9} {'wall %':>8} {'cpu %':>8}  runs (wall s)")
for k, (w, c) in med.items():
    print(f"  {k:8} {w:9.2f} {c:9.2f} {100 * w / fw:7.1f}% {100 * c / fc:7.1f}%  {[w for w, _ in times[k]]}")
# what the uninterrupted run spends after the stop (full - stopped) is work no resume can skip
rest_w, rest_c = fw - med["stopped"][0], fc - med["stopped"][1]
print(f"  {'rest':8} {rest_w:9.2f} {rest_c:9.2f} {100 * rest_w / fw:7.1f}% {100 * rest_c / fc:7.1f}%"
      "  full - stopped: the run's own work after the stop")
PY
