"""Where the real RGB-D test frames are.

The TUM RGB-D frames (``tum_*``, CC BY 4.0) ship in ``test/data/rgbd`` with their
``frames.yaml``. The NYU-derived frames (``nyu_*``, licence unclear) are not in the
repository: they are read from ``<shared>/data/rgbd`` (``<shared>`` = $EXPLORE_SEG_SHARED or
``../shared`` beside the checkout) when present, and a test that needs one skips, naming the
missing file and where to put it.
"""

from __future__ import annotations

import os
from pathlib import Path

import pytest
import yaml

TEST_DIR = Path(__file__).resolve().parent
#: The frames shipped with the tests.
FRAMES_DIR = TEST_DIR / "data" / "rgbd"
#: The frames that ship in FRAMES_DIR (a test checks that frames.yaml lists exactly these).
LICENSED_FRAMES = ("tum_fr3_office", "tum_fr2_desk_a", "tum_fr2_desk_b")
#: Frames with an unclear licence, never copied into the repository.
EXTRA_FRAMES = ("nyu_home_1", "nyu_home_2")


def extra_dir() -> Path:
    """Where the frames of EXTRA_FRAMES are looked for."""
    env = os.environ.get("EXPLORE_SEG_SHARED")
    shared = Path(env) if env else TEST_DIR.parents[1] / "shared"
    return shared / "data" / "rgbd"


def frame_dir(name: str) -> Path:
    """The folder that holds (or would hold) a frame's files and its frames.yaml entry."""
    return FRAMES_DIR if name in LICENSED_FRAMES else extra_dir()


def _entries(folder: Path) -> dict[str, dict]:
    path = folder / "frames.yaml"
    if not path.is_file():
        return {}
    return {f["name"]: f for f in yaml.safe_load(path.read_text())["frames"]}


def annotations(names: tuple[str, ...] | list[str]) -> dict[str, dict]:
    """{name: frames.yaml entry} of ``names``, in that order; skips the test (naming the
    missing file and where to put it) when a frame's entry or image files are absent."""
    out = {}
    for name in names:
        folder = frame_dir(name)
        entry = _entries(folder).get(name)
        missing = [folder / "frames.yaml"] if entry is None else [
            folder / entry[k] for k in ("color_file", "depth_file")
            if not (folder / entry[k]).is_file()]
        if missing:
            pytest.skip(f"RGB-D frame {name} is not in the repository (licence unclear); "
                        f"missing {missing[0]}: put {name}_color.png, {name}_depth.png and a "
                        f"frames.yaml with its entry in {folder} (see test/data/rgbd/README.md)")
        out[name] = entry
    return out


def color_path(name: str) -> Path:
    """The colour image of a frame (skips the test as :func:`annotations` does)."""
    entry = annotations([name])[name]
    return frame_dir(name) / entry["color_file"]
