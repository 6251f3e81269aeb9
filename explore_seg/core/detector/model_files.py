"""Where the YOLOv3-tiny model files are looked for, and reading their class names."""

from __future__ import annotations

import os
from pathlib import Path

from explore_seg.core.detector.coco import COCO_NAMES, DARKNET_NAME_ALIASES

#: Environment variable naming the folder with the model files.
MODEL_DIR_ENV = "EXPLORE_SEG_MODEL_DIR"
CFG_FILE = "yolov3-tiny.cfg"
WEIGHTS_FILE = "yolov3-tiny.weights"
NAMES_FILE = "coco.names"


def default_model_dir(explicit: str | os.PathLike[str] | None = None) -> Path:
    """Folder that holds (or should hold) the YOLOv3-tiny model files.

    Resolution order: ``explicit`` (when non-empty) > ``$EXPLORE_SEG_MODEL_DIR`` >
    ``<repo>/models/yolov3-tiny`` > ``~/.cache/explore_seg/yolov3-tiny``. Among the last two
    the first one holding the weights wins; when neither does, the repository folder is
    returned (where ``scripts/fetch_weights.py`` puts them by default).

    Parameters
    ----------
    explicit : str or PathLike, optional

    Returns
    -------
    Path
    """
    if explicit:
        return Path(explicit).expanduser()
    env = os.environ.get(MODEL_DIR_ENV, "")
    if env:
        return Path(env).expanduser()
    repo = Path(__file__).resolve().parents[3] / "models" / "yolov3-tiny"
    cache = Path.home() / ".cache" / "explore_seg" / "yolov3-tiny"
    for candidate in (repo, cache):
        if (candidate / WEIGHTS_FILE).is_file():
            return candidate
    return repo


def model_files(model_dir: Path) -> tuple[Path, Path, Path]:
    """``(cfg, weights, names)`` paths in ``model_dir``.

    Raises
    ------
    FileNotFoundError
        Naming the missing files and how to fetch them.
    """
    paths = (model_dir / CFG_FILE, model_dir / WEIGHTS_FILE, model_dir / NAMES_FILE)
    missing = [p.name for p in paths if not p.is_file()]
    if missing:
        raise FileNotFoundError(
            f"missing {missing} in {model_dir}; run `python scripts/fetch_weights.py "
            f"--dest {model_dir}` (or set ${MODEL_DIR_ENV})")
    return paths


def read_class_names(path: Path) -> tuple[str, ...]:
    """Class names of a Darknet names file, Darknet spellings mapped to COCO ones.

    Raises
    ------
    ValueError
        If the names are not the 80 COCO classes in YOLO order.
    """
    names = tuple(DARKNET_NAME_ALIASES.get(n.strip(), n.strip())
                  for n in path.read_text(encoding="utf-8").splitlines() if n.strip())
    if names != COCO_NAMES:
        diff = [(i, n) for i, n in enumerate(names) if i >= len(COCO_NAMES) or n != COCO_NAMES[i]]
        raise ValueError(f"{path}: expected the {len(COCO_NAMES)} COCO names in order, got "
                         f"{len(names)} names, first mismatches {diff[:3]}")
    return names
