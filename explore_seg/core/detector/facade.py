"""The :class:`Detector` facade: one network or oracle backend behind one ``detect``."""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np
import numpy.typing as npt

from explore_seg.core.detector.backends import NetworkBackend, make_network
from explore_seg.core.detector.coco import Detection
from explore_seg.core.detector.model_files import default_model_dir
from explore_seg.core.detector.oracle import OracleBackend
from explore_seg.core.detector.params import DetectorParams
from explore_seg.core.detector.postprocess import decode
from explore_seg.core.detector.preprocess import letterbox, validate_label_image, validate_rgb


class Detector:
    """2D object detector producing :class:`Detection` lists.

    Parameters
    ----------
    params : DetectorParams, optional
        Defaults when omitted.
    sim_class_ids : mapping of str to int, optional
        Simulator class name -> id table; required by the ``oracle`` backend.

    Raises
    ------
    FileNotFoundError
        When a network backend cannot find its model files.
    ValueError
        When the oracle backend gets no (usable) ``sim_class_ids``, or the names file is
        not COCO.

    Examples
    --------
    >>> det = Detector(DetectorParams(backend="oracle"), sim_class_ids={"chair": 3})
    >>> sem = np.zeros((40, 60), np.uint8); sem[10:30, 5:25] = 3
    >>> [(d.cls_name, d.box_xyxy) for d in det.detect(np.zeros((40, 60, 3), np.uint8),
    ...                                                semantic=sem)]
    [('chair', (5.0, 10.0, 25.0, 30.0))]
    """

    def __init__(self, params: DetectorParams | None = None, *,
                 sim_class_ids: Mapping[str, int] | None = None) -> None:
        self.params = params or DetectorParams()
        self.model_dir = default_model_dir(self.params.model_dir)
        self._network: NetworkBackend | None = None
        self._oracle: OracleBackend | None = None
        #: Where the network runs (``cpu``, ``cuda fp16``, ``CUDAExecutionProvider``, ...).
        self.device_name = "cpu"
        #: One log line when the network could not run where ``device`` asked ('' if it does).
        self.device_note = ""
        if self.params.backend == "oracle":
            if not sim_class_ids:
                raise ValueError("backend 'oracle' needs sim_class_ids (sim class name -> id), "
                                 f"got {sim_class_ids!r}")
            self._oracle = OracleBackend(self.params, sim_class_ids)
            self.backend_name = OracleBackend.name
        else:
            self._network = make_network(self.params, self.model_dir)
            self.backend_name = self._network.name
            self.device_name = self._network.device.describe()
            self.device_note = self._network.device.note

    @property
    def network(self) -> NetworkBackend | None:
        """The network backend (None for the oracle)."""
        return self._network

    def detect(self, rgb: npt.NDArray[np.uint8], *,
               semantic: npt.NDArray[np.integer] | None = None,
               instance: npt.NDArray[np.integer] | None = None) -> list[Detection]:
        """Detect objects in one frame.

        Parameters
        ----------
        rgb : ndarray of uint8, shape (H, W, 3)
            RGB image (R first).
        semantic : ndarray of int, shape (H, W), optional
            Simulator class ids; required (and only used) by the oracle backend.
        instance : ndarray of int, shape (H, W), optional
            Simulator instance ids (oracle only).

        Returns
        -------
        list of Detection
            Boxes in ``rgb`` pixels, by decreasing score for the network backends.

        Raises
        ------
        ValueError
            On a wrong type, dtype or shape of an input, or a missing ``semantic`` for
            the oracle.
        """
        validate_rgb(rgb)
        hw = (rgb.shape[0], rgb.shape[1])
        if self._oracle is not None:
            if semantic is None:
                raise ValueError("the oracle backend needs a semantic image (H, W), got None")
            validate_label_image("semantic", semantic, hw)
            if instance is not None:
                validate_label_image("instance", instance, hw)
            return self._oracle.detect(semantic, instance)
        if self._network is None:  # unreachable: one of the two backends is always set
            raise RuntimeError("detector has no backend")
        blob, geo = letterbox(rgb, self.params.input_size, self.params.letterbox_fill)
        return decode(self._network.infer(blob), geo, self.params)
