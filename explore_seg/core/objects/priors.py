"""Per-class size priors of the object costmap (``config/object_priors.yaml``)."""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path


@dataclass(frozen=True)
class SizePrior:
    """Plausible size of a class: footprint sides in [min_xy_m, max_xy_m], height in
    [min_z_m, max_z_m] (metres).

    Raises
    ------
    ValueError
        On non-finite, negative or inverted ranges.
    """

    min_xy_m: float
    max_xy_m: float
    min_z_m: float
    max_z_m: float

    def __post_init__(self) -> None:
        vals = (self.min_xy_m, self.max_xy_m, self.min_z_m, self.max_z_m)
        if not all(math.isfinite(v) and v >= 0 for v in vals):
            raise ValueError(f"size prior values must be finite and >= 0, got {vals}")
        if self.min_xy_m > self.max_xy_m or self.min_z_m > self.max_z_m:
            raise ValueError(f"size prior ranges must satisfy min <= max, got {vals}")
        if self.max_xy_m <= 0 or self.max_z_m <= 0:
            raise ValueError(f"size prior maxima must be > 0, got {vals}")


def default_priors_path() -> Path:
    """The source tree's ``config/object_priors.yaml`` (an installed package's nodes pass
    the share folder's file instead: :func:`explore_seg.node_util.config_file`).

    Raises
    ------
    FileNotFoundError
        When the file is not there.
    """
    here = Path(__file__).resolve().parents[3] / "config" / "object_priors.yaml"
    if here.is_file():
        return here
    raise FileNotFoundError(f"object priors not found at {here}: pass the file's path")


def load_priors(path: str | Path | None = None) -> dict[str, SizePrior]:
    """Read per-class size priors.

    Parameters
    ----------
    path : str or Path, optional
        YAML with ``priors: {class_name: {min_xy_m, max_xy_m, min_z_m, max_z_m}}``;
        ``None`` or ``""`` = :func:`default_priors_path`.

    Returns
    -------
    dict of str to SizePrior
        Keyed by class name (COCO names, e.g. ``"chair"``, ``"dining table"``).

    Raises
    ------
    ValueError
        When the file does not hold a ``priors`` mapping of complete, valid entries.
    FileNotFoundError
        When the file does not exist.
    """
    import yaml

    p = default_priors_path() if path in (None, "") else Path(path)
    data = yaml.safe_load(Path(p).read_text())
    if not isinstance(data, dict) or not isinstance(data.get("priors"), dict):
        raise ValueError(
            f"{p}: expected a mapping with a 'priors' mapping, got {type(data).__name__}")
    out: dict[str, SizePrior] = {}
    keys = ("min_xy_m", "max_xy_m", "min_z_m", "max_z_m")
    for name, entry in data["priors"].items():
        if not isinstance(entry, dict) or set(keys) - set(entry):
            raise ValueError(f"{p}: prior {name!r} must have keys {keys}, got {entry!r}")
        try:
            out[str(name)] = SizePrior(*(float(entry[k]) for k in keys))
        except (TypeError, ValueError) as err:
            raise ValueError(f"{p}: prior {name!r}: {err}") from err
    if not out:
        raise ValueError(f"{p}: 'priors' is empty")
    return out
