#!/usr/bin/env bash
# Exploration demo: sim_bridge + explorer as two ROS processes on sim time, watched by a
# monitor (scripts/demo.py). Usage:
#   [LIVE=1] scripts/run_demo.sh [OUT] [extra scripts/demo.py options...]
# Defaults: OUT=out/demo, the embedded cluttered house (DEMO_WORLD), real-time factor
# DEMO_RTF (4; 1 with LIVE=1), sim-time limit DEMO_MAX_SIM_TIME (1500 s).
# Headless (LIVE=0, the default): ROS discovery stays on localhost with a private
# ROS_DOMAIN_ID and, where the kernel allows it, everything runs in a private network
# namespace (loopback only), so nothing outside can see or disturb it.
# LIVE=1: no network namespace, so RViz on this machine can watch; discovery still stays on
# localhost (ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST) on a printed ROS_DOMAIN_ID, and the
# script prints the rviz2 command that opens config/explore_seg.rviz on it.
# DEMO_DRY_RUN=1 prints what would run and exits (the tests use it).
set -uo pipefail
cd "$(dirname "$0")/.."
ROOT=$(pwd)
OUT=${1:-out/demo}
shift || true
PY=.venv/bin/python
LIVE=${LIVE:-0}
case "$LIVE" in
  0|1) ;;
  *) echo "[demo] LIVE must be 0 or 1, got '$LIVE'" >&2; exit 2 ;;
esac
if [ "$LIVE" = 1 ]; then RTF=${DEMO_RTF:-1}; else RTF=${DEMO_RTF:-4}; fi
MAX_SIM=${DEMO_MAX_SIM_TIME:-1500}
for v in "$RTF" "$MAX_SIM"; do
  if ! awk -v x="$v" 'BEGIN { exit !(x ~ /^[0-9]*\.?[0-9]+([eE][-+]?[0-9]+)?$/ && x + 0 > 0) }'; then
    echo "[demo] DEMO_RTF and DEMO_MAX_SIM_TIME must be numbers > 0, got '$v'" >&2
    exit 2
  fi
done
unset _ROS_WHEELS_BOOTSTRAP_COMPLETE || true
export ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST
export ROS_DOMAIN_ID=${ROS_DOMAIN_ID:-$(( 20 + $$ % 70 ))}
export PYTHONDONTWRITEBYTECODE=1
cmd=("$PY" scripts/demo.py "$OUT" --world "${DEMO_WORLD:-house_cluttered}"
     --rtf "$RTF" --max-sim-time "$MAX_SIM")
if [ "$LIVE" = 1 ]; then
  # The wall-clock limit follows the real-time factor: the sim-time limit at RTF, plus 5 min.
  cmd+=(--wall-timeout "$(awk -v s="$MAX_SIM" -v r="$RTF" 'BEGIN { printf "%.0f", s / r + 300 }')")
fi
cmd+=("$@")

if [ "${DEMO_DRY_RUN:-0}" = 1 ]; then
  echo "[demo] dry run: LIVE=$LIVE ROS_DOMAIN_ID=$ROS_DOMAIN_ID ROS_AUTOMATIC_DISCOVERY_RANGE=$ROS_AUTOMATIC_DISCOVERY_RANGE"
fi
if [ "$LIVE" = 1 ]; then
  echo "[demo] live: no network namespace, ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST, ROS_DOMAIN_ID=$ROS_DOMAIN_ID, real-time factor $RTF"
  echo "[demo] watch it in RViz from another terminal of this machine (a ROS 2 Jazzy install with rviz2):"
  echo "  ROS_DOMAIN_ID=$ROS_DOMAIN_ID ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST rviz2 -d $ROOT/config/explore_seg.rviz --ros-args -p use_sim_time:=true"
  echo "[demo] (sim_bridge publishes no TF: the scan and odom displays stay empty; map, regions, objects, frontiers, goal, pose and plan are in the map frame)"
fi
if [ "${DEMO_DRY_RUN:-0}" = 1 ]; then
  printf '[demo] would run:'; printf ' %q' "${cmd[@]}"; echo
  exit 0
fi
if ! "$PY" -c "import rclpy" 2>/dev/null; then
  echo "[demo] FAILED: $PY cannot import rclpy; run 'make setup' first" >&2
  exit 1
fi
mkdir -p "$OUT"

if [ "$LIVE" = 1 ]; then
  "${cmd[@]}"
elif [ "${EXPLORE_SEG_NO_NETNS:-0}" != 1 ] && unshare -n true 2>/dev/null; then
  echo "[demo] private network namespace (unshare -n), ROS_DOMAIN_ID=$ROS_DOMAIN_ID"
  unshare -n sh -c 'ip link set lo up && exec "$@"' sh "${cmd[@]}"
elif [ "${EXPLORE_SEG_NO_NETNS:-0}" != 1 ] && unshare -rn true 2>/dev/null; then
  echo "[demo] private user+network namespace (unshare -rn), ROS_DOMAIN_ID=$ROS_DOMAIN_ID"
  unshare -rn sh -c 'ip link set lo up && exec "$@"' sh "${cmd[@]}"
else
  echo "[demo] no network namespace available: LOCALHOST discovery, ROS_DOMAIN_ID=$ROS_DOMAIN_ID"
  "${cmd[@]}"
fi
