#!/usr/bin/env bash
# Same bits on every x86-64 CPU: a grid of every env x every optimizer, run twice, once as is and
# once as a CPU without AVX2 would run it: glibc told to ignore AVX2, FMA and AVX-512 (so libm
# would pick its other exp/log/pow/sin variants) and every batched kernel on SSE2 (DSB_SIMD=sse2,
# common/simd_path.hpp: the MPM engine's lanes, the batched exp/log and the GP's pairwise loops),
# must give one digest (sha256 of `harness export`).
# Prints both digests. The
# particle envs (seconds per episode) run at a short horizon (fluid-h5, plb-pinch-h5) with a few
# episodes; the others with 30.
#   tests/check_cpu_features.sh BUILD_DIR
# Exit 0: equal; 1: different (the differing (env, optimizer) pairs are listed); 77 (skipped):
# this CPU has none of the masked features, so the comparison would prove nothing.
set -euo pipefail
build=$(cd "${1:?usage: check_cpu_features.sh BUILD_DIR}" && pwd)
harness=$build/bin/harness
mask=glibc.cpu.hwcaps=-AVX2,-FMA,-AVX512F
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

# glibc reports which x86-64 levels (v2, v3 = AVX2 + FMA, v4 = AVX-512) it uses; the mask must
# change that, or this machine cannot show a difference
ldso=/lib64/ld-linux-x86-64.so.2
levels() { "$ldso" --list-diagnostics | sed -n 's/^dl_hwcaps_subdirs_active=//p'; }
plain_levels=$(levels)
masked_levels=$(GLIBC_TUNABLES=$mask levels)
if [[ "$plain_levels" == "$masked_levels" ]]; then
  echo "check_cpu_features: the mask changes nothing on this CPU (x86-64 levels $plain_levels): skipped"
  exit 77
fi

# every env of `harness list` but the particle tasks, which get their short-horizon variants
# (awk reads to the end: an early exit would leave the harness writing into a closed pipe)
light_envs=$("$harness" list | awk 'NR > 1 && NF == 0 { done = 1 } NR > 1 && !done { print $1 }' | grep -v -E '^(fluid|plb-)' | paste -sd, -)
# every optimizer but the RL learners (below, on the cartpoles, at budgets that reach an update)
# (the optimizer table: from its header to the next blank line; ext:NAME needs a command)
plain_optimizers=$("$harness" list | awk 'f && !NF { f = 0 } f { print $1 } /^optimizer/ { f = 1 }' | grep -v -E '^(ppo|sac|ext:NAME)$' | paste -sd, -)

# a grid exits 3 when some of its runs failed: they are results (rows of the table), not a crash
grid() { "$@" || (($? == 3)); }

run() {  # run NAME [env assignments...]: grid into NAME.sqlite, export to NAME.csv
  local name=$1
  shift
  grid env "$@" "$harness" --env "$light_envs" --optimizer "$plain_optimizers" --seeds 2 --budget 30 --jobs 2 --quiet \
    --db "$work/$name.sqlite"
  # the RL learners on the cartpoles at budgets that reach their updates: ppo 21 episodes (2,100
  # decisions, one update), sac 3 (200 gradient steps)
  grid env "$@" "$harness" --env cartpole1,cartpole3 --optimizer ppo --seeds 2 --budget 21 --jobs 2 --quiet --db "$work/$name.sqlite"
  grid env "$@" "$harness" --env cartpole1,cartpole3 --optimizer sac --seeds 2 --budget 3 --jobs 2 --quiet --db "$work/$name.sqlite"
  grid env "$@" "$harness" --all --env fluid-h5 --seeds 2 --budget 4 --jobs 2 --quiet --db "$work/$name.sqlite"
  grid env "$@" "$harness" --all --env plb-pinch-h5 --seeds 2 --budget 2 --jobs 2 --quiet --db "$work/$name.sqlite"
  "$harness" export --db "$work/$name.sqlite" --out "$work/$name.csv" >/dev/null
}
run plain
run masked GLIBC_TUNABLES=$mask DSB_SIMD=sse2

plain=$(sha256sum <"$work/plain.csv" | cut -d' ' -f1)
masked=$(sha256sum <"$work/masked.csv" | cut -d' ' -f1)
echo "check_cpu_features: $(($(wc -l <"$work/plain.csv") - 1)) episodes"
echo "  digest as is                     ($plain_levels): $plain"
echo "  digest with $mask and DSB_SIMD=sse2 ($masked_levels): $masked"
if [[ "$plain" != "$masked" ]]; then
  echo "check_cpu_features: FAILED, results depend on the CPU's features; differing env,optimizer:"
  diff "$work/plain.csv" "$work/masked.csv" | sed -n 's/^< \([^,]*,[^,]*\),.*/    \1/p' | sort | uniq -c
  exit 1
fi
echo "check_cpu_features: OK"
