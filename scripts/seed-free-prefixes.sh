#!/usr/bin/env bash
# How long each optimizer's seed-free prefix is (docs/determinism.md "Sharing across seeds"): the episodes a
# run simulates before its optimizer's first random draw, which every other seed of the same
# env, optimizer, configs and budget replays instead of simulating. The prefix does not depend on
# the seed, so one seed per (env, optimizer) measures it.
#   scripts/seed-free-prefixes.sh BUILD_DIR DB OUT.csv [--budget N] [--envs A,B]
# On every env but the full particle tasks (fluid-h5 stands for fluid), at seed 0, into DB
# (resumable: the same command goes on where it stopped): the optimizers whose `harness list`
# seed use is late or never at --budget (default 1000), and every optimizer (ppo and sac on the RL
# envs) at 20 episodes, which shows that the others draw before their first episode. Then writes
# OUT.csv: env,optimizer,budget,seed_free_episodes,share.
set -euo pipefail
build=$(cd "${1:?usage: seed-free-prefixes.sh BUILD_DIR DB OUT.csv [--budget N] [--envs A,B]}" && pwd)
db=${2:?usage: seed-free-prefixes.sh BUILD_DIR DB OUT.csv}
out=${3:?usage: seed-free-prefixes.sh BUILD_DIR DB OUT.csv}
shift 3
budget=1000
envs=
while (($#)); do
  case $1 in
    --budget) budget=${2:?--budget needs a number}; shift 2 ;;
    --envs) envs=${2:?--envs needs names}; shift 2 ;;
    *) echo "seed-free-prefixes: unknown option '$1'" >&2; exit 2 ;;
  esac
done
harness=$build/bin/harness
[[ -x $harness ]] || { echo "seed-free-prefixes: no harness at $harness" >&2; exit 2; }
if [[ -z $envs ]]; then
  # the env table of `harness list`, to its blank line, without the particle tasks
  envs=$("$harness" list | awk 'NR > 1 && NF == 0 { done = 1 } NR > 1 && !done { print $1 }' |
    grep -v -E '^(fluid|plb-)' | paste -sd, -),fluid-h5
fi
# a grid exits 3 when some of its runs failed: they are results, not a crash
grid() { "$@" || (($? == 3)); }
# the optimizer table of `harness list`, to its blank line: name, gradient, rl, seed use, ...
sharing=$("$harness" list | awk 'f && !NF { f = 0 } f && ($4 == "late" || $4 == "never") { print $1 } /^optimizer/ { f = 1 }' |
  paste -sd, -)
grid "$harness" --env "$envs" --optimizer "$sharing" --seeds 1 --budget "$budget" --quiet --db "$db"
grid "$harness" --all --env "$envs" --seeds 1 --budget 20 --quiet --db "$db"
/usr/bin/python3 - "$db" "$out" <<'PY'
import csv, sqlite3, sys
db, out = sys.argv[1], sys.argv[2]
con = sqlite3.connect("file:" + db + "?mode=ro", uri=True)
rows = con.execute("SELECT env, optimizer, budget, seed_free_episodes FROM runs WHERE status='done' AND seed=0 "
                   "ORDER BY env, optimizer").fetchall()
with open(out + ".tmp", "w", newline="") as f:
    w = csv.writer(f, lineterminator="\n")
    w.writerow(["env", "optimizer", "budget", "seed_free_episodes", "share"])
    for env, opt, budget, free in rows:
        w.writerow([env, opt, budget, free, f"{free / budget:.3f}"])
import os
os.replace(out + ".tmp", out)
print(f"seed-free-prefixes: {len(rows)} runs -> {out}")
PY
