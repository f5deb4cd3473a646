#!/usr/bin/env bash
# Installs what inlay needs on Debian/Ubuntu when it is missing: the Vulkan
# loader, Mesa's lavapipe (a CPU Vulkan device, so no GPU is required), the
# Khronos validation layer, the X11 client libraries the window uses, and Xvfb
# for the window tests. Uses sudo when not root. Checks that cargo exists.
set -euo pipefail

packages=(libvulkan1 mesa-vulkan-drivers vulkan-validationlayers
          libx11-6 libx11-xcb1 libxcursor1 libxi6 libxkbcommon-x11-0 xvfb)
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if ((${#missing[@]})); then
  echo "installing: ${missing[*]}" >&2
  sudo=""
  [ "$(id -u)" -eq 0 ] || sudo=sudo
  $sudo apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi

if ! command -v cargo >/dev/null 2>&1; then
  if [ -x "$HOME/.cargo/bin/cargo" ]; then
    echo "note: add \$HOME/.cargo/bin to PATH" >&2
  else
    echo "error: cargo (Rust 1.85 or newer) is not installed; install it with rustup (see the README) and run this again" >&2
  fi
  exit 1
fi
