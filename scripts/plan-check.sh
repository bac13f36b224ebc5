#!/usr/bin/env bash
# Does `harness plan` tell the truth? Runs a sample grid and compares each (env, optimizer) pair's
# planned seconds with the wall seconds its runs took (the table: docs/running.md, "Does the plan
# tell the truth?" and "The main job at a glance").
#   scripts/plan-check.sh BUILD_DIR WORK_DIR OUT.csv
# The sample: the 12 light envs of the claims grid x every optimizer x 2 seeds at 200 episodes,
# and fluid-h10 and plb-pinch-h5 with cmaes, gd and boleap. The envs are calibrated first (the
# cost cache, `harness calibrate`); the plan is made before the grid runs, from an empty
# database (the cost model alone), and kept in WORK_DIR, so the same command resumes an
# interrupted check. OUT.csv: env,optimizer,runs,planned_s,measured_s,ratio,within (|ratio - 1|
# <= 0.3); the last line of the output says how many pairs are within.
set -euo pipefail
build=$(cd "${1:?usage: plan-check.sh BUILD_DIR WORK_DIR OUT.csv}" && pwd)
work=${2:?usage: plan-check.sh BUILD_DIR WORK_DIR OUT.csv}
out=${3:?usage: plan-check.sh BUILD_DIR WORK_DIR OUT.csv}
harness=$build/bin/harness
[[ -x $harness ]] || { echo "plan-check: no harness at $harness" >&2; exit 2; }
mkdir -p "$work"
db=$work/check.sqlite
light=ackley-10,bounce,branin,cartpole1,cartpole3,hartmann6,pinball-1x2,pinball-4x4,rastrigin-10,rosenbrock-10,sphere-10,styblinski-10
parts=("--all --env $light" "--env fluid-h10,plb-pinch-h5 --optimizer cmaes,gd,boleap")
common="--seeds 2 --budget 200"
# a grid exits 3 when some of its runs failed: they are results, not a crash
grid() { "$@" || (($? == 3)); }
for i in "${!parts[@]}"; do
  # shellcheck disable=SC2086
  "$harness" calibrate ${parts[$i]} $common >/dev/null
  if [[ ! -f $work/planned-$i.csv ]]; then
    [[ ! -e $db ]] || { echo "plan-check: $db exists but no plan of part $i: use a new WORK_DIR" >&2; exit 2; }
    # shellcheck disable=SC2086
    "$harness" plan ${parts[$i]} $common --db "$work/empty.sqlite" --runs-csv "$work/planned-$i.csv" >/dev/null
  fi
done
for i in "${!parts[@]}"; do
  # shellcheck disable=SC2086
  grid "$harness" ${parts[$i]} $common --jobs 2 --quiet --db "$db"
done
/usr/bin/python3 - "$db" "$out" "$work"/planned-*.csv <<'PY'
import csv, os, sqlite3, sys
db, out, plans = sys.argv[1], sys.argv[2], sys.argv[3:]
planned = {}
for p in plans:
    for r in csv.DictReader(open(p)):
        planned[(r["env"], r["optimizer"], int(r["seed"]))] = float(r["planned_s"])
con = sqlite3.connect("file:" + db + "?mode=ro", uri=True)
pairs = {}
for env, opt, seed, wall in con.execute("SELECT env, optimizer, seed, wall_s FROM runs WHERE status IN ('done', 'failed')"):
    if (env, opt, seed) not in planned:
        continue
    p = pairs.setdefault((env, opt), [0, 0.0, 0.0])
    p[0] += 1
    p[1] += planned[(env, opt, seed)]
    p[2] += wall
rows, within = [], 0
for (env, opt), (n, plan_s, wall_s) in sorted(pairs.items()):
    ratio = wall_s / plan_s if plan_s > 0 else float("inf")
    ok = abs(ratio - 1.0) <= 0.3
    within += ok
    rows.append([env, opt, n, f"{plan_s:.4g}", f"{wall_s:.4g}", f"{ratio:.3f}", int(ok)])
with open(out + ".tmp", "w", newline="") as f:
    w = csv.writer(f, lineterminator="\n")
    w.writerow(["env", "optimizer", "runs", "planned_s", "measured_s", "ratio", "within"])
    w.writerows(rows)
os.replace(out + ".tmp", out)
print(f"plan-check: {within} of {len(rows)} (env, optimizer) pairs within +-30% of the plan "
      f"({100.0 * within / max(1, len(rows)):.1f}%) -> {out}")
# a pair whose runs take milliseconds in all is at the mercy of the scheduler (the same run twice
# differs up to 2x there): the pairs that take at least 0.1 s are counted apart, and the whole
long = [(p, m, ok) for (p, m, ok) in ((float(r[3]), float(r[4]), r[6]) for r in rows) if m >= 0.1]
print(f"plan-check: of the {len(long)} pairs whose runs took at least 0.1 s, {sum(ok for _, _, ok in long)} within +-30%; "
      f"all pairs: planned {sum(float(r[3]) for r in rows):.4g} s, measured {sum(float(r[4]) for r in rows):.4g} s")
PY
