"""Input side of the detector: checks of the input images and the Darknet letterbox."""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np
import numpy.typing as npt


@dataclass(frozen=True)
class Letterbox:
    """Geometry of a letterbox resize, and the mapping between its two pixel frames.

    Parameters
    ----------
    src_hw : tuple of int
        Original image height, width.
    size : int
        Side of the square network input.
    resized_hw : tuple of int
        Size of the resized image inside the canvas.
    offset_xy : tuple of int
        Canvas position of the resized image's top-left corner.
    """

    src_hw: tuple[int, int]
    size: int
    resized_hw: tuple[int, int]
    offset_xy: tuple[int, int]

    @classmethod
    def fit(cls, src_hw: tuple[int, int], size: int) -> Letterbox:
        """Darknet's letterbox geometry: scale to fit, centre, integer sizes/offsets."""
        h, w = src_hw
        if w >= h:  # the long side fills the canvas exactly
            new_w, new_h = size, max(1, min(size, int(h * size / w)))
        else:
            new_w, new_h = max(1, min(size, int(w * size / h))), size
        return cls((h, w), size, (new_h, new_w), ((size - new_w) // 2, (size - new_h) // 2))

    def to_original(self, boxes_xyxy: npt.ArrayLike) -> npt.NDArray[np.float64]:
        """Map ``(N, 4)`` boxes from network-input to original pixels and clip to the image."""
        b = np.asarray(boxes_xyxy, dtype=np.float64).reshape(-1, 4)
        sx = self.resized_hw[1] / self.src_hw[1]
        sy = self.resized_hw[0] / self.src_hw[0]
        out = np.empty_like(b)
        out[:, [0, 2]] = (b[:, [0, 2]] - self.offset_xy[0]) / sx
        out[:, [1, 3]] = (b[:, [1, 3]] - self.offset_xy[1]) / sy
        out[:, [0, 2]] = out[:, [0, 2]].clip(0.0, self.src_hw[1])
        out[:, [1, 3]] = out[:, [1, 3]].clip(0.0, self.src_hw[0])
        return out

    def to_network(self, boxes_xyxy: npt.ArrayLike) -> npt.NDArray[np.float64]:
        """Map ``(N, 4)`` boxes from original to network-input pixels (inverse, no clip)."""
        b = np.asarray(boxes_xyxy, dtype=np.float64).reshape(-1, 4)
        sx = self.resized_hw[1] / self.src_hw[1]
        sy = self.resized_hw[0] / self.src_hw[0]
        out = np.empty_like(b)
        out[:, [0, 2]] = b[:, [0, 2]] * sx + self.offset_xy[0]
        out[:, [1, 3]] = b[:, [1, 3]] * sy + self.offset_xy[1]
        return out


def validate_rgb(rgb: object) -> npt.NDArray[np.uint8]:
    """Check that ``rgb`` is an ``(H, W, 3)`` uint8 array; return it.

    Raises
    ------
    ValueError
        Naming the expected and the received type, dtype or shape.
    """
    if not isinstance(rgb, np.ndarray):
        raise ValueError(f"rgb must be a numpy array (H, W, 3) uint8, got {type(rgb).__name__}")
    if rgb.dtype != np.uint8:
        raise ValueError(f"rgb must have dtype uint8, got {rgb.dtype}")
    if rgb.ndim != 3 or rgb.shape[2] != 3 or rgb.shape[0] < 1 or rgb.shape[1] < 1:
        raise ValueError(f"rgb must have shape (H, W, 3) with H, W >= 1, got {rgb.shape}")
    return rgb


def letterbox(rgb: npt.NDArray[np.uint8], size: int,
              fill: float = 0.5) -> tuple[npt.NDArray[np.float32], Letterbox]:
    """Resize an RGB image into a square network input, keeping its aspect ratio.

    Parameters
    ----------
    rgb : ndarray of uint8, shape (H, W, 3)
        RGB image.
    size : int
        Side of the square output.
    fill : float
        Value of the padding, in [0, 1] (Darknet uses 0.5).

    Returns
    -------
    blob : ndarray of float32, shape (1, 3, size, size)
        RGB in [0, 1], channels first.
    geometry : Letterbox
        To map boxes back with :meth:`Letterbox.to_original`.

    Raises
    ------
    ValueError
        On a bad image (see :func:`validate_rgb`) or ``size < 1``.
    """
    validate_rgb(rgb)
    if size < 1:
        raise ValueError(f"size must be >= 1, got {size}")
    geo = Letterbox.fit((rgb.shape[0], rgb.shape[1]), size)
    new_h, new_w = geo.resized_hw
    resized = cv2.resize(rgb, (new_w, new_h), interpolation=cv2.INTER_LINEAR)
    blob = np.full((1, 3, size, size), fill, dtype=np.float32)
    x0, y0 = geo.offset_xy
    blob[0, :, y0:y0 + new_h, x0:x0 + new_w] = resized.transpose(2, 0, 1) / np.float32(255)
    return blob, geo


def validate_label_image(name: str, image: object, hw: tuple[int, int]) -> npt.NDArray:
    if not isinstance(image, np.ndarray):
        raise ValueError(f"{name} must be a numpy array (H, W) of integers, "
                         f"got {type(image).__name__}")
    if not np.issubdtype(image.dtype, np.integer):
        raise ValueError(f"{name} must have an integer dtype, got {image.dtype}")
    if image.shape != hw:
        raise ValueError(f"{name} must have shape {hw} (the rgb's H, W), got {image.shape}")
    return image
