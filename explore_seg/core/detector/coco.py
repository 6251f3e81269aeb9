"""COCO class names, the Darknet spellings, the default class lists and the
:class:`Detection` a detector reports.

Class names are the official COCO names (``"dining table"``, ``"couch"``, ``"tv"``,
``"potted plant"``); the older Darknet spellings found in ``coco.names``
(``diningtable``, ``sofa``, ``tvmonitor``, ``pottedplant``, ``motorbike``, ``aeroplane``)
are translated when the file is read.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

#: The 80 COCO class names in YOLO's class-id order (official 2017 spellings).
COCO_NAMES: tuple[str, ...] = (
    "person", "bicycle", "car", "motorcycle", "airplane", "bus", "train", "truck", "boat",
    "traffic light", "fire hydrant", "stop sign", "parking meter", "bench", "bird", "cat",
    "dog", "horse", "sheep", "cow", "elephant", "bear", "zebra", "giraffe", "backpack",
    "umbrella", "handbag", "tie", "suitcase", "frisbee", "skis", "snowboard", "sports ball",
    "kite", "baseball bat", "baseball glove", "skateboard", "surfboard", "tennis racket",
    "bottle", "wine glass", "cup", "fork", "knife", "spoon", "bowl", "banana", "apple",
    "sandwich", "orange", "broccoli", "carrot", "hot dog", "pizza", "donut", "cake", "chair",
    "couch", "potted plant", "bed", "dining table", "toilet", "tv", "laptop", "mouse",
    "remote", "keyboard", "cell phone", "microwave", "oven", "toaster", "sink",
    "refrigerator", "book", "clock", "vase", "scissors", "teddy bear", "hair drier",
    "toothbrush",
)
#: Darknet ``coco.names`` spellings -> official COCO names.
DARKNET_NAME_ALIASES: Mapping[str, str] = {
    "motorbike": "motorcycle", "aeroplane": "airplane", "sofa": "couch",
    "pottedplant": "potted plant", "diningtable": "dining table", "tvmonitor": "tv",
}

#: Default classes for an indoor robot: furniture and large appliances that are static
#: obstacles a 2D lidar sees badly (table/chair legs, overhangs) or that name a room
#: (bed, toilet, couch, oven, refrigerator, sink). People and small objects are left out:
#: they move, or are not obstacles.
DEFAULT_CLASSES: tuple[str, ...] = (
    "chair", "couch", "bed", "dining table", "toilet", "bench", "potted plant", "tv",
    "refrigerator", "oven", "sink",
)
#: Default simulator class name -> COCO name map of the oracle (``"sim:coco"`` pairs).
DEFAULT_ORACLE_CLASS_MAP: tuple[str, ...] = (
    "chair:chair", "table:dining table", "desk:dining table", "sofa:couch", "couch:couch",
    "bed:bed", "toilet:toilet", "tv:tv", "plant:potted plant", "bench:bench",
    "fridge:refrigerator", "refrigerator:refrigerator", "oven:oven", "sink:sink",
)



@dataclass(frozen=True)
class Detection:
    """One detected object.

    Parameters
    ----------
    cls_name : str
        COCO class name (``"chair"``).
    class_id : int
        Index of ``cls_name`` in :data:`COCO_NAMES`.
    score : float
        Confidence in (0, 1].
    box_xyxy : tuple of 4 float
        ``(x0, y0, x1, y1)`` in pixels of the ORIGINAL image; continuous coordinates
        (pixel ``(u, v)`` spans ``[u, u + 1) x [v, v + 1)``), clipped to the image.
    """

    cls_name: str
    class_id: int
    score: float
    box_xyxy: tuple[float, float, float, float]



def parse_oracle_class_map(pairs: Sequence[str]) -> dict[str, str]:
    """Parse ``"sim_class:coco_name"`` pairs into a dict.

    Raises
    ------
    ValueError
        On a pair without exactly one ``:``, an empty side, a COCO name not in
        :data:`COCO_NAMES` or a sim class listed twice.
    """
    out: dict[str, str] = {}
    for pair in pairs:
        parts = pair.split(":")
        if len(parts) != 2 or not parts[0].strip() or not parts[1].strip():
            raise ValueError(f"oracle_class_map entries must be 'sim_class:coco_name', "
                             f"got {pair!r}")
        sim, coco = parts[0].strip(), parts[1].strip()
        if coco not in COCO_NAMES:
            raise ValueError(f"oracle_class_map: {coco!r} (in {pair!r}) is not a COCO name")
        if sim in out:
            raise ValueError(f"oracle_class_map: sim class {sim!r} listed twice")
        out[sim] = coco
    return out
