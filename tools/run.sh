#!/usr/bin/env bash
# Installs what is missing, builds inlay in release mode and runs it.
# Default: render the bundled CUPS scene at 1280x720 to inlay-cups.png in the
# current directory (baking its field first; the field is cached).
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
"$root/tools/ensure-deps.sh"
export PATH="$HOME/.cargo/bin:$PATH"
cargo build --release --manifest-path "$root/Cargo.toml" --bin inlay
if [ "$#" -eq 0 ]; then
  set -- render "$root/scenes/cups.toml" --width 1280 --height 720 --out inlay-cups.png
fi
exec "$root/target/release/inlay" "$@"
