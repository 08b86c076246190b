#!/bin/sh
# make demo: renders the Cornell box with every method into out/, then
# relights the radiosity bake with scenes/cornell-box/emissions.json.
#   scripts/demo.sh BUILD_DIR OUT_DIR
set -eu
BIN=${1:-build/release}
OUT=${2:-out}
SRC=$(cd "$(dirname "$0")/.." && pwd)
mkdir -p "$OUT"
for job in "$SRC"/scenes/cornell-box/*.json; do
    [ "$(basename "$job")" = scene.json ] && continue
    # Only job files (they name a method) are rendered.
    grep -q '"method"' "$job" || continue
    echo "== $(basename "$job")"
    "$BIN/gi" render "$job" --out "$OUT"
done
# New light for the radiosity bake, from the factorization it left: no
# form factors, milliseconds (README, docs/job-format.md "gi relight").
echo "== relight: radiosity.json emissions.json"
box="$SRC/scenes/cornell-box"
"$BIN/gi" relight "$box/radiosity.json" "$box/emissions.json" --out "$OUT"
echo
echo "Outputs are in $OUT/ (an animation's frames as one line):"
# NAME.0003.EXT files of one sequence as NAME.####.EXT (N frames).
ls -1 "$OUT" | awk -v out="$OUT" '
    { key = $0; seq = sub(/\.[0-9][0-9][0-9][0-9]+\./, ".####.", key)
      if (!(key in n)) { order[++k] = key; isseq[key] = seq }
      n[key]++ }
    END { for (i = 1; i <= k; i++) {
            key = order[i]
            if (!isseq[key]) printf "  %s/%s\n", out, key
            else printf "  %s/%s (%d frame%s)\n", out, key, n[key], n[key] == 1 ? "" : "s" } }'
