#!/usr/bin/env python3
"""Benchmark the 2D detector: p50/p95 milliseconds per 640x480 frame.

Times the whole :meth:`Detector.detect` (letterbox, network, decoding, NMS) for the torch
and onnx backends at input sizes 320 and 416 on each device present (``detector.device``:
the CPU always; CUDA for torch when ``torch.cuda.is_available()``, also in fp16; onnxruntime's
TensorRT / CUDA providers when its build has them), plus the oracle backend on a synthetic
semantic image. Prints, never asserts. Times the real frame ``tum_fr3_office`` of the test
data (``test/data/rgbd``). Target: <= 30 ms per frame on 2 CPU threads.

Usage::

    python bench/bench_detector.py [--iterations 30] [--warmup 3] [--threads 2] [--cpu-only]
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import cv2
import numpy as np

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

from explore_seg.core.detector import Detector, DetectorParams  # noqa: E402
from explore_seg.core.detector.devices import ONNX_GPU_PROVIDERS  # noqa: E402

FRAME = ROOT / "test" / "data" / "rgbd" / "tum_fr3_office_color.png"
FRAME_HW = (480, 640)


def _frame() -> tuple[np.ndarray, str]:
    img = cv2.imread(str(FRAME))
    if img is None:
        raise SystemExit(f"cannot read the benchmark frame {FRAME}")
    return cv2.cvtColor(img, cv2.COLOR_BGR2RGB), FRAME.name


def _time(fn, iterations: int, warmup: int) -> tuple[float, float, int]:
    for _ in range(warmup):
        fn()
    times = []
    n = 0
    for _ in range(iterations):
        t0 = time.perf_counter()
        n = len(fn())
        times.append((time.perf_counter() - t0) * 1e3)
    return float(np.percentile(times, 50)), float(np.percentile(times, 95)), n


def device_runs(cpu_only: bool) -> list[tuple[str, str, bool]]:
    """(backend, device, half) to time: the CPU, plus the GPU devices this machine has."""
    runs = [("torch", "cpu", False), ("onnx", "cpu", False)]
    if cpu_only:
        return runs
    try:
        import torch
        if torch.cuda.is_available():
            runs += [("torch", "cuda", False), ("torch", "cuda", True)]
    except ImportError:
        pass
    try:
        import onnxruntime as ort
        if set(ort.get_available_providers()) & set(ONNX_GPU_PROVIDERS):
            runs.append(("onnx", "cuda", False))
    except ImportError:
        pass
    return runs


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--iterations", type=int, default=30)
    parser.add_argument("--warmup", type=int, default=3)
    parser.add_argument("--threads", type=int, default=2)
    parser.add_argument("--cpu-only", action="store_true", help="skip GPU devices")
    args = parser.parse_args(argv)
    rgb, source = _frame()
    print(f"frame: {source} {rgb.shape[1]}x{rgb.shape[0]}, threads {args.threads}, "
          f"{args.iterations} iterations (machine load inflates these numbers)")
    print(f"{'backend':>8} {'device':>22} {'size':>5} {'load_s':>7} {'p50_ms':>8} "
          f"{'p95_ms':>8} {'dets':>5}")
    for backend, device, half in device_runs(args.cpu_only):
        for size in (320, 416):
            t0 = time.perf_counter()
            det = Detector(DetectorParams(backend=backend, input_size=size, device=device,
                                          half=half, num_threads=args.threads))
            load_s = time.perf_counter() - t0
            if det.device_note:
                print(f"  ({det.device_note})")
            p50, p95, n = _time(lambda: det.detect(rgb), args.iterations, args.warmup)
            print(f"{backend:>8} {det.device_name[:22]:>22} {size:>5} {load_s:>7.2f} "
                  f"{p50:>8.1f} {p95:>8.1f} {n:>5}")
    semantic = np.zeros(FRAME_HW, np.uint8)
    semantic[200:400, 50:250] = 1
    semantic[250:450, 350:600] = 2
    oracle = Detector(DetectorParams(backend="oracle", oracle_jitter_px=2.0),
                      sim_class_ids={"chair": 1, "table": 2})
    p50, p95, n = _time(lambda: oracle.detect(rgb, semantic=semantic), args.iterations,
                        args.warmup)
    print(f"{'oracle':>8} {'-':>22} {'-':>5} {'-':>7} {p50:>8.1f} {p95:>8.1f} {n:>5}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
