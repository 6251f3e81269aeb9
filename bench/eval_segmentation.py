#!/usr/bin/env python3
"""Recall / precision (Bormann et al. 2016, IPA definition) of the DuDe segmentation.

Three modes:

* furnished floor plans (``--set furnished``): the seeded maps of
  ``sim_bridge.worlds.furnished`` (offices, open-plan offices, homes; ``--kinds
  real_office``: furnished like the real plans of the IPA set), each segmented
  plain (walls only) and furnished (furniture as a lidar sees it, scanned), side by side:
  recall, precision and segments per room (segments whose largest overlap is that room,
  averaged over rooms; max over the rooms of a map)::

      python bench/eval_segmentation.py --set furnished --maps 30 [--furniture-as-room]

  ``--furniture-as-room`` scores the furnished maps against the plain map's rooms
  (furniture cells count as room, as in the IPA ground truth; default: free cells only).

* generated houses (default): for every seed, ``sim_bridge.worlds.generate_house`` gives
  the rooms (``World.room_labels``) and ``ground_truth(world).as_map("lidar")`` the map
  (0 inside free, 100 occupied, -1 elsewhere); the map is segmented in batch and scored
  against the rooms, for every ``--tau`` (a sweep when several are given)::

      python bench/eval_segmentation.py --seeds 0-9 --tau 1.5,2.0,2.5,3.0 [--cluttered]

* the IPA development set (``--set ipa_dev``): five real floor plans of the IPA
  room-segmentation benchmark (Bormann et al. 2016), plain and with their furniture drawn in,
  with human-drawn room ground truth, read from ``<shared>/data/ipa_dev`` (``<shared>`` =
  ``$EXPLORE_SEG_SHARED`` or ``../shared`` beside the repository; ``--ipa-dir`` overrides).
  Academic, non-commercial licence: the maps are read from there, never copied into the
  package. Scored as the set's README says (maps binarised: free = grey 254, everything else
  occupied; rooms = 8-connected components of the ground truth, > 100 px)::

      python bench/eval_segmentation.py --set ipa_dev

* a label image pair (16-bit or 8-bit PNGs of the same size; 0 = none)::

      python bench/eval_segmentation.py --pred labels.png --gt rooms.png [--gt-connected]

``--gt-connected`` takes the 8-connected components of the non-zero ground-truth pixels
as rooms (IPA's ground-truth drawings). Prints per-map and mean values, never asserts.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

from explore_seg.core.segmentation.eval import evaluate  # noqa: E402
from explore_seg.core.segmentation import SegmentationParams, segment  # noqa: E402


def parse_seeds(text: str) -> list[int]:
    """``"0-4,7"`` -> [0, 1, 2, 3, 4, 7]."""
    out: list[int] = []
    for part in text.split(","):
        if "-" in part:
            a, b = part.split("-")
            out += list(range(int(a), int(b) + 1))
        elif part:
            out.append(int(part))
    return out


def house_cases(seeds: list[int], cluttered: bool, size_m: float):
    """(name, map GridMap, room labels) of generated houses."""
    from sim_bridge.worlds import generate_house, ground_truth

    for seed in seeds:
        w = generate_house(seed, size_m=(size_m, size_m), cluttered=cluttered)
        grid = ground_truth(w).as_map("lidar")
        if grid.shape != w.room_labels.shape:
            raise ValueError(f"room labels {w.room_labels.shape} do not match the map "
                             f"{grid.shape}")
        yield w.name, grid, w.room_labels


def run_houses(seeds: list[int], taus: list[float], cluttered: bool, size_m: float,
               base: SegmentationParams, verbose: bool = True) -> dict[float, dict]:
    """Mean recall/precision per tau over the houses; prints one line per house."""
    cases = list(house_cases(seeds, cluttered, size_m))
    results: dict[float, dict] = {}
    for tau in taus:
        params = SegmentationParams(**{**base.__dict__, "tau_m": tau})
        rec, prec, times = [], [], []
        for name, grid, rooms in cases:
            t0 = time.perf_counter()
            labels = segment(grid, params)
            times.append(time.perf_counter() - t0)
            e = evaluate(labels, rooms)
            rec.append(e["recall"])
            prec.append(e["precision"])
            if verbose:
                print(f"  tau={tau:.2f} {name:24s} {grid.width}x{grid.height}  "
                      f"recall {e['recall'] * 100:5.1f}  precision {e['precision'] * 100:5.1f}"
                      f"  rooms {e['n_rooms']:3d}  segments {e['n_segments']:3d}  "
                      f"{times[-1] * 1e3:6.0f} ms")
        results[tau] = {"recall": float(np.mean(rec)), "recall_std": float(np.std(rec)),
                        "precision": float(np.mean(prec)),
                        "precision_std": float(np.std(prec)),
                        "time_ms": float(np.mean(times) * 1e3)}
    return results


def segments_per_room(e: dict) -> tuple[float, int]:
    """Mean and max over the rooms of ``evaluate``'s result of the number of segments
    whose best room it is."""
    per = {r: 0 for r in e["rooms"]}
    for v in e["segments"].values():
        if v["best_room"] in per:
            per[v["best_room"]] += 1
    if not per:
        return float("nan"), 0
    return float(np.mean(list(per.values()))), int(max(per.values()))


def run_furnished(n_maps: int, first_seed: int, params: SegmentationParams,
                  verbose: bool = True, kinds: tuple[str, ...] | None = None,
                  furniture_as_room: bool = False) -> dict[str, dict[str, float]]:
    """Plain and furnished scores over the furnished evaluation set (``kinds``: the
    floor-plan styles cycled, default ``MAP_KINDS``); prints per map. The furnished
    maps' rooms are their free cells, or with ``furniture_as_room`` the plain map's
    (furniture cells count as room, as in the IPA ground truth)."""
    from sim_bridge.worlds.furnished import MAP_KINDS, furnished_map, furnished_set

    acc: dict[str, dict[str, list[float]]] = {
        k: {"recall": [], "precision": [], "spr": [], "spr_max": [], "time_ms": []}
        for k in ("plain", "furnished")}
    for seed, kind in furnished_set(n_maps, first_seed, kinds or MAP_KINDS):
        m = furnished_map(seed, kind)
        line = f"  {m.name:18s}"
        for key, grid, rooms in (("plain", m.plain, m.plain_rooms),
                                 ("furnished", m.furnished,
                                  m.plain_rooms if furniture_as_room else m.furnished_rooms)):
            t0 = time.perf_counter()
            labels = segment(grid, params)
            dt = (time.perf_counter() - t0) * 1e3
            e = evaluate(labels, rooms)
            spr, spr_max = segments_per_room(e)
            a = acc[key]
            for name, v in (("recall", e["recall"]), ("precision", e["precision"]),
                            ("spr", spr), ("spr_max", spr_max), ("time_ms", dt)):
                a[name].append(v)
            line += (f"  {key} R {e['recall'] * 100:5.1f} P {e['precision'] * 100:5.1f} "
                     f"seg/room {spr:4.2f} (max {spr_max})")
        if verbose:
            print(line + f"  rooms {e['n_rooms']}")
    return {k: {name: float(np.mean(v)) for name, v in a.items()} | {
        "spr_max": float(np.max(a["spr_max"])), "recall_min": float(np.min(a["recall"]))}
        for k, a in acc.items()}


def parse_overrides(items: list[str]) -> dict[str, float | int | bool]:
    """``["name=value", ...]`` -> {name: value} for SegmentationParams (numbers, true/false).

    Raises
    ------
    ValueError
        When an item is not ``name=value`` or names no field.
    """
    import dataclasses

    fields = {f.name: f for f in dataclasses.fields(SegmentationParams)}
    out: dict[str, float | int | bool] = {}
    for item in items:
        name, sep, text = item.partition("=")
        if not sep or name not in fields:
            raise ValueError(f"expected NAME=VALUE with a SegmentationParams field, got {item!r}")
        default = fields[name].default
        if isinstance(default, bool):
            out[name] = text.strip().lower() in ("1", "true", "yes", "on")
        elif isinstance(default, int):
            out[name] = int(text)
        else:
            out[name] = float(text)
    return out


IPA_DEV_MAPS = ("office_a", "office_h", "lab_ipa", "Freiburg79_scan", "lab_c_scan")


def ipa_dev_dir() -> Path:
    """``$EXPLORE_SEG_SHARED/data/ipa_dev`` or ``../shared/data/ipa_dev``."""
    import os

    env = os.environ.get("EXPLORE_SEG_SHARED")
    shared = Path(env) if env else ROOT.parent / "shared"
    return shared / "data" / "ipa_dev"


def ipa_dev_cases(folder: Path, furnished: bool):
    """(name, GridMap, room labels in grid rows) of the IPA development maps.

    Raises
    ------
    FileNotFoundError
        When a map or its ground truth is missing (naming the file).
    """
    import cv2

    from explore_seg.core.grid import GridMap

    suffix = "_furnitures" if furnished else ""
    for name in IPA_DEV_MAPS:
        img_path = folder / "maps" / f"{name}{suffix}.pgm"
        gt_path = folder / "gt" / f"{name}{suffix}.png"
        for path in (img_path, gt_path):
            if not path.is_file():
                raise FileNotFoundError(f"IPA development set: {path} is missing")
        img = cv2.imread(str(img_path), cv2.IMREAD_UNCHANGED)
        gt = cv2.imread(str(gt_path), cv2.IMREAD_UNCHANGED)
        if img is None or gt is None or img.shape != gt.shape[:2]:
            raise ValueError(f"IPA development set: cannot read {img_path} / {gt_path} as "
                             f"two images of one size")
        # The IPA evaluation binarises: free = 254, everything else (unknown too) occupied.
        data = np.where(img == 254, 0, 100).astype(np.int8)[::-1].copy()
        yield f"{name}{suffix}", GridMap(data, 0.05, (0.0, 0.0)), gt[::-1].astype(np.int64)


def run_ipa_dev(folder: Path, params: SegmentationParams, min_px: int,
                verbose: bool = True) -> dict[str, dict[str, float]]:
    """Plain and furnished scores over the IPA development maps; prints per map."""
    out: dict[str, dict[str, float]] = {}
    for key, furnished in (("plain", False), ("furnished", True)):
        acc: dict[str, list[float]] = {"recall": [], "precision": [], "spr": [],
                                       "spr_max": [], "time_ms": []}
        for name, grid, rooms in ipa_dev_cases(folder, furnished):
            t0 = time.perf_counter()
            labels = segment(grid, params)
            dt = (time.perf_counter() - t0) * 1e3
            e = evaluate(labels, rooms, min_px, gt_connected=True)
            spr, spr_max = segments_per_room(e)
            for name_v, v in (("recall", e["recall"]), ("precision", e["precision"]),
                              ("spr", spr), ("spr_max", spr_max), ("time_ms", dt)):
                acc[name_v].append(v)
            if verbose:
                print(f"  {name:28s} {grid.width}x{grid.height}  R {e['recall'] * 100:5.1f}  "
                      f"P {e['precision'] * 100:5.1f}  rooms {e['n_rooms']:3d}  segments "
                      f"{e['n_segments']:3d}  seg/room {spr:4.2f} (max {spr_max})  {dt:5.0f} ms")
        out[key] = {name_v: float(np.mean(v)) for name_v, v in acc.items()} | {
            "spr_max": float(np.max(acc["spr_max"])), "recall_min": float(np.min(acc["recall"])),
            "recall_std": float(np.std(acc["recall"])),
            "precision_std": float(np.std(acc["precision"]))}
    return out


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--set", choices=("houses", "furnished", "ipa_dev"), default="houses",
                    help="generated houses, the generated furnished floor plans, or the IPA "
                         "development set (real plans; plain and furnished side by side)")
    ap.add_argument("--ipa-dir", type=Path, default=None,
                    help="ipa_dev: folder with maps/ and gt/ (default <shared>/data/ipa_dev)")
    ap.add_argument("--maps", type=int, default=30, help="furnished set: number of maps")
    ap.add_argument("--first-seed", type=int, default=0, help="furnished set: first seed")
    ap.add_argument("--kinds", default="",
                    help="furnished set: comma-separated floor-plan styles cycled (default "
                         "office,open_office,home; real_office: furnished like real plans)")
    ap.add_argument("--furniture-as-room", action="store_true",
                    help="furnished set: score the furnished maps against the plain map's "
                         "rooms (furniture cells count as room, as in the IPA ground truth)")
    ap.add_argument("--seeds", default="0-7", help="house seeds, e.g. 0-9 or 1,4,7")
    ap.add_argument("--tau", default=str(SegmentationParams().tau_m),
                    help="tau in metres, comma-separated for a sweep")
    ap.add_argument("--cluttered", action="store_true", help="furnished houses")
    ap.add_argument("--size", type=float, default=20.0, help="house side (m)")
    ap.add_argument("--corridor-merge", action="store_true", help="enable corridor merge")
    ap.add_argument("--seg", action="append", default=[], metavar="NAME=VALUE",
                    help="set a SegmentationParams field (repeatable), e.g. "
                         "--seg furniture_min_thickness_m=0.7 --seg passage_merge_ratio=0.7")
    ap.add_argument("--pred", help="predicted label PNG (pair mode)")
    ap.add_argument("--gt", help="ground-truth label PNG (pair mode)")
    ap.add_argument("--gt-connected", action="store_true",
                    help="rooms = 8-connected components of the non-zero gt pixels")
    ap.add_argument("--min-px", type=int, default=100, help="IPA minimum size (px)")
    ap.add_argument("--quiet", action="store_true", help="only the summary lines")
    args = ap.parse_args(argv)

    if args.pred or args.gt:
        import cv2

        if not (args.pred and args.gt):
            ap.error("--pred and --gt go together")
        imgs = []
        for path in (args.pred, args.gt):
            img = cv2.imread(path, cv2.IMREAD_UNCHANGED)
            if img is None:
                sys.stderr.write(f"eval_segmentation: cannot read {path}\n")
                return 1
            if img.ndim == 3:     # colour label image: one id per colour
                flat = img.reshape(-1, img.shape[2]).astype(np.int64)
                key = flat[:, 0] * 65536 + flat[:, 1] * 256 + flat[:, 2]
                _u, inv = np.unique(key, return_inverse=True)
                img = np.where(key == 0, 0, inv + 1).reshape(img.shape[:2])
            imgs.append(img.astype(np.int64))
        try:
            e = evaluate(imgs[0], imgs[1], args.min_px, gt_connected=args.gt_connected)
        except ValueError as err:
            sys.stderr.write(f"eval_segmentation: {err}\n")
            return 1
        print(f"recall {e['recall'] * 100:.1f} %  precision {e['precision'] * 100:.1f} %  "
              f"(weighted {e['recall_weighted'] * 100:.1f} / "
              f"{e['precision_weighted'] * 100:.1f})  rooms {e['n_rooms']}  "
              f"segments {e['n_segments']}")
        return 0

    taus = [float(t) for t in args.tau.split(",") if t]
    try:
        base = SegmentationParams(corridor_merge=args.corridor_merge,
                                  **parse_overrides(args.seg))
    except (TypeError, ValueError) as err:
        ap.error(f"--seg: {err}")
    if args.set == "ipa_dev":
        params = SegmentationParams(**{**base.__dict__, "tau_m": taus[0]})
        folder = args.ipa_dir or ipa_dev_dir()
        print(f"IPA development set ({folder}), tau {taus[0]:.2f} m; IPA recall/precision, "
              f"min size {args.min_px} px")
        try:
            res_i = run_ipa_dev(folder, params, args.min_px, verbose=not args.quiet)
        except (FileNotFoundError, ValueError) as err:
            sys.stderr.write(f"eval_segmentation: {err}\n")
            return 1
        for key, r in res_i.items():
            print(f"{key:9s}: recall {r['recall'] * 100:5.1f} +- {r['recall_std'] * 100:4.1f} % "
                  f"(min {r['recall_min'] * 100:5.1f})  precision {r['precision'] * 100:5.1f} +- "
                  f"{r['precision_std'] * 100:4.1f} %  segments per room {r['spr']:4.2f} "
                  f"(max {r['spr_max']:.0f})  mean time {r['time_ms']:.0f} ms")
        return 0
    if args.set == "furnished":
        params = SegmentationParams(**{**base.__dict__, "tau_m": taus[0]})
        print(f"furnished floor plans ({args.maps} maps from seed {args.first_seed}), tau "
              f"{taus[0]:.2f} m; IPA recall/precision, min size {args.min_px} px")
        kinds = tuple(k for k in args.kinds.split(",") if k) or None
        try:
            res_f = run_furnished(args.maps, args.first_seed, params, verbose=not args.quiet,
                                  kinds=kinds, furniture_as_room=args.furniture_as_room)
        except ValueError as err:
            ap.error(f"--kinds: {err}")
        for key, r in res_f.items():
            print(f"{key:9s}: recall {r['recall'] * 100:5.1f} % (min {r['recall_min'] * 100:5.1f})"
                  f"  precision {r['precision'] * 100:5.1f} %  segments per room "
                  f"{r['spr']:4.2f} (max {r['spr_max']:.0f})  mean time {r['time_ms']:.0f} ms")
        return 0
    kind = "cluttered" if args.cluttered else "plain"
    print(f"generated houses ({kind}, {args.size:.0f} m, seeds {args.seeds}); "
          f"IPA recall/precision, min size {args.min_px} px")
    res = run_houses(parse_seeds(args.seeds), taus, args.cluttered, args.size, base,
                     verbose=not args.quiet)
    for tau, r in res.items():
        print(f"tau {tau:.2f} m: recall {r['recall'] * 100:5.1f} +- "
              f"{r['recall_std'] * 100:4.1f} %  precision {r['precision'] * 100:5.1f} +- "
              f"{r['precision_std'] * 100:4.1f} %  mean time {r['time_ms']:.0f} ms")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
