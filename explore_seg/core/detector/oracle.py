"""The oracle detector: boxes read off the simulator's semantic (and instance) image,
with configurable misses, jitter and score."""

from __future__ import annotations

from collections.abc import Mapping

import cv2
import numpy as np
import numpy.typing as npt

from explore_seg.core.detector.coco import COCO_NAMES, Detection, parse_oracle_class_map
from explore_seg.core.detector.params import DetectorParams


class OracleBackend:
    """Detections read from the simulator's semantic (and instance) image.

    Parameters
    ----------
    params : DetectorParams
        ``oracle_*`` fields and ``classes``.
    sim_class_ids : mapping of str to int
        The simulator's class name -> id table (``sim_bridge.sensors.CLASS_IDS``); passed
        in so the core never imports the simulator.

    Raises
    ------
    ValueError
        If no entry of ``oracle_class_map`` names a class of ``sim_class_ids``.
    """

    name = "oracle"

    def __init__(self, params: DetectorParams, sim_class_ids: Mapping[str, int]) -> None:
        self.params = params
        mapping = parse_oracle_class_map(params.oracle_class_map)
        allowed = set(params.classes) if params.classes else set(COCO_NAMES)
        self.ignored_sim_classes = tuple(sorted(s for s in mapping if s not in sim_class_ids))
        self._id_to_coco = {int(sim_class_ids[s]): c for s, c in mapping.items()
                            if s in sim_class_ids and c in allowed}
        if not any(s in sim_class_ids for s in mapping):
            raise ValueError(f"oracle_class_map names none of the simulator's classes "
                             f"{sorted(sim_class_ids)}; got {sorted(mapping)}")
        self._rng = np.random.default_rng(params.oracle_seed)

    def detect(self, semantic: npt.NDArray[np.integer],
               instance: npt.NDArray[np.integer] | None = None) -> list[Detection]:
        """Boxes of the mapped objects in a semantic image.

        Each object is one instance id within a class when ``instance`` is given, else one
        8-connected component of the class mask. The box spans the object's pixels
        (``x1 = last column + 1``), gets Gaussian jitter of ``oracle_jitter_px`` per
        corner, is clipped to the image, and is dropped with ``oracle_miss_prob``.

        Parameters
        ----------
        semantic : ndarray of int, shape (H, W)
            Simulator class id per pixel.
        instance : ndarray of int, shape (H, W), optional
            Object instance id per pixel.

        Returns
        -------
        list of Detection
            Ordered by sim class id, then instance id / component.
        """
        p = self.params
        h, w = semantic.shape
        out: list[Detection] = []
        if semantic.dtype.kind == "u" and semantic.dtype.itemsize <= 2:  # fast path
            present = set(np.flatnonzero(np.bincount(semantic.ravel())).tolist())
        else:
            present = set(np.unique(semantic).tolist())
        for sim_id in sorted(self._id_to_coco):
            if sim_id not in present:
                continue
            mask = semantic == sim_id
            coco = self._id_to_coco[sim_id]
            for box, area in self._objects(mask, None if instance is None else instance[mask]):
                if area < p.oracle_min_area_px:
                    continue
                if self._rng.random() < p.oracle_miss_prob:
                    continue
                if p.oracle_jitter_px > 0:
                    box = box + self._rng.normal(0.0, p.oracle_jitter_px, 4)
                x0, x1 = sorted((float(np.clip(box[0], 0, w)), float(np.clip(box[2], 0, w))))
                y0, y1 = sorted((float(np.clip(box[1], 0, h)), float(np.clip(box[3], 0, h))))
                if x1 <= x0 or y1 <= y0:
                    continue
                out.append(Detection(coco, COCO_NAMES.index(coco), p.oracle_score,
                                     (x0, y0, x1, y1)))
        return out

    @staticmethod
    def _objects(mask: npt.NDArray[np.bool_], instance_values: npt.NDArray | None):
        """Yield ``(box_xyxy float64 (4,), pixel count)`` per object of a class mask."""
        if instance_values is None:
            n, _, stats, _ = cv2.connectedComponentsWithStats(
                mask.astype(np.uint8), connectivity=8)
            for k in range(1, n):
                x, y, bw, bh, area = stats[k]
                yield np.array([x, y, x + bw, y + bh], dtype=np.float64), int(area)
            return
        rows, cols = np.nonzero(mask)
        for inst in np.unique(instance_values):
            sel = instance_values == inst
            r, c = rows[sel], cols[sel]
            yield (np.array([c.min(), r.min(), c.max() + 1, r.max() + 1], dtype=np.float64),
                   int(sel.sum()))
