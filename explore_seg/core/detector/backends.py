"""Network backends: eager torch (:class:`TorchBackend`) and onnxruntime
(:class:`OnnxBackend`, on an ONNX file exported once from the torch module).

``torch`` is imported only when a network must be built (not by the ONNX backend once
its cached ONNX file exists); ``onnx`` and ``onnxruntime`` only by the ONNX backend.
"""

from __future__ import annotations

import hashlib
import logging
import os
import tempfile
import warnings
from pathlib import Path
from typing import Protocol

import numpy as np
import numpy.typing as npt

from explore_seg.core.detector.devices import DevicePlan, onnx_plan, session_note, torch_plan
from explore_seg.core.detector.model_files import model_files, read_class_names
from explore_seg.core.detector.params import DetectorParams

LOG = logging.getLogger(__name__)

#: Bumped whenever the exported graph changes, so stale ONNX caches are re-exported.
ONNX_EXPORT_VERSION = "1"
ONNX_OPSET = 17
_ONNX_META_KEY = "explore_seg_source"
ONNX_FILE_MODE = 0o644


class NetworkBackend(Protocol):
    """A YOLO network: ``(1, 3, S, S)`` float32 blob -> ``(N, 5 + C)`` raw rows."""

    name: str
    input_size: int
    #: Where it runs (and a note when that is not what was asked for).
    device: DevicePlan

    def infer(self, blob: npt.NDArray[np.float32]) -> npt.NDArray[np.float32]:
        """Run the network on one letterboxed blob."""
        ...


class TorchBackend:
    """Eager torch inference of the Darknet module.

    Parameters
    ----------
    model_dir : Path
        Folder with the model files.
    input_size : int
        Network input side.
    num_threads : int
        Passed to ``torch.set_num_threads`` (process-wide).
    device : str
        ``cpu``, ``cuda`` or ``auto`` (:func:`~explore_seg.core.detector.devices.torch_plan`).
    half : bool
        fp16 on CUDA.
    """

    name = "torch"

    def __init__(self, model_dir: Path, input_size: int, num_threads: int,
                 device: str = "cpu", half: bool = False) -> None:
        import torch

        from explore_seg.core.detector.darknet import load_darknet

        cfg, weights, names = model_files(model_dir)
        self.class_names = read_class_names(names)
        self.input_size = input_size
        torch.set_num_threads(num_threads)
        self._torch = torch
        self.device = torch_plan(device, half, torch.cuda.is_available())
        self.net = load_darknet(cfg, weights).to(self.device.target)
        if self.device.half:
            self.net = self.net.half()

    def infer(self, blob: npt.NDArray[np.float32]) -> npt.NDArray[np.float32]:
        x = self._torch.from_numpy(blob).to(self.device.target)
        with self._torch.inference_mode():
            heads = self.net(x.half() if self.device.half else x)
        return np.concatenate([h[0].float().cpu().numpy() for h in heads], axis=0)


def _source_digest(cfg: Path, weights: Path, input_size: int) -> str:
    """Identity of an ONNX export: export version, input size, cfg and weights content."""
    digest = hashlib.sha256()
    digest.update(f"{ONNX_EXPORT_VERSION}:{input_size}:".encode())
    digest.update(cfg.read_bytes())
    with weights.open("rb") as stream:
        for chunk in iter(lambda: stream.read(1 << 20), b""):
            digest.update(chunk)
    return digest.hexdigest()


def export_onnx(cfg: Path, weights: Path, input_size: int, path: Path, source: str) -> None:
    """Export the Darknet module to ONNX at ``path`` (atomically), tagging its source digest.

    Raises
    ------
    OSError
        If ``path``'s folder is not writable.
    """
    import onnx
    import torch

    from explore_seg.core.detector.darknet import load_darknet

    net = load_darknet(cfg, weights)
    dummy = torch.zeros(1, 3, input_size, input_size)
    n_heads = len(net(dummy))
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    os.close(fd)
    try:
        with warnings.catch_warnings():
            # Tracing fixes the input size on purpose (one file per size): silence the
            # tracer's warnings about shapes turned into constants.
            warnings.simplefilter("ignore")
            torch.onnx.export(net, (dummy,), tmp, dynamo=False, opset_version=ONNX_OPSET,
                              input_names=["images"],
                              output_names=[f"head{i}" for i in range(n_heads)])
        model = onnx.load(tmp)
        entry = model.metadata_props.add()
        entry.key, entry.value = _ONNX_META_KEY, source
        onnx.save(model, tmp)
        os.chmod(tmp, ONNX_FILE_MODE)
        os.replace(tmp, path)
    finally:
        Path(tmp).unlink(missing_ok=True)


class OnnxBackend:
    """onnxruntime inference of the Darknet module, exported once to an ONNX cache file.

    The file ``yolov3-tiny_<size>.onnx`` lives next to the weights, or in
    ``<tmp>/explore_seg_onnx`` when that folder is not writable. It carries a digest of
    the cfg, weights, input size and export version and is re-exported when that differs.

    Parameters
    ----------
    model_dir : Path
        Folder with the model files.
    input_size : int
        Network input side.
    num_threads : int
        onnxruntime intra-op threads.
    cache_dir : Path, optional
        Where to keep the ONNX file (default: ``model_dir``, falling back to a temp dir).
    device : str
        ``cpu``, ``cuda`` or ``auto`` (:func:`~explore_seg.core.detector.devices.onnx_plan`).
    """

    name = "onnx"

    def __init__(self, model_dir: Path, input_size: int, num_threads: int,
                 cache_dir: Path | None = None, device: str = "cpu") -> None:
        import onnxruntime as ort

        cfg, weights, names = model_files(model_dir)
        self.class_names = read_class_names(names)
        self.input_size = input_size
        source = _source_digest(cfg, weights, input_size)
        file_name = f"{cfg.stem}_{input_size}.onnx"
        dirs = [cache_dir] if cache_dir else [
            model_dir, Path(tempfile.gettempdir()) / "explore_seg_onnx"]
        self.onnx_path = self._ensure_export(cfg, weights, input_size, source, file_name, dirs)
        options = ort.SessionOptions()
        options.intra_op_num_threads = num_threads
        options.inter_op_num_threads = 1
        options.execution_mode = ort.ExecutionMode.ORT_SEQUENTIAL
        options.graph_optimization_level = ort.GraphOptimizationLevel.ORT_ENABLE_ALL
        plan = onnx_plan(device, ort.get_available_providers())
        self._session = ort.InferenceSession(str(self.onnx_path), options,
                                             providers=list(plan.target))
        used = self._session.get_providers()
        self.device = DevicePlan(tuple(used), False, session_note(plan, used))
        self._input = self._session.get_inputs()[0].name

    @staticmethod
    def _ensure_export(cfg: Path, weights: Path, input_size: int, source: str, file_name: str,
                       dirs: list[Path]) -> Path:
        for d in dirs:
            if onnx_source(d / file_name) == source:
                return d / file_name
        errors = []
        for d in dirs:
            try:
                export_onnx(cfg, weights, input_size, d / file_name, source)
                LOG.info("exported %s", d / file_name)
                return d / file_name
            except OSError as err:
                errors.append(f"{d}: {err}")
        raise OSError(f"cannot write the ONNX export anywhere: {errors}")

    def infer(self, blob: npt.NDArray[np.float32]) -> npt.NDArray[np.float32]:
        heads = self._session.run(None, {self._input: blob})
        return np.concatenate([h[0] for h in heads], axis=0)


def onnx_source(path: Path) -> str | None:
    """The source digest stored in an exported ONNX file, or None if absent/unreadable."""
    if not path.is_file():
        return None
    import onnx

    from google.protobuf.message import DecodeError

    try:
        model = onnx.load(str(path), load_external_data=False)
    except (OSError, ValueError, RuntimeError, DecodeError) as err:  # corrupt: re-export
        LOG.warning("ignoring unreadable ONNX cache %s: %s", path, err)
        return None
    return next((p.value for p in model.metadata_props if p.key == _ONNX_META_KEY), None)


def make_network(params: DetectorParams, model_dir: Path) -> NetworkBackend:
    """The network backend of ``params.backend``; ``auto`` falls back to torch when
    onnxruntime or onnx cannot be imported."""
    if params.backend in ("auto", "onnx"):
        try:
            return OnnxBackend(model_dir, params.input_size, params.num_threads,
                               device=params.device)
        except ImportError as err:
            if params.backend == "onnx":
                raise
            LOG.info("onnx backend unavailable (%s): using torch", err)
    return TorchBackend(model_dir, params.input_size, params.num_threads, params.device,
                        params.half)
