#!/usr/bin/env bash
# Open a Rerun recording in the real Rerun viewer (native, under a virtual X display with
# software Vulkan) and save a screenshot of its window.
#
# Usage: tools/rerun_screenshot.sh RECORDING.rrd SCREENSHOT.png [WIDTHxHEIGHT]
#
# Installs what it needs, outside the repository:
#   * the Rerun viewer: `pip install rerun-sdk==<the SDK version in Cargo.lock>` into a venv
#     ($TREAD_SCREENSHOT_VENV, default ~/.cache/tread/rerun-venv);
#   * Xvfb, Mesa's software Vulkan driver (lavapipe) and the X11 libraries of the viewer, from
#     Debian packages with apt-get, when Xvfb or the lavapipe driver is missing (needs root).
# When an install fails (no network, not root, no apt-get) it says what is missing and exits 1:
# no screenshot is made without the real viewer.
#
# How: `rerun --screenshot-to FILE --window-size WxH RECORDING` on a fresh Xvfb display; the
# viewer draws with Vulkan on lavapipe (`--renderer gl` fails there on a texture format), and
# --screenshot-to captures the frame itself, so Xvfb needs no Composite extension.
set -euo pipefail
die() { echo "rerun_screenshot: $*" >&2; exit 1; }
[ $# -ge 2 ] || die "usage: $0 RECORDING.rrd SCREENSHOT.png [WIDTHxHEIGHT]"
REC=$(realpath "$1")
OUT=$(realpath -m "$2")
SIZE=${3:-1600x1000}
[ -f "$REC" ] || die "no such recording: $1"
ROOT=$(cd "$(dirname "$0")/.." && pwd)
VERSION=$(awk '/^name = "rerun"$/ { getline; gsub(/[^0-9.]/, ""); print; exit }' "$ROOT/Cargo.lock")
[ -n "$VERSION" ] || die "cannot read the rerun version from Cargo.lock"
VENV=${TREAD_SCREENSHOT_VENV:-$HOME/.cache/tread/rerun-venv}

# 1. The viewer, at the SDK's exact version.
if ! "$VENV/bin/rerun" --version 2>/dev/null | grep -q "rerun-cli $VERSION "; then
    python3 -m venv "$VENV" || die "cannot create the venv $VENV (python3 -m venv)"
    "$VENV/bin/pip" install -q --disable-pip-version-check "rerun-sdk==$VERSION" \
        || die "cannot install rerun-sdk==$VERSION from PyPI (no network?)"
fi

# 2. Xvfb and software Vulkan from Debian packages.
lavapipe() { ls /usr/share/vulkan/icd.d/lvp_icd*.json >/dev/null 2>&1; }
if ! command -v Xvfb >/dev/null || ! lavapipe; then
    command -v apt-get >/dev/null || die "Xvfb or Mesa's lavapipe Vulkan driver is missing and there is no apt-get: install Xvfb and Mesa's Vulkan drivers by hand"
    SUDO=""
    [ "$(id -u)" = 0 ] || SUDO="sudo -n"
    echo "rerun_screenshot: installing xvfb, mesa-vulkan-drivers and X11 libraries with apt-get" >&2
    if ! { $SUDO apt-get update -qq && DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq \
            xvfb mesa-vulkan-drivers libvulkan1 libxkbcommon-x11-0 libxcursor1 libxrandr2 libxi6 \
            libx11-xcb1 libgl1 >/dev/null; }; then
        die "apt-get could not install xvfb and mesa-vulkan-drivers (no network, or not root?); no screenshot made"
    fi
    command -v Xvfb >/dev/null && lavapipe || die "Xvfb or the lavapipe driver is still missing after apt-get"
fi

# 3. A virtual display, the viewer, the screenshot.
DISPLAY_NUM=$(( 90 + RANDOM % 100 ))
W=${SIZE%x*}
H=${SIZE#*x}
# The screen is larger than the window (at the top left) so that the pointer, which starts at
# the screen centre, does not hover over the window and open a tooltip in the picture.
Xvfb ":$DISPLAY_NUM" -screen 0 "$((3 * W))x$((3 * H))x24" -nolisten tcp >/dev/null 2>&1 &
XVFB=$!
trap 'kill "$XVFB" 2>/dev/null || true' EXIT
sleep 1
kill -0 "$XVFB" 2>/dev/null || die "Xvfb did not start on :$DISPLAY_NUM"
rm -f "$OUT"
RUNDIR=$(mktemp -d)
trap 'kill "$XVFB" 2>/dev/null || true; rm -rf "$RUNDIR"' EXIT
# The viewer's own server listens on the loopback address only, on a free-ish port. Rerun 0.36.3
# panics while quitting after --screenshot-to ("Failed to take store hub"), after the file is
# written: its exit status is reported, the file decides.
set +e
DISPLAY=":$DISPLAY_NUM" XDG_RUNTIME_DIR="$RUNDIR" WINIT_X11_SCALE_FACTOR=1 \
    VK_ICD_FILENAMES=$(ls /usr/share/vulkan/icd.d/lvp_icd*.json | head -1) \
    timeout 180 "$VENV/bin/rerun" --bind 127.0.0.1 --port $(( 20000 + RANDOM % 20000 )) \
    --renderer vulkan --window-size "$SIZE" --screenshot-to "$OUT" "$REC" >"$RUNDIR/viewer.log" 2>&1
STATUS=$?
set -e
if [ ! -s "$OUT" ]; then
    tail -n 30 "$RUNDIR/viewer.log" >&2
    die "the viewer (exit status $STATUS) wrote no screenshot"
fi
[ "$STATUS" = 0 ] || echo "rerun_screenshot: note: the viewer exited with status $STATUS after writing the screenshot" >&2
echo "rerun_screenshot: $OUT ($(stat -c %s "$OUT") bytes) from $REC with rerun $VERSION"
