#!/usr/bin/env bash
# Samples the CPU seconds of a grid's pieces while they run, for scripts/plan_vs_measured.py: the
# harness records each episode's wall time, which pieces side by side and anything else on the
# machine stretch, but not the CPU time a run took.
#
#   scripts/piece-cpu-monitor.sh PIECES_DIR OUT.csv [SECONDS]
#
# Every SECONDS (default 20) it appends, for each harness process whose --db is a file in
# PIECES_DIR, one line: unix_time,pid,piece,cpu_s,started_at_unix (cpu_s: utime + stime from
# /proc/PID/stat, whole seconds, cumulative since the process started; piece: the database's name
# without .sqlite). The last line of a process is its total within SECONDS. Run it niced beside the
# grid (e.g. `setsid nohup nice -n 5 scripts/piece-cpu-monitor.sh DIR/pieces DIR/cpu.csv &`) and
# start it before the pieces: a process that starts and ends unseen is missing from the file. OUT
# is appended to when it is this script's (its header line), and refused otherwise.
set -euo pipefail
dir=${1:?usage: piece-cpu-monitor.sh PIECES_DIR OUT.csv [SECONDS]}
out=${2:?usage: piece-cpu-monitor.sh PIECES_DIR OUT.csv [SECONDS]}
every=${3:-20}
header="unix_time,pid,piece,cpu_s,started_at_unix"
[[ -d $dir ]] || { echo "piece-cpu-monitor: PIECES_DIR $dir is not a directory" >&2; exit 2; }
[[ $every =~ ^[1-9][0-9]*$ ]] || { echo "piece-cpu-monitor: SECONDS must be a whole number from 1, got '$every'" >&2; exit 2; }
dir=$(cd "$dir" && pwd)
if [[ -e $out ]]; then
  [[ $(head -n 1 "$out") == "$header" ]] || { echo "piece-cpu-monitor: $out exists and is not a CPU log: name a new file" >&2; exit 2; }
else
  echo "$header" > "$out"
fi
ticks=$(getconf CLK_TCK)
boot=$(awk '/^btime/ {print $2}' /proc/stat)
while true; do
  for pid in $(pgrep -f -- "--db $dir/" || true); do
    stat=$(cat "/proc/$pid/stat" 2>/dev/null) || continue
    db=$(tr '\0' '\n' < "/proc/$pid/cmdline" 2>/dev/null | grep -m 1 "^$dir/.*\.sqlite$" || true)
    [[ -n $db ]] || continue
    # the fields after the command's closing parenthesis: 12 utime, 13 stime, 20 starttime (ticks)
    read -r -a f <<< "${stat##*) }"
    echo "$(date +%s),$pid,$(basename "$db" .sqlite),$(( (f[11] + f[12]) / ticks )),$(( boot + f[19] / ticks ))" >> "$out"
  done
  sleep "$every"
done
