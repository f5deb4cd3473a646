#!/usr/bin/env bash
# Installs what is missing, builds inlay in release mode and runs it.
# Default: the engine demo (a window when a display exists, else headless
# images inlay-demo.exr/.png in the current directory).
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
"$root/tools/ensure-deps.sh"
export PATH="$HOME/.cargo/bin:$PATH"
cargo build --release --manifest-path "$root/Cargo.toml" --bin inlay
if [ "$#" -eq 0 ]; then
  set -- demo
fi
exec "$root/target/release/inlay" "$@"
