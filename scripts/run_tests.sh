#!/usr/bin/env bash
# Run the test suite the way CI does: ROS discovery on localhost only, a private domain id,
# and, where the kernel allows it, inside a private network namespace with loopback up, so
# no DDS packet can leave this machine. Extra arguments go to pytest.
set -uo pipefail
cd "$(dirname "$0")/.."
PY=.venv/bin/python
unset _ROS_WHEELS_BOOTSTRAP_COMPLETE || true
export ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST
export ROS_DOMAIN_ID=${ROS_DOMAIN_ID:-$(( 20 + $$ % 70 ))}
export ROS_LOG_DIR=${ROS_LOG_DIR:-$(mktemp -d -t explore_seg_roslog.XXXXXX)}
export PYTHONDONTWRITEBYTECODE=1
cmd=("$PY" -m pytest -p no:dash -p no:cacheprovider "$@")

if [ "${EXPLORE_SEG_NO_NETNS:-0}" != 1 ] && unshare -n true 2>/dev/null; then
  echo "[test] private network namespace (unshare -n), loopback only, ROS_DOMAIN_ID=$ROS_DOMAIN_ID"
  unshare -n sh -c 'ip link set lo up && exec "$@"' sh "${cmd[@]}"
  rc=$?
elif [ "${EXPLORE_SEG_NO_NETNS:-0}" != 1 ] && unshare -rn true 2>/dev/null; then
  echo "[test] private user+network namespace (unshare -rn), ROS_DOMAIN_ID=$ROS_DOMAIN_ID"
  unshare -rn sh -c 'ip link set lo up && exec "$@"' sh "${cmd[@]}"
  rc=$?
else
  echo "[test] no network namespace available: LOCALHOST discovery only, ROS_DOMAIN_ID=$ROS_DOMAIN_ID"
  "${cmd[@]}"
  rc=$?
fi
if [ $rc -eq 5 ]; then
  echo "[test] FAILED: pytest collected no tests (exit 5)" >&2
  exit 1
fi
exit $rc
