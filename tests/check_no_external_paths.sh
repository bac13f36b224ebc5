#!/usr/bin/env bash
# The repository stands on its own: no tracked file points to a document outside it (the team's
# spec folder beside the checkout, its reference notes). Fails listing each file:line that does.
#   tests/check_no_external_paths.sh SOURCE_DIR
set -euo pipefail
src=${1:?usage: check_no_external_paths.sh SOURCE_DIR}
cd "$src"
self=tests/check_no_external_paths.sh
# a relative path up out of the checkout into a sibling "shared" folder, or the spec's file names
pattern='\.\./shared|shared/spec|spec/reference|[a-z]+-facts\.md|design\.md'
if git rev-parse --is-inside-work-tree >/dev/null 2>&1; then
  mapfile -t files < <(git ls-files | grep -v -x "$self")
else
  mapfile -t files < <(find . -type f -not -path './build*' -not -path './.git/*' -not -path "./$self" | sed 's|^\./||')
fi
if hits=$(grep -nIE "$pattern" -- "${files[@]}"); then
  echo "files that point outside the repository:" >&2
  echo "$hits" >&2
  exit 1
fi
echo "no file of ${#files[@]} points outside the repository"
