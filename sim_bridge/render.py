"""Headless pictures of a run: map PNGs with overlays and a bounded-memory GIF writer.

Pure numpy + PIL (no display, no matplotlib state). A picture is drawn over one
:class:`~explore_seg.core.grid.GridMap` (unknown grey, free white, occupied black), with
image row 0 at the top (largest y), ``scale`` pixels per cell. Overlays are given in
world coordinates (metres) or as masks/labels aligned with the map, so callers never
convert cells themselves.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Sequence

import numpy as np
import numpy.typing as npt
from PIL import Image, ImageDraw

from explore_seg.core.grid import OCCUPIED_THRESHOLD, GridMap

RGB = tuple[int, int, int]


@dataclass(frozen=True)
class RenderStyle:
    """Colours (RGB) and sizes of the pictures."""

    unknown: RGB = (160, 160, 160)
    free: RGB = (255, 255, 255)
    occupied: RGB = (0, 0, 0)
    truth: RGB = (0, 170, 255)
    path: RGB = (0, 140, 0)
    plan: RGB = (255, 140, 0)
    robot: RGB = (0, 90, 255)
    collision: RGB = (230, 0, 0)
    frontier: RGB = (255, 0, 200)
    goal: RGB = (150, 0, 255)
    box: RGB = (255, 200, 0)
    region_alpha: float = 0.35
    marker_px: int = 5
    line_px: int = 2
    max_side_px: int = 1600


@dataclass
class Overlays:
    """Everything that can be drawn over the map (all optional).

    Attributes
    ----------
    truth : GridMap, optional
        Ground-truth footprint raster; its occupied cells are outlined in ``style.truth``.
    robot_path : ndarray, shape (N, 2), optional
        Travelled (x, y) points.
    plan : ndarray, shape (N, 2), optional
        Current plan (x, y).
    robot_pose : (x, y, yaw), optional
    collisions : sequence of (x, y)
        Contact positions, drawn as red crosses.
    frontiers : ndarray, optional
        Frontier cells: a bool mask of the map's shape (H, W), or world points (N, 2).
    regions : ndarray of int, shape (H, W) of the map, optional
        Region labels (0 = none), tinted with one colour per label.
    boxes : sequence of ndarray (K, 2)
        Object outlines (closed polygons, world metres).
    goals : sequence of (x, y)
    """

    truth: GridMap | None = None
    robot_path: npt.NDArray[np.float64] | None = None
    plan: npt.NDArray[np.float64] | None = None
    robot_pose: tuple[float, float, float] | None = None
    collisions: Sequence[tuple[float, float]] = field(default_factory=list)
    frontiers: npt.NDArray[np.bool_] | npt.NDArray[np.float64] | None = None
    regions: npt.NDArray[np.integer] | None = None
    boxes: Sequence[npt.NDArray[np.float64]] = field(default_factory=list)
    goals: Sequence[tuple[float, float]] = field(default_factory=list)


def label_colours(n: int, seed: int = 7) -> npt.NDArray[np.uint8]:
    """``n + 1`` distinct-ish RGB colours; index 0 (no label) is black."""
    rng = np.random.default_rng(seed)
    hues = (np.arange(n) * 0.618033988749895 + rng.random()) % 1.0
    out = np.zeros((n + 1, 3), dtype=np.uint8)
    for i, h in enumerate(hues, start=1):
        out[i] = _hsv_to_rgb(h, 0.65, 0.95)
    return out


def _hsv_to_rgb(h: float, s: float, v: float) -> tuple[int, int, int]:
    i = int(h * 6.0) % 6
    f = h * 6.0 - int(h * 6.0)
    p, q, t = v * (1 - s), v * (1 - f * s), v * (1 - (1 - f) * s)
    r, g, b = [(v, t, p), (q, v, p), (p, v, t), (p, q, v), (t, p, v), (v, p, q)][i]
    return int(r * 255), int(g * 255), int(b * 255)


class _Canvas:
    """Maps world points to pixel coordinates of the upscaled, row-flipped map image."""

    def __init__(self, grid: GridMap, scale: int) -> None:
        self.grid = grid
        self.scale = scale

    def px(self, xy: npt.ArrayLike) -> list[tuple[float, float]]:
        a = np.asarray(xy, dtype=np.float64).reshape(-1, 2)
        r, c = self.grid.world_to_cell_float(a[:, 0], a[:, 1])
        u = c * self.scale
        v = (self.grid.height - r) * self.scale
        return list(zip(u.tolist(), v.tolist()))


def render_map(grid: GridMap, overlays: Overlays | None = None,
               style: RenderStyle | None = None, scale: int | None = None
               ) -> npt.NDArray[np.uint8]:
    """Draw the map and overlays.

    Parameters
    ----------
    grid : GridMap
    overlays : Overlays, optional
    style : RenderStyle, optional
    scale : int, optional
        Pixels per cell (default: the largest that keeps the picture within
        ``style.max_side_px``, at least 1).

    Returns
    -------
    ndarray of uint8, shape (H * scale, W * scale, 3)
        RGB picture, row 0 at the top (largest y).

    Raises
    ------
    ValueError
        When a mask/label overlay does not have the map's shape.
    """
    st = style if style is not None else RenderStyle()
    ov = overlays if overlays is not None else Overlays()
    if scale is None:
        scale = max(1, st.max_side_px // max(grid.width, grid.height, 1))
    rgb = np.empty(grid.shape + (3,), dtype=np.uint8)
    rgb[:] = st.unknown
    rgb[grid.free_mask()] = st.free
    if ov.regions is not None:
        labels = np.asarray(ov.regions)
        if labels.shape != grid.shape:
            raise ValueError(f"regions shape {labels.shape} differs from the map {grid.shape}")
        n = int(labels.max()) if labels.size else 0
        if n > 0:
            colours = label_colours(n)
            lab = np.clip(labels, 0, n)
            m = lab > 0
            a = st.region_alpha
            rgb[m] = ((1 - a) * rgb[m] + a * colours[lab[m]]).astype(np.uint8)
    if ov.truth is not None:  # under the map's obstacles, so misplaced walls show
        occ = ov.truth.resample_to(grid, fill=0) >= OCCUPIED_THRESHOLD
        edge = occ & ~_erode(occ)
        rgb[edge] = st.truth
    rgb[grid.occupied_mask()] = st.occupied
    frontier_pts = None
    if ov.frontiers is not None:
        fr = np.asarray(ov.frontiers)
        if fr.dtype == bool:
            if fr.shape != grid.shape:
                raise ValueError(f"frontier mask shape {fr.shape} differs from the map "
                                 f"{grid.shape}")
            rgb[fr] = st.frontier
        elif fr.ndim == 2 and fr.shape[1] == 2:
            frontier_pts = fr.astype(np.float64)
        else:
            raise ValueError(f"frontiers must be a bool mask {grid.shape} or (N, 2) points, "
                             f"got {fr.dtype} {fr.shape}")
    img = Image.fromarray(np.ascontiguousarray(rgb[::-1]), "RGB")
    if scale > 1:
        img = img.resize((grid.width * scale, grid.height * scale), Image.NEAREST)
    draw = ImageDraw.Draw(img)
    cv = _Canvas(grid, scale)
    lw = max(1, st.line_px)
    mk = max(2, st.marker_px)
    for poly in ov.boxes:
        pts = cv.px(poly)
        if len(pts) >= 2:
            draw.line(pts + [pts[0]], fill=st.box, width=lw)
    if ov.robot_path is not None and len(ov.robot_path) >= 2:
        draw.line(cv.px(ov.robot_path), fill=st.path, width=lw)
    if ov.plan is not None and len(ov.plan) >= 2:
        draw.line(cv.px(ov.plan), fill=st.plan, width=lw)
    if frontier_pts is not None:
        r = max(1, scale // 2)
        for u, v in cv.px(frontier_pts):
            draw.rectangle([u - r, v - r, u + r, v + r], fill=st.frontier)
    for gx, gy in ov.goals:
        (u, v), = cv.px([gx, gy])
        draw.ellipse([u - mk, v - mk, u + mk, v + mk], outline=st.goal, width=lw)
    for cx, cy in ov.collisions:
        (u, v), = cv.px([cx, cy])
        draw.line([(u - mk, v - mk), (u + mk, v + mk)], fill=st.collision, width=lw + 1)
        draw.line([(u - mk, v + mk), (u + mk, v - mk)], fill=st.collision, width=lw + 1)
    if ov.robot_pose is not None:
        x, y, yaw = ov.robot_pose
        (u, v), = cv.px([x, y])
        (hu, hv), = cv.px([x + 0.3 * math.cos(yaw), y + 0.3 * math.sin(yaw)])
        draw.ellipse([u - mk, v - mk, u + mk, v + mk], fill=st.robot)
        draw.line([(u, v), (hu, hv)], fill=st.robot, width=lw)
    return np.asarray(img)


def _erode(mask: npt.NDArray[np.bool_]) -> npt.NDArray[np.bool_]:
    """4-neighbour erosion (cells outside count as set, so borders are not edges)."""
    p = np.pad(mask, 1, constant_values=True)
    return p[1:-1, 1:-1] & p[:-2, 1:-1] & p[2:, 1:-1] & p[1:-1, :-2] & p[1:-1, 2:]


def save_png(path: str | Path, image: npt.NDArray[np.uint8]) -> Path:
    """Write an RGB array as PNG (parents created); returns the path."""
    out = Path(path)
    out.parent.mkdir(parents=True, exist_ok=True)
    Image.fromarray(np.asarray(image, dtype=np.uint8), "RGB").save(out)
    return out


def render_map_png(path: str | Path, grid: GridMap, overlays: Overlays | None = None,
                   style: RenderStyle | None = None, scale: int | None = None) -> Path:
    """:func:`render_map` straight to a PNG file."""
    return save_png(path, render_map(grid, overlays, style, scale))


class GifWriter:
    """Collects frames of a run and writes an animated GIF, with bounded memory.

    Frames are downscaled to fit ``max_side_px`` and kept every ``every``-th call. When
    ``max_frames`` are held, every other kept frame is dropped and the keep interval
    doubles, so any run length fits in ``max_frames`` frames spread over the whole run.

    Parameters
    ----------
    path : str or Path
    every : int
        Keep one frame out of this many :meth:`add` calls at first.
    max_frames : int
        Most frames held in memory (and written).
    max_side_px : int
        Frames are shrunk so their longer side is at most this.
    frame_ms : int
        Display time of each frame.
    """

    def __init__(self, path: str | Path, every: int = 1, max_frames: int = 200,
                 max_side_px: int = 480, frame_ms: int = 100) -> None:
        if every < 1 or max_frames < 2 or max_side_px < 16 or frame_ms < 1:
            raise ValueError(f"need every >= 1, max_frames >= 2, max_side_px >= 16, "
                             f"frame_ms >= 1; got {every}, {max_frames}, {max_side_px}, "
                             f"{frame_ms}")
        self.path = Path(path)
        self._every = every
        self._max = max_frames
        self._side = max_side_px
        self._ms = frame_ms
        self._calls = 0
        self._frames: list[Image.Image] = []

    def __len__(self) -> int:
        return len(self._frames)

    def add(self, image: npt.NDArray[np.uint8]) -> bool:
        """Offer a frame (RGB array); returns True when it was kept."""
        keep = self._calls % self._every == 0
        self._calls += 1
        if not keep:
            return False
        img = Image.fromarray(np.asarray(image, dtype=np.uint8), "RGB")
        w, h = img.size
        f = min(1.0, self._side / max(w, h))
        if f < 1.0:
            img = img.resize((max(1, int(w * f)), max(1, int(h * f))), Image.BILINEAR)
        # Frames of one GIF must share a size: pad/crop to the first frame's size.
        if self._frames and img.size != self._frames[0].size:
            canvas = Image.new("RGB", self._frames[0].size, (160, 160, 160))
            canvas.paste(img, (0, 0))
            img = canvas
        self._frames.append(img.convert("P", palette=Image.ADAPTIVE, colors=64))
        if len(self._frames) >= self._max:
            self._frames = self._frames[::2]
            self._every *= 2
        return True

    def write(self) -> Path:
        """Write the GIF (parents created); returns its path.

        Raises
        ------
        ValueError
            When no frame was added.
        """
        if not self._frames:
            raise ValueError("no frames to write")
        self.path.parent.mkdir(parents=True, exist_ok=True)
        first, rest = self._frames[0], self._frames[1:]
        first.save(self.path, save_all=True, append_images=rest, duration=self._ms, loop=0)
        return self.path


def engine_overlays(engine, truth: str | None = "footprint",
                    path_xy: npt.NDArray[np.float64] | None = None) -> Overlays:
    """Overlays describing a :class:`~sim_bridge.engine.SimEngine` state (pose, plan,
    collisions, goal, ground-truth outline).

    The picture is the map's: the plan and the goal are in its frame, the robot is drawn
    at its map-frame pose (``slam_pose``), and ``path_xy`` and the collisions (world
    points) are moved into the map frame by the mapping error's current drift. The
    ground-truth outline stays in the world frame: under a mapping error its offset from
    the map's walls shows the drift."""
    gt = engine.ground_truth
    truth_grid = getattr(gt, truth) if (gt is not None and truth) else None
    goal = engine.nav_status.goal
    model = engine.slam_error
    collisions = [(e.x_m, e.y_m) for e in engine.metrics.collisions]
    if model is not None:
        dx, dy, dyaw = model.drift
        c, s = math.cos(dyaw), math.sin(dyaw)
        if path_xy is not None and len(path_xy):
            p = np.asarray(path_xy, dtype=np.float64)
            path_xy = np.column_stack([dx + c * p[:, 0] - s * p[:, 1],
                                       dy + s * p[:, 0] + c * p[:, 1]])
        collisions = [(dx + c * x - s * y, dy + s * x + c * y) for x, y in collisions]
    return Overlays(
        truth=truth_grid,
        robot_path=path_xy,
        plan=engine.plan if len(engine.plan) else None,
        robot_pose=engine.slam_pose,
        collisions=collisions,
        goals=[(goal[0], goal[1])] if goal is not None else [])
