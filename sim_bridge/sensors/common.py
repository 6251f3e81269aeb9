"""What the simulated sensors share: the semantic class table and a parameter check."""

from __future__ import annotations

import math

#: Semantic class ids of the camera's ``semantic`` image (0 = floor / nothing).
CLASS_IDS: dict[str, int] = {"none": 0, "wall": 1, "chair": 2, "table": 3, "desk": 4,
                             "cabinet": 5, "sofa": 6, "other": 7}
#: Inverse of :data:`CLASS_IDS`.
CLASS_NAMES: dict[int, str] = {v: k for k, v in CLASS_IDS.items()}
#: RGB colour of each class id (floor = id 0 uses :data:`FLOOR_RGB` with a checker pattern).
CLASS_RGB: dict[int, tuple[int, int, int]] = {
    0: (40, 40, 48), 1: (205, 200, 185), 2: (200, 60, 40), 3: (150, 100, 50),
    4: (90, 140, 60), 5: (60, 90, 170), 6: (120, 60, 140), 7: (140, 140, 140)}
#: Floor colours of the two checker tiles.
FLOOR_RGB = ((150, 150, 150), (120, 120, 120))


def require_positive(name: str, value: float) -> None:
    """Raise ValueError unless ``value`` is finite and > 0.

    Raises
    ------
    ValueError
        Naming the parameter and the value it got.
    """
    if not (math.isfinite(value) and value > 0):
        raise ValueError(f"{name} must be finite and > 0, got {value}")
