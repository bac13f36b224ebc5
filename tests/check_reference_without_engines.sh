#!/usr/bin/env bash
# The reference adapters build without MuJoCo and Bullet (cmake -DDSB_WITH_MUJOCO=OFF
# -DDSB_WITH_BULLET=OFF, or a machine without them): every reference/*.cpp is compiled, syntax
# only, with neither DSB_HAVE_MUJOCO nor DSB_HAVE_BULLET defined, so the code outside their #if
# blocks must stand on its own.
#   tests/check_reference_without_engines.sh SOURCE_DIR CXX EIGEN_INCLUDE_DIR
set -euo pipefail
src=${1:?usage: check_reference_without_engines.sh SOURCE_DIR CXX EIGEN_INCLUDE_DIR}
cxx=${2:?usage: check_reference_without_engines.sh SOURCE_DIR CXX EIGEN_INCLUDE_DIR}
eigen=${3:?usage: check_reference_without_engines.sh SOURCE_DIR CXX EIGEN_INCLUDE_DIR}
failed=0 checked=0
for f in "$src"/reference/*.cpp; do
  checked=$((checked + 1))
  if ! "$cxx" -std=c++20 -fsyntax-only -I"$src" -I"$eigen" -UDSB_HAVE_MUJOCO -UDSB_HAVE_BULLET "$f"; then
    echo "reference without engines: ${f#"$src"/} does not compile" >&2
    failed=$((failed + 1))
  fi
done
echo "reference without engines: $checked files, $failed failed"
((failed == 0))
