#!/usr/bin/env bash
# Headless exploration demo: sim_bridge + explorer as two ROS processes on sim time,
# faster than real time, watched by a monitor (scripts/demo.py). Usage:
#   scripts/run_demo.sh [OUT] [extra scripts/demo.py options...]
# Defaults: OUT=out/demo, the embedded cluttered house (DEMO_WORLD), real-time factor
# DEMO_RTF. ROS discovery stays on localhost with a private ROS_DOMAIN_ID and, where the
# kernel allows it, everything runs in a private network namespace (loopback only).
set -uo pipefail
cd "$(dirname "$0")/.."
OUT=${1:-out/demo}
shift || true
PY=.venv/bin/python
if ! "$PY" -c "import rclpy" 2>/dev/null; then
  echo "[demo] FAILED: $PY cannot import rclpy; run 'make setup' first" >&2
  exit 1
fi
unset _ROS_WHEELS_BOOTSTRAP_COMPLETE || true
export ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST
export ROS_DOMAIN_ID=${ROS_DOMAIN_ID:-$(( 20 + $$ % 70 ))}
export PYTHONDONTWRITEBYTECODE=1
mkdir -p "$OUT"
cmd=("$PY" scripts/demo.py "$OUT" --world "${DEMO_WORLD:-house_cluttered}"
     --rtf "${DEMO_RTF:-4}" --max-sim-time "${DEMO_MAX_SIM_TIME:-1500}" "$@")

if [ "${EXPLORE_SEG_NO_NETNS:-0}" != 1 ] && unshare -n true 2>/dev/null; then
  echo "[demo] private network namespace (unshare -n), ROS_DOMAIN_ID=$ROS_DOMAIN_ID"
  unshare -n sh -c 'ip link set lo up && exec "$@"' sh "${cmd[@]}"
elif [ "${EXPLORE_SEG_NO_NETNS:-0}" != 1 ] && unshare -rn true 2>/dev/null; then
  echo "[demo] private user+network namespace (unshare -rn), ROS_DOMAIN_ID=$ROS_DOMAIN_ID"
  unshare -rn sh -c 'ip link set lo up && exec "$@"' sh "${cmd[@]}"
else
  echo "[demo] no network namespace available: LOCALHOST discovery, ROS_DOMAIN_ID=$ROS_DOMAIN_ID"
  "${cmd[@]}"
fi
