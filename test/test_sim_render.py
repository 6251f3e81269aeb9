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
