#!/usr/bin/env bash
# Renders what must not change when the code is reorganised, into OUT:
# every bundled scene from each of its cameras with and without its
# objects (linear EXR), the probe and fit at each scene's first object
# (EXR), and the profiler's pass list with its skip reasons (text).
# Compare two such folders with
#   INLAY_GUARD_BEFORE=A INLAY_GUARD_AFTER=B \
#     cargo test --release --test render_guard -- --ignored
# (images within 1e-6 relative, pass lists identical).
# Usage: tools/guard-renders.sh OUT [INLAY_BINARY]
set -euo pipefail
out=${1:?usage: tools/guard-renders.sh OUT [INLAY_BINARY]}
inlay=${2:-target/release/inlay}
mkdir -p "$out"
for scene in scenes/*.toml; do
  name=$(basename "$scene" .toml)
  cameras=$(grep -c '^\[\[cameras\]\]' "$scene")
  for ((c = 0; c < cameras; c++)); do
    "$inlay" render "$scene" --camera "$c" --width 160 --height 90 --frames 2 \
      --out "$out/$name-$c-objects.exr" > /dev/null
    "$inlay" render "$scene" --camera "$c" --width 160 --height 90 --frames 1 \
      --no-objects --out "$out/$name-$c-bare.exr" > /dev/null
  done
  # The first object's position (the first `position` after `[[objects]]`).
  at=$(awk '/^\[\[objects\]\]/ { o = 1 } o && /^position/ { gsub(/[^0-9.,-]/, "", $0); print; exit }' "$scene")
  if [ -n "$at" ]; then
    "$inlay" probe "$scene" --at="$at" --out "$out/$name-probe.exr" > /dev/null
    "$inlay" profile "$scene" --width 160 --height 90 --frames 3 \
      --json "$out/$name-profile.json" --trace /dev/null > /dev/null
    # Pass names and skip reasons only (timings differ run to run).
    grep -o '"\(name\|reason\|module\)": *"[^"]*"' "$out/$name-profile.json" > "$out/$name-passes.txt"
    rm "$out/$name-profile.json"
  fi
done
ls "$out" | wc -l
