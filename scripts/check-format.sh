#!/usr/bin/env bash
# Fails on C++ that clang-format would change: every file named, or with none named every C++
# file git tracks (.cpp, .hpp, .cpp.in), against the repository's .clang-format.
#   scripts/check-format.sh [FILE...]
# Exit 0: all formatted; 1: not (each file named, with clang-format's first complaint);
# 2: no clang-format (Debian: clang-format, which scripts/install-deps.sh installs).
# Fix a file with: clang-format -i --style=file FILE
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
tool=${CLANG_FORMAT:-clang-format}
command -v "$tool" >/dev/null || { echo "check-format: no $tool (apt-get install clang-format)" >&2; exit 2; }
files=("$@")
if ((${#files[@]} == 0)); then
  mapfile -t files < <(git -C "$root" ls-files '*.cpp' '*.hpp' '*.cpp.in' | sed "s|^|$root/|")
fi
bad=0
for f in "${files[@]}"; do
  if ! out=$("$tool" --style="file:$root/.clang-format" --dry-run --Werror "$f" 2>&1); then
    echo "${f#"$root"/}: not formatted: $(grep -m1 -E 'error|warning' <<<"$out" || echo "$out" | head -1)"
    bad=$((bad + 1))
  fi
done
if ((bad > 0)); then
  echo "check-format: $bad of ${#files[@]} files not formatted (clang-format -i --style=file FILE)"
  exit 1
fi
echo "check-format: ${#files[@]} files formatted"
