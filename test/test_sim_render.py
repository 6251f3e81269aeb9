"""Rendering of maps, overlays and GIFs."""

from __future__ import annotations

from PIL import Image
import numpy as np
import pytest

from explore_seg.core.grid import grid_from_ascii
from sim_bridge.render import GifWriter, Overlays, render_map, render_map_png


def test_render_map_colours_and_overlays(tmp_path):
    grid, _ = grid_from_ascii("""
    ?????
    ?...#
    ?...#
    """, resolution_m=0.1)
    img = render_map(grid, Overlays(collisions=[(0.25, 0.15)]), scale=10)
    assert img.shape == (30, 50, 3)
    assert tuple(img[5, 5]) == (160, 160, 160)             # unknown, top-left
    assert tuple(img[25, 45]) == (0, 0, 0)                 # occupied, bottom-right
    assert tuple(img[15, 15]) == (255, 255, 255)           # free
    red = (img[..., 0] > 200) & (img[..., 1] < 50) & (img[..., 2] < 50)
    ys, xs = np.nonzero(red)
    assert abs(xs.mean() - 25) < 2 and abs(ys.mean() - 15) < 2
    with pytest.raises(ValueError, match="regions shape"):
        render_map(grid, Overlays(regions=np.zeros((2, 2), np.int32)))
    with pytest.raises(ValueError, match="frontier mask shape"):
        render_map(grid, Overlays(frontiers=np.zeros((2, 2), bool)))
    with pytest.raises(ValueError, match="frontiers must be"):
        render_map(grid, Overlays(frontiers=np.zeros((4, 3))))
    pts = render_map(grid, Overlays(frontiers=np.array([[0.15, 0.25]])), scale=10)
    mask = np.zeros(grid.shape, bool)
    mask[2, 1] = True                                    # the same cell as a mask
    cells = render_map(grid, Overlays(frontiers=mask), scale=10)
    magenta = (255, 0, 200)
    assert tuple(pts[5, 15]) == magenta and tuple(cells[5, 15]) == magenta
    path = render_map_png(tmp_path / "m.png", grid, scale=4)
    assert Image.open(path).size == (20, 12)


def test_gif_writer_keeps_at_most_max_frames(tmp_path):
    w = GifWriter(tmp_path / "run.gif", every=1, max_frames=6, max_side_px=32)
    for k in range(50):
        w.add(np.full((64, 40, 3), k * 5, np.uint8))
    assert 3 <= len(w) < 6
    out = w.write()
    with Image.open(out) as im:
        assert im.n_frames == len(w) and max(im.size) <= 32
    with pytest.raises(ValueError, match="no frames"):
        GifWriter(tmp_path / "x.gif").write()


def test_engine_overlays_draw_the_robot_and_its_path_in_the_map_frame():
    """Under a mapping error the map is in the map frame: the robot is drawn at its SLAM
    pose, and its (world) path moved by the current drift ends there."""
    from sim_bridge.engine import SimEngine, SimParams
    from sim_bridge.render import engine_overlays
    from sim_scenes import FAST, room_world
    eng = SimEngine(room_world([]), SimParams(**{**FAST, "mapping_error": "harsh"}))
    eng.step(0.1)
    eng.set_cmd_vel(0.2, 0.3)
    eng.step(8.0)
    assert eng.slam_error is not None and np.hypot(*eng.slam_error.drift[:2]) > 1e-4
    ov = engine_overlays(eng, path_xy=eng.trail)
    assert ov.robot_pose == eng.slam_pose != eng.pose
    assert ov.robot_path[-1] == pytest.approx(eng.slam_pose[:2], abs=1e-9)
    assert ov.robot_path[0] != pytest.approx(eng.trail[0], abs=1e-9)
