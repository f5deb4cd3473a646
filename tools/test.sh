#!/usr/bin/env bash
# Installs what is missing, builds, and runs every test on the Vulkan device
# the engine picks (Mesa's lavapipe on a machine without a GPU), with the
# validation layer on: any validation error fails the tests.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
"$root/tools/ensure-deps.sh"
export PATH="$HOME/.cargo/bin:$PATH"
cd "$root"
cargo test --workspace --all-targets "$@"
