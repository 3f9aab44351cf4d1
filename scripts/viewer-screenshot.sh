#!/usr/bin/env bash
# Captures a screenshot of the running viewer under a virtual X server
# (no GPU, no display: Mesa's software OpenGL through the glow renderer) and
# saves it as docs/img/viewer.png (or OUT). Usage:
#   scripts/viewer-screenshot.sh [PROBLEM] [ITERATIONS] [OUT]
# e.g. scripts/viewer-screenshot.sh scenes/problems/layout.toml 6 docs/img/viewer.png
# The viewer runs ITERATIONS iterations (`--autorun`), waits for the render
# to refine and the overlay to arrive, saves the window (`--screenshot`) and
# quits. EPSM_VIEWER=path/to/epsm-viewer uses that binary instead of a
# release build. On Debian, as root, it installs what it needs first:
#   xvfb (the X server), libgl1 + libgl1-mesa-dri (software OpenGL through
#   GLX), libx11-6, libx11-xcb1, libxcursor1, libxi6, libxkbcommon-x11-0
#   (loaded at run time by winit/glutin; checked with LD_DEBUG=files).
set -euo pipefail
cd "$(dirname "$0")/.."
problem=${1:-scenes/problems/layout.toml}
iterations=${2:-6}
out=${3:-docs/img/viewer.png}
packages=(xvfb libgl1 libgl1-mesa-dri libx11-6 libx11-xcb1 libxcursor1 libxi6 libxkbcommon-x11-0)
if ! command -v Xvfb > /dev/null || ! dpkg -s "${packages[@]}" > /dev/null 2>&1; then
  if [ "$(id -u)" -ne 0 ]; then
    echo "needs: ${packages[*]} (run as root to install them)" >&2
    exit 1
  fi
  apt-get update -qq
  DEBIAN_FRONTEND=noninteractive apt-get install -y -qq "${packages[@]}"
fi
viewer=${EPSM_VIEWER:-}
if [ -z "$viewer" ]; then
  cargo build --release -p epsm-viewer
  viewer=${CARGO_TARGET_DIR:-target}/release/epsm-viewer
fi
display=:97
Xvfb "$display" -screen 0 1600x1000x24 -nolisten tcp &
xvfb=$!
config=$(mktemp -d)
trap 'kill "$xvfb" 2> /dev/null || true; rm -rf "$config"' EXIT
sleep 1
# Software rendering; no accessibility bus on a bare X server; a throwaway
# recent-files list.
XDG_CONFIG_HOME=$config DISPLAY=$display LIBGL_ALWAYS_SOFTWARE=1 NO_AT_BRIDGE=1 \
  timeout 900 "$viewer" "$problem" \
  --autorun "$iterations" --screenshot "$out" --size 1560x960 \
  --overlay arrows,flow,matching
echo "saved $out"
