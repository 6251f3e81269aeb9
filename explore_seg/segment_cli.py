"""``segment_map``: DuDe room segmentation of a map file into a 16-bit label PNG.

Usage::

    segment_map MAP.yaml|MAP.pgm|MAP.png --out labels.png [--color color.png] [--tau 1.6]

* a map_server YAML (``image``, ``resolution``, ``origin``, ``negate``,
  ``occupied_thresh``, ``free_thresh``, ``mode`` trinary/scale/raw) is read as
  map_server does;
* a bare image is read as the IPA room segmentation tools do: grey >= ``--free-grey``
  (250) is free, everything else an obstacle; ``--resolution`` gives its cell size.

The output is a 16-bit PNG at the input's size and orientation (row 0 = top, as in the
file): 0 = no region, k > 0 = region id. ``--color`` also writes an RGB visualisation.
Exit status: 0 on success, 1 on unreadable/corrupt input or unwritable output, 2 on bad
arguments.
"""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

import cv2
import numpy as np
import numpy.typing as npt

from explore_seg.core.grid import MAP_IMAGE_MODES, GridMap, occupancy_from_map_image
from explore_seg.core.segmentation import SegmentationParams, segment

#: map_server defaults.
_DEFAULT_OCC_THRESH = 0.65
_DEFAULT_FREE_THRESH = 0.196
#: Largest id a 16-bit PNG holds.
_MAX_ID_16 = 65535


class MapFileError(ValueError):
    """A map file that cannot be read or understood."""


def _read_grey(path: Path) -> npt.NDArray[np.uint8]:
    if not path.is_file():
        raise MapFileError(f"{path}: no such file")
    img = cv2.imread(str(path), cv2.IMREAD_UNCHANGED)
    if img is None:
        raise MapFileError(f"{path}: not a readable image (corrupt or unknown format)")
    if img.dtype != np.uint8:
        raise MapFileError(f"{path}: expected an 8-bit image, got {img.dtype}")
    if img.ndim == 3:
        if img.shape[2] not in (3, 4):
            raise MapFileError(f"{path}: expected 1, 3 or 4 channels, got {img.shape[2]}")
        img = np.rint(img[:, :, :3].astype(np.float64).mean(axis=2)).astype(np.uint8)
    if img.ndim != 2 or img.size == 0:
        raise MapFileError(f"{path}: expected a non-empty 2D image, got shape {img.shape}")
    return img




def _number(doc: dict, key: str, default: float | None, path: Path) -> float:
    val = doc.get(key, default)
    if val is None:
        raise MapFileError(f"{path}: missing key {key!r}")
    if isinstance(val, bool) or not isinstance(val, (int, float)) or not math.isfinite(val):
        raise MapFileError(f"{path}: {key} must be a finite number, got {val!r}")
    return float(val)


def load_map(path: str | Path, resolution_m: float = 0.05, free_grey: int = 250
             ) -> GridMap:
    """Read a map_server YAML or a bare image into a GridMap (row = y, flipped once).

    Parameters
    ----------
    path : str or Path
        ``.yaml``/``.yml`` (map_server) or an image file.
    resolution_m : float
        Cell size of a bare image (ignored for YAML).
    free_grey : int
        Bare images: grey >= this is free (0), else occupied (100).

    Returns
    -------
    GridMap

    Raises
    ------
    MapFileError
        Missing, unreadable or malformed files.
    """
    path = Path(path)
    if path.suffix.lower() in (".yaml", ".yml"):
        import yaml

        if not path.is_file():
            raise MapFileError(f"{path}: no such file")
        try:
            doc = yaml.safe_load(path.read_text())
        except (yaml.YAMLError, UnicodeDecodeError) as err:
            raise MapFileError(f"{path}: not valid YAML ({err})") from None
        if not isinstance(doc, dict):
            raise MapFileError(f"{path}: expected a mapping, got {type(doc).__name__}")
        if "image" not in doc or not isinstance(doc["image"], str):
            raise MapFileError(f"{path}: missing 'image' file name")
        res = _number(doc, "resolution", None, path)
        if res <= 0:
            raise MapFileError(f"{path}: resolution must be > 0, got {res}")
        origin = doc.get("origin", [0.0, 0.0, 0.0])
        if (not isinstance(origin, (list, tuple)) or len(origin) < 2
                or not all(isinstance(v, (int, float)) and math.isfinite(v)
                           for v in origin[:3])):
            raise MapFileError(f"{path}: origin must be [x, y, yaw], got {origin!r}")
        mode = str(doc.get("mode", "trinary"))
        if mode not in MAP_IMAGE_MODES:
            raise MapFileError(f"{path}: mode must be one of {MAP_IMAGE_MODES}, got {mode!r}")
        negate = doc.get("negate", 0)
        occ_t = _number(doc, "occupied_thresh", _DEFAULT_OCC_THRESH, path)
        free_t = _number(doc, "free_thresh", _DEFAULT_FREE_THRESH, path)
        img_path = Path(doc["image"])
        if not img_path.is_absolute():
            img_path = path.parent / img_path
        img = _read_grey(img_path)
        values = occupancy_from_map_image(img, mode, bool(negate), occ_t, free_t)
        yaw = float(origin[2]) if len(origin) > 2 else 0.0
        return GridMap(values[::-1].copy(), res, (float(origin[0]), float(origin[1])), yaw)
    img = _read_grey(path)
    values = np.where(img >= free_grey, 0, 100).astype(np.int8)
    return GridMap(values[::-1].copy(), resolution_m, (0.0, 0.0))


def label_colors(labels: npt.NDArray[np.int32], grid: GridMap) -> npt.NDArray[np.uint8]:
    """RGB visualisation (rows as ``labels``): regions coloured by id, obstacles dark grey,
    other cells light grey."""
    ids = labels.astype(np.int64)
    # a deterministic hash of the id to a saturated colour
    hue = (ids * 47) % 180
    hsv = np.stack([hue, np.full_like(hue, 200), np.full_like(hue, 230)], axis=-1)
    rgb = cv2.cvtColor(hsv.astype(np.uint8), cv2.COLOR_HSV2RGB)
    rgb[labels == 0] = 200
    rgb[(labels == 0) & grid.occupied_mask()] = 60
    return rgb


def build_parser() -> argparse.ArgumentParser:
    """Argument parser of ``segment_map``."""
    ap = argparse.ArgumentParser(
        prog="segment_map",
        description="DuDe room segmentation of a map into a 16-bit label PNG.")
    ap.add_argument("map", help="map_server YAML, or a PGM/PNG image (free >= --free-grey)")
    ap.add_argument("--out", required=True, help="output label PNG (16-bit, 0 = no region)")
    ap.add_argument("--color", help="optional RGB visualisation PNG")
    ap.add_argument("--tau", type=float, default=SegmentationParams().tau_m,
                    help="DuDe max concavity tau in metres (default %(default)s)")
    ap.add_argument("--resolution", type=float, default=0.05,
                    help="cell size of a bare image in metres (default %(default)s)")
    ap.add_argument("--free-grey", type=int, default=250,
                    help="bare images: grey >= this is free (default %(default)s)")
    return ap


def main(argv: list[str] | None = None) -> int:
    """Run ``segment_map``; returns the exit status."""
    ap = build_parser()
    try:
        args = ap.parse_args(argv)
    except SystemExit as exc:            # argparse already printed the usage error
        return int(exc.code) if isinstance(exc.code, int) else 2
    err = sys.stderr
    try:
        params = SegmentationParams(tau_m=args.tau)
    except ValueError as exc:
        err.write(f"segment_map: error: {exc}\n")
        return 2
    if Path(args.out).suffix.lower() != ".png":
        err.write(f"segment_map: error: --out must be a .png file, got {args.out}\n")
        return 2
    if args.color and Path(args.color).suffix.lower() != ".png":
        err.write(f"segment_map: error: --color must be a .png file, got {args.color}\n")
        return 2
    if not (math.isfinite(args.resolution) and args.resolution > 0):
        err.write(f"segment_map: error: --resolution must be > 0, got {args.resolution}\n")
        return 2
    try:
        grid = load_map(args.map, args.resolution, args.free_grey)
    except (MapFileError, ValueError) as exc:
        err.write(f"segment_map: error: {exc}\n")
        return 1
    labels = segment(grid, params)
    if labels.max(initial=0) > _MAX_ID_16:
        err.write(f"segment_map: error: {labels.max()} regions do not fit a 16-bit PNG\n")
        return 1
    out_img = labels[::-1].astype(np.uint16)          # back to row 0 = top
    try:
        ok = cv2.imwrite(str(args.out), out_img)
    except cv2.error as exc:
        ok = False
        err.write(f"segment_map: error: {exc}\n")
    if not ok:
        err.write(f"segment_map: error: cannot write {args.out} (use a .png name in an "
                  f"existing folder)\n")
        return 1
    if args.color:
        rgb = label_colors(labels, grid)[::-1]
        try:
            ok = cv2.imwrite(str(args.color), cv2.cvtColor(rgb, cv2.COLOR_RGB2BGR))
        except cv2.error:
            ok = False
        if not ok:
            err.write(f"segment_map: error: cannot write {args.color}\n")
            return 1
    n = int(len(np.unique(labels[labels > 0])))
    sys.stdout.write(f"segment_map: {n} regions -> {args.out}\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
