#!/usr/bin/env bash
# Installs the Debian 12 packages diffsim-bench needs, only those that are missing.
# Safe to run again: when everything is present it changes nothing and needs no network.
set -euo pipefail

packages=(
  build-essential cmake pkg-config git clang-format
  libeigen3-dev libsqlite3-dev sqlite3
  libnlopt-cxx-dev libgtest-dev libgmock-dev libbenchmark-dev
  libcli11-dev nlohmann-json3-dev libfmt-dev libsleef-dev zlib1g-dev libgd-dev
  libmujoco-dev libqhull-dev libbullet-dev
  python3 python3-pandas python3-matplotlib python3-scipy python3-optuna
  python3-dev python3-numpy pybind11-dev
  slurmctld slurmd slurm-client munge
  firefox-esr
)
# firefox-esr (about 350 MB with its libraries, --no-install-recommends) only for the report's
# headless screenshot test (ctest -L long, tests/report_screenshot_test.py; skipped without it)

missing=()
for p in "${packages[@]}"; do
  status=$(dpkg-query -W -f='${Status}' "$p" 2>/dev/null || true)
  [[ "$status" == "install ok installed" ]] || missing+=("$p")
done

if ((${#missing[@]} == 0)); then
  echo "install-deps: all ${#packages[@]} packages present"
  exit 0
fi

sudo_cmd=()
if [[ $(id -u) -ne 0 ]]; then
  command -v sudo >/dev/null || { echo "install-deps: need root or sudo to install: ${missing[*]}" >&2; exit 2; }
  sudo_cmd=(sudo)
fi

echo "install-deps: installing ${missing[*]}"
export DEBIAN_FRONTEND=noninteractive
"${sudo_cmd[@]}" apt-get update -qq
"${sudo_cmd[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
echo "install-deps: done"
