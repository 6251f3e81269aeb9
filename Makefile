# explore_seg: the one entry point. `make demo` and `make test` set up what is missing first.
SHELL := /bin/bash
PY := .venv/bin/python
OUT ?= out/demo
LIVE ?= 0
BENCH_OUT ?= out/bench
RUNS ?= 20
QUICK_OUT ?= out/bench-quick

PREDICTOR_SEED ?= 0

.PHONY: help setup test demo bench bench-report bench-quick build clean train-predictor

help:
	@echo "make demo   - headless exploration demo on the embedded cluttered house -> $(OUT)/"
	@echo "make demo LIVE=1 - the same at real time, watchable in RViz (prints the rviz2 command)"
	@echo "make test   - the test suite (private network namespace where possible)"
	@echo "make bench  - the full matrix: every strategy x 20 worlds x $(RUNS) runs (10 in maze, office_floor) -> $(BENCH_OUT)/, BENCHMARKS.md; again: continues (--resume)"
	@echo "make bench SHARD=K/N - the K-th of N slices of the matrix (one per machine) -> $(BENCH_OUT)/"
	@echo "make bench-report - BENCHMARKS.md again from $(BENCH_OUT)/ (one code version; BENCH_ARGS=--allow-mixed to mark mixed ones)"
	@echo "make bench-quick - a representative subset (~10 min on 2 cores) -> $(QUICK_OUT)/QUICK.md, ratios vs bench/results/matrix"
	@echo "make build  - colcon build of the package into build/ install/"
	@echo "make setup  - only the idempotent set-up (venv, apt packages, detector weights)"
	@echo "make train-predictor - train the floor-plan predictor on generated plans (seed PREDICTOR_SEED, 1 CPU thread) -> explore_seg/core/prediction/weights/"

setup:
	@bash scripts/setup_env.sh

test: setup
	@bash scripts/run_tests.sh $(PYTEST_ARGS)

demo: setup
	@LIVE=$(LIVE) bash scripts/run_demo.sh $(OUT)

bench: setup
	@BENCH_RESUME=1 bash scripts/run_bench.sh $(BENCH_OUT) $(RUNS) $(if $(SHARD),--shard $(SHARD))

bench-report: setup
	@$(PY) bench/report.py $(BENCH_OUT) $(BENCH_ARGS)

bench-quick: setup
	@bash scripts/run_bench.sh --quick $(QUICK_OUT)

train-predictor: setup
	@nice -n 19 $(PY) bench/train_predictor.py --seed $(PREDICTOR_SEED)

build: setup
	@unset _ROS_WHEELS_BOOTSTRAP_COMPLETE; . .venv/bin/activate && colcon build --base-paths . --build-base build --install-base install

clean:
	rm -rf build install log out
