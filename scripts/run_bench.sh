#!/usr/bin/env bash
# Exploration benchmark (bench/run_bench.py): RUNS seeded lock-step runs per world x
# strategy, results + figures in OUT, summary in BENCHMARKS.md. Usage:
#   scripts/run_bench.sh [OUT] [RUNS] [extra run_bench.py options...]
# e.g. scripts/run_bench.sh out/bench 20 --worlds house,house_cluttered --jobs 2
# BENCH_ARGS (environment) is appended too, so `make bench BENCH_ARGS="--worlds maze"` works.
# BENCH_RESUME=1 adds --resume (what `make bench` does: running it again continues the
# matrix where it stopped). The last line printed is the matrix's wall time and CPU seconds.
# `scripts/run_bench.sh --quick [OUT] [extra options...]` runs bench/quick.py instead (the
# subset of `make bench-quick`, compared with bench/results/matrix).
set -uo pipefail
cd "$(dirname "$0")/.."
QUICK=0
if [ "${1:-}" = "--quick" ]; then QUICK=1; shift; fi
PY=.venv/bin/python
unset _ROS_WHEELS_BOOTSTRAP_COMPLETE || true
export ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST
export ROS_DOMAIN_ID=${ROS_DOMAIN_ID:-$(( 20 + $$ % 70 ))}
export PYTHONDONTWRITEBYTECODE=1
# One thread per worker process: the pool already uses the cores.
export OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1 MKL_NUM_THREADS=1
if [ "$QUICK" = 1 ]; then
  OUT=${1:-out/bench-quick}
  shift 1 2>/dev/null || true
  # shellcheck disable=SC2086
  exec "$PY" bench/quick.py --out "$OUT" "$@" ${BENCH_ARGS:-}
fi
OUT=${1:-out/bench}
RUNS=${2:-20}
shift 2 2>/dev/null || shift $#
# shellcheck disable=SC2086
RESUME=()
if [ "${BENCH_RESUME:-0}" = 1 ]; then RESUME=(--resume); fi
exec "$PY" bench/run_bench.py --out "$OUT" --runs "$RUNS" "${RESUME[@]}" "$@" ${BENCH_ARGS:-}
