#!/usr/bin/env python3
"""Side by side: the package's point-cloud steps and mean shift against Open3D and
scikit-learn on the inputs they get in the simulator, timings and whether outputs match.

Inputs are recorded, not made up: the calls of ``voxel_downsample``,
``statistical_outlier_mask`` and ``euclidean_clusters`` while the object pipeline processes
the simulator camera's frames at the viewpoints of ``test/test_object_layer_sim.py``
(``--cloud-world``), the synthetic room and, when present, the real frame ``tum_fr3_office`` of
``bench/bench_objects.py``; the point sets that rrt_exploration's filter passes to
``mean_shift`` during lock-step runs (``--rrt-world``, ``--rrt-seeds``,
``--rrt-sim-time``).

Per step and implementation it prints the per-call wall time (the best of ``--reps``
repeats of each input; median and p95 over the inputs, library conversions included) and
how many inputs give the same output as the package's function (exactly; for mean shift
also within 1e-9 m). The library versions:

* voxel: Open3D ``voxel_down_sample_and_trace`` on the package's grid (``floor(p / voxel)``,
  bounds on voxel edges), the first input point of each voxel and every point's voxel;
* SOR: Open3D ``remove_statistical_outlier(k + 1, std_ratio * sqrt((n - 1) / n))`` (its
  neighbours include the point itself; its standard deviation is the sample one);
* clusters: Open3D ``cluster_dbscan(tolerance, 1)`` (the components of the tolerance
  graph), the extra links (which ``cluster_dbscan`` does not take) joining components with
  scipy, relabelled by size; calls with and without extra links apart;
* mean shift: scikit-learn ``MeanShift(bandwidth).fit(points).cluster_centers_``.

``--import-cost`` also measures, in fresh processes, the import time and peak memory of
``explore_seg.object_costmap_node`` with and without ``import open3d``.

Prints, never asserts. Usage::

    .venv/bin/python bench/bench_libraries.py [--reps 3] [--import-cost]
"""

from __future__ import annotations

import argparse
import subprocess
import sys
import time
from pathlib import Path
from typing import Any, Callable

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
for extra in (ROOT, ROOT / "test"):
    if str(extra) not in sys.path:
        sys.path.insert(0, str(extra))

from bench.percentiles import pct  # noqa: E402
from explore_seg.core.objects import cloud  # noqa: E402
from explore_seg.core.rrt.mean_shift import mean_shift  # noqa: E402


# ------------------------------------------------------------------ recording the inputs
class Recorder:
    """Replaces module attributes by wrappers that keep a copy of every call's arguments."""

    def __init__(self) -> None:
        self.calls: dict[str, list[tuple[tuple, dict]]] = {}
        self._undo: list[tuple[Any, str, Any]] = []

    def wrap(self, module: Any, name: str, key: str) -> None:
        original = getattr(module, name)
        calls = self.calls.setdefault(key, [])

        def recorded(*args, **kwargs):
            calls.append((tuple(np.array(a, copy=True) if isinstance(a, np.ndarray) else a
                                for a in args), dict(kwargs)))
            return original(*args, **kwargs)

        self._undo.append((module, name, original))
        setattr(module, name, recorded)

    def restore(self) -> None:
        for module, name, original in reversed(self._undo):
            setattr(module, name, original)
        self._undo.clear()


def record_cloud_calls(world_name: str, max_views: int | None = None
                       ) -> dict[str, list[tuple[tuple, dict]]]:
    """Arguments of the point-cloud steps (keys ``voxel``, ``sor``, ``clusters``) over the
    simulator's frames (the first ``max_views`` viewpoints; all when None), the synthetic
    room and the real frame."""
    from bench import bench_objects
    from explore_seg.core.objects import (ObjectParams, boxes, detections, legs, load_priors,
                                          process_frame)
    from sim_bridge.worlds import default_world, ground_truth
    from test_object_layer_sim import plan_viewpoints, run_pipeline

    rec = Recorder()
    for mod in (detections, legs, boxes):
        for name, key in (("voxel_downsample", "voxel"), ("statistical_outlier_mask", "sor"),
                          ("euclidean_clusters", "clusters")):
            if hasattr(mod, name):
                rec.wrap(mod, name, key)
    try:
        world = default_world(world_name)
        gt = ground_truth(world)
        views = plan_viewpoints(world, gt)[:max_views]
        run_pipeline(world, gt, views)
        print(f"recorded {world_name}: {len(views)} simulator frames")
        params, priors = ObjectParams(), load_priors()
        frame, dets, scan = bench_objects.synthetic_case()
        process_frame(frame, dets, priors, params, scan)
        real = bench_objects.real_case()
        if real is not None:
            process_frame(real[0], real[1], priors, params)
        print(f"recorded the synthetic room{' and tum_fr3_office' if real else ''}")
    finally:
        rec.restore()
    return rec.calls


def record_mean_shift_calls(world_spec: str, seeds: list[int], sim_time_s: float
                            ) -> list[tuple[tuple, dict]]:
    """Arguments of ``mean_shift`` in rrt_exploration's filter during lock-step runs."""
    from bench.worlds import load
    from explore_seg.core.rrt import detector
    from sim_bridge.lockstep import LockstepParams, run_exploration

    rec = Recorder()
    rec.wrap(detector, "mean_shift", "mean_shift")
    try:
        world, gt = load(world_spec)
        for seed in seeds:
            r = run_exploration(world, "rrt_exploration", seed, ground_truth=gt,
                                params=LockstepParams(max_sim_time_s=sim_time_s))
            print(f"recorded {world_spec} seed {seed}: {r.coverage_pct:.1f} % coverage, "
                  f"{len(rec.calls['mean_shift'])} mean-shift calls so far")
    finally:
        rec.restore()
    return rec.calls["mean_shift"]


# ------------------------------------------------------------------ library versions
def _o3d_cloud(points: np.ndarray):
    import open3d as o3d
    pts = np.ascontiguousarray(np.asarray(points, dtype=np.float64)[:, :3])
    if pts.shape[1] < 3:
        pts = np.hstack([pts, np.zeros((len(pts), 3 - pts.shape[1]))])
    return o3d.geometry.PointCloud(o3d.utility.Vector3dVector(pts))


def voxel_open3d(points: np.ndarray, voxel_m: float, return_inverse: bool = False):
    """Open3D's voxel trace on the package's grid: first point per voxel (+ inverse)."""
    n = len(points)
    if voxel_m <= 0 or n == 0:
        keep = np.arange(n, dtype=np.int64)
        return (keep, keep.copy()) if return_inverse else keep
    pts = np.asarray(points, dtype=np.float64)
    lo = np.floor(pts.min(axis=0) / voxel_m) * voxel_m
    hi = (np.floor(pts.max(axis=0) / voxel_m) + 1.0) * voxel_m
    _, _, traced = _o3d_cloud(pts).voxel_down_sample_and_trace(voxel_m, lo, hi, False)
    members = [np.asarray(v, dtype=np.int64) for v in traced]
    firsts = np.array([m.min() for m in members], dtype=np.int64)
    order = np.argsort(firsts, kind="stable")
    keep = firsts[order]
    if not return_inverse:
        return keep
    rank = np.empty_like(order)
    rank[order] = np.arange(len(order))
    inverse = np.empty(n, dtype=np.int64)
    inverse[np.concatenate(members)] = np.repeat(rank, [len(m) for m in members])
    return keep, inverse


def sor_open3d(points: np.ndarray, k: int, std_ratio: float) -> np.ndarray:
    """Open3D's statistical outlier removal as a mask (k neighbours besides the point;
    the ratio scaled so that its sample standard deviation gives the package's threshold,
    which uses the population one)."""
    n = len(points)
    if n <= k:
        return np.ones(n, dtype=bool)
    ratio = std_ratio * np.sqrt((n - 1) / n)
    _, ind = _o3d_cloud(points).remove_statistical_outlier(k + 1, ratio)
    mask = np.zeros(n, dtype=bool)
    mask[np.asarray(ind, dtype=np.int64)] = True
    return mask


def clusters_open3d(points: np.ndarray, tolerance_m: float, min_points: int,
                    extra_edges: np.ndarray | None = None) -> np.ndarray:
    """Open3D DBSCAN with one point per core (the components of the tolerance graph), the
    extra links joining components, labels by decreasing size."""
    from scipy import sparse
    from scipy.sparse.csgraph import connected_components
    n = len(points)
    if n == 0:
        return np.zeros(0, dtype=np.int64)
    comp = np.asarray(_o3d_cloud(points).cluster_dbscan(tolerance_m, 1), dtype=np.int64)
    if extra_edges is not None and len(extra_edges):
        e = comp[np.asarray(extra_edges, dtype=np.int64).reshape(-1, 2)]
        m = int(comp.max()) + 1
        graph = sparse.coo_matrix((np.ones(len(e), dtype=np.int8), (e[:, 0], e[:, 1])),
                                  shape=(m, m))
        comp = connected_components(graph, directed=False)[1][comp]
    counts = np.bincount(comp)
    order = np.argsort(-counts, kind="stable")
    rank = np.empty_like(order)
    rank[order] = np.arange(len(order))
    labels = rank[comp]
    labels[counts[comp] < min_points] = -1
    return labels


def mean_shift_sklearn(points: np.ndarray, bandwidth: float) -> np.ndarray:
    from sklearn.cluster import MeanShift
    return MeanShift(bandwidth=bandwidth).fit(np.asarray(points, np.float64)).cluster_centers_


def _same_partition(a: np.ndarray, b: np.ndarray) -> bool:
    """Equal labels up to renaming clusters of equal size (the order among ties)."""
    if a.shape != b.shape:
        return False
    if np.array_equal(a, b):
        return True
    pairs = np.unique(np.stack([a, b], axis=1), axis=0)
    return len(np.unique(pairs[:, 0])) == len(pairs) == len(np.unique(pairs[:, 1])) and \
        np.array_equal(a < 0, b < 0)


# ------------------------------------------------------------------ timing and report
def best_time(fn: Callable[[], Any], reps: int) -> tuple[float, float, Any]:
    """(wall s, process CPU s, output) of the repeat with the least wall time."""
    best, cpu, out = np.inf, np.inf, None
    for _ in range(reps):
        t0, c0 = time.perf_counter(), time.process_time()
        out = fn()
        t1, c1 = time.perf_counter(), time.process_time()
        if t1 - t0 < best:
            best, cpu = t1 - t0, c1 - c0
    return best, cpu, out


def compare(label: str, calls: list[tuple[tuple, dict]], ours: Callable, lib: Callable,
            same: Callable[[Any, Any], bool], reps: int,
            close: Callable[[Any, Any], bool] | None = None) -> np.ndarray:
    """Print both implementations' ms per call (wall and process CPU) on the calls the
    library handles, and how many of them give the same output."""
    rows, n_na = [], 0
    for args, kwargs in calls:
        ta, ca, a = best_time(lambda: ours(*args, **kwargs), reps)
        tb, cb, b = best_time(lambda: lib(*args, **kwargs), reps)
        if b is None:
            n_na += 1
            continue
        rows.append((len(args[0]), ta * 1e3, ca * 1e3, tb * 1e3, cb * 1e3, bool(same(a, b)),
                     bool(close(a, b)) if close is not None else False))
    r = np.asarray(rows, dtype=np.float64).reshape(-1, 7)
    print(f"\n== {label}: {len(calls)} calls"
          + (f" ({n_na} not applicable, left out)" if n_na else "")
          + f"; points per call p50 {pct(r[:, 0], 50):.0f} p95 {pct(r[:, 0], 95):.0f} "
          f"max {r[:, 0].max(initial=0):.0f}")
    for name, col in (("package", 1), ("library", 3)):
        print(f"  {name}  ms/call wall p50 {pct(r[:, col], 50):8.3f} p95 "
              f"{pct(r[:, col], 95):8.3f}   CPU p50 {pct(r[:, col + 1], 50):8.3f} p95 "
              f"{pct(r[:, col + 1], 95):8.3f}   wall sum {r[:, col].sum():8.1f}")
    print(f"  same output: {int(r[:, 5].sum())} of {len(r)}"
          + (f"; within 1e-9: {int(r[:, 6].sum())} of {len(r)}" if close is not None else ""))
    return r


def _has_links(call: tuple[tuple, dict]) -> bool:
    args, kwargs = call
    edges = args[3] if len(args) > 3 else kwargs.get("extra_edges")
    return edges is not None and len(edges) > 0


def _voxel_same(a, b) -> bool:
    if isinstance(a, tuple):
        return all(np.array_equal(x, y) for x, y in zip(a, b))
    return np.array_equal(a, b)


def _centres(a) -> np.ndarray:
    return a[0] if isinstance(a, tuple) else a


def import_cost() -> None:
    """Import time and peak RSS of the object costmap node, with and without Open3D."""
    # Peak RSS from /proc (VmHWM): ru_maxrss survives exec, so a child reports its parent's.
    code = ("import time; t = time.perf_counter(); import explore_seg.object_costmap_node"
            "{extra}; dt = time.perf_counter() - t; "
            "hwm = [ln.split()[1] for ln in open('/proc/self/status') if ln.startswith('VmHWM')]; "
            "print(dt, int(hwm[0]) / 1024)")
    print("\n== import cost (fresh process each, 3 runs; s, peak RSS MB)")
    for label, extra in (("object_costmap_node", ""), ("+ import open3d", "; import open3d"),
                         ("+ sklearn.cluster", "; import sklearn.cluster")):
        res = []
        for _ in range(3):
            out = subprocess.run([sys.executable, "-c", code.format(extra=extra)], cwd=ROOT,
                                 capture_output=True, text=True, check=True).stdout.split()
            res.append((float(out[-2]), float(out[-1])))
        t, m = np.median(np.asarray(res), axis=0)
        print(f"  {label:<22} {t:6.2f} s  {m:6.0f} MB  (median of 3)")


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--reps", type=int, default=3, help="repeats per input (best is kept)")
    ap.add_argument("--cloud-world", default="small_cluttered")
    ap.add_argument("--rrt-world", action="append", default=None,
                    help="bench world spec (repeatable); default eb/corridor_asym, small_house")
    ap.add_argument("--rrt-seeds", default="0,1")
    ap.add_argument("--rrt-sim-time", type=float, default=300.0)
    ap.add_argument("--import-cost", action="store_true")
    args = ap.parse_args(argv)

    calls = record_cloud_calls(args.cloud_world)
    compare("voxel downsample (Open3D voxel_down_sample_and_trace)", calls.get("voxel", []),
            cloud.voxel_downsample, voxel_open3d, _voxel_same, args.reps)
    compare("statistical outlier removal (Open3D remove_statistical_outlier)",
            calls.get("sor", []), cloud.statistical_outlier_mask, sor_open3d, np.array_equal,
            args.reps)
    linked = [c for c in calls.get("clusters", []) if _has_links(c)]
    for label, group in (("with", linked), ("without", [c for c in calls.get("clusters", [])
                                                        if not _has_links(c)])):
        compare(f"Euclidean clusters {label} extra links (Open3D cluster_dbscan, min_points 1"
                f"{'; links joined by scipy' if label == 'with' else ''})", group,
                cloud.euclidean_clusters, clusters_open3d, _same_partition, args.reps)

    ms_calls = []
    seeds = [int(s) for s in args.rrt_seeds.split(",") if s]
    for spec in args.rrt_world or ["eb/corridor_asym", "small_house"]:
        ms_calls += record_mean_shift_calls(spec, seeds, args.rrt_sim_time)
    compare("mean shift (scikit-learn MeanShift)", ms_calls, mean_shift,
            mean_shift_sklearn,
            lambda a, b: _centres(a).shape == b.shape and np.array_equal(_centres(a), b),
            args.reps,
            close=lambda a, b: _centres(a).shape == b.shape
            and np.allclose(_centres(a), b, rtol=0.0, atol=1e-9))
    if args.import_cost:
        import_cost()


if __name__ == "__main__":
    main()
