#!/usr/bin/env bash
# Installs what is missing, builds inlay in release mode and runs it.
# Default: open the viewer on the bundled DOG scene (drag the silver ball
# across the field); without a display it renders the same view headless to
# inlay-view.png in the current directory. The field and the object's SSDF
# are baked on first use and cached.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
"$root/tools/ensure-deps.sh"
export PATH="$HOME/.cargo/bin:$PATH"
cargo build --release --manifest-path "$root/Cargo.toml" --bin inlay
if [ "$#" -eq 0 ]; then
  set -- view "$root/scenes/dog.toml"
fi
exec "$root/target/release/inlay" "$@"
