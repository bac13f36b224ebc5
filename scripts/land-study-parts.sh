#!/usr/bin/env bash
# Copies a variant study's finished parts (OUTDIR/parts/ENV__LABEL.csv, scripts/lib/variant-study.sh)
# into the folder they are committed from (data/STUDY/), so that a study longer than one machine's
# life loses nothing when the machine goes:
#   scripts/land-study-parts.sh OUTDIR DEST
# New parts are copied; a part DEST already holds with the same bytes is left alone; one that
# differs is refused (exit 2, naming both files, nothing copied): a landed part is the study's
# record and is never written over. Prints what it copied.
set -euo pipefail
out=${1:?usage: land-study-parts.sh OUTDIR DEST}
dest=${2:?usage: land-study-parts.sh OUTDIR DEST}
[[ -d $out/parts ]] || { echo "land-study-parts: no parts folder in '$out'" >&2; exit 2; }
[[ -d $dest ]] || { echo "land-study-parts: no folder '$dest'" >&2; exit 2; }
new=()
for f in "$out"/parts/*.csv; do
  [[ -e $f ]] || continue
  landed=$dest/$(basename "$f")
  if [[ -e $landed ]]; then
    cmp -s "$f" "$landed" || { echo "land-study-parts: $landed differs from $f: a landed part is never replaced" >&2; exit 2; }
    continue
  fi
  new+=("$f")
done
for f in "${new[@]}"; do
  cp "$f" "$dest/$(basename "$f").tmp"
  mv "$dest/$(basename "$f").tmp" "$dest/$(basename "$f")"
  echo "landed: $(basename "$f")"
done
echo "land-study-parts: ${#new[@]} new part(s) in $dest"
