#!/usr/bin/env bash
# Pictures of the best run of every simulated env in a harness database, for the report:
#   scripts/render-best.sh DB OUTDIR    ->  OUTDIR/render_<env>.png (4 time points each)
# then: harness report --db DB --renders OUTDIR. The database is only read. Synthetic envs are
# skipped (nothing is simulated). HARNESS overrides the program (default build/bin/harness).
set -euo pipefail
db=${1:?usage: render-best.sh DB OUTDIR}
out=${2:?usage: render-best.sh DB OUTDIR}
here=$(cd "$(dirname "$0")/.." && pwd)
harness=${HARNESS:-$here/build/bin/harness}
[[ -f "$db" ]] || { echo "render-best: no database file '$db'" >&2; exit 2; }
mkdir -p "$out"
# the envs with a done run, read-only
mapfile -t envs < <(sqlite3 -readonly "$db" "SELECT DISTINCT env FROM runs WHERE status='done' ORDER BY env")
rendered=0
for env in "${envs[@]}"; do
  # a synthetic env answers "is not simulated" (exit 2): skipped; any other error stops the script
  if ! msg=$("$harness" render --best-of "$db" --env "$env" --frames 4 --force --out "$out/render_$env.png" 2>&1); then
    if [[ "$msg" == *"is not simulated"* ]]; then continue; fi
    echo "$msg" >&2
    exit 1
  fi
  echo "$msg"
  rendered=$((rendered + 1))
done
echo "render-best: $rendered env(s) rendered into $out"
