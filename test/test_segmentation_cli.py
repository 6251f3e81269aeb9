"""``segment_map`` command line tool (explore_seg.segment_cli)."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from explore_seg.segment_cli import load_map, main
from test_segmentation import two_rooms


def _pgm_of(grid) -> np.ndarray:
    """map_server image of a grid: 254 free, 0 occupied, 205 unknown; row 0 = top."""
    img = np.full(grid.shape, 205, np.uint8)
    img[grid.data == 0] = 254
    img[grid.data == 100] = 0
    return img[::-1].copy()


@pytest.fixture
def map_files(tmp_path):
    g = two_rooms(door_at_end=True)
    pgm = tmp_path / "house.pgm"
    cv2.imwrite(str(pgm), _pgm_of(g))
    yaml = tmp_path / "house.yaml"
    yaml.write_text("image: house.pgm\nresolution: 0.05\norigin: [-1.0, 2.0, 0.0]\n"
                    "negate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.196\n")
    return g, yaml, pgm, tmp_path


def test_yaml_map_gives_a_16bit_label_png_in_file_orientation(map_files):
    g, yaml, _pgm, tmp = map_files
    out, color = tmp / "labels.png", tmp / "color.png"
    assert main([str(yaml), "--out", str(out), "--color", str(color), "--tau", "2.5"]) == 0
    lab = cv2.imread(str(out), cv2.IMREAD_UNCHANGED)
    assert lab.dtype == np.uint16 and lab.shape == g.shape
    assert sorted(np.unique(lab).tolist()) == [0, 1, 2]
    # row 0 of the file is the top of the map: the free cells line up with the PGM
    assert ((lab[::-1] > 0) <= (g.data == 0)).all()
    rgb = cv2.imread(str(color), cv2.IMREAD_COLOR)
    assert rgb.shape == g.shape + (3,)


def test_load_map_reads_yaml_geometry_and_trinary_values(map_files):
    g, yaml, pgm, _tmp = map_files
    m = load_map(yaml)
    assert m.resolution_m == 0.05 and m.origin_xy_m == (-1.0, 2.0)
    np.testing.assert_array_equal(m.data, g.data)
    bare = load_map(pgm, resolution_m=0.1)
    assert bare.resolution_m == 0.1
    # bare images as IPA: >= 250 free, everything else (unknown included) occupied
    np.testing.assert_array_equal(bare.data, np.where(g.data == 0, 0, 100))


def test_bare_png_image(map_files):
    g, _yaml, _pgm, tmp = map_files
    png = tmp / "ipa.png"
    img = np.where(_pgm_of(g) == 254, 255, 0).astype(np.uint8)
    cv2.imwrite(str(png), img)
    out = tmp / "l.png"
    assert main([str(png), "--out", str(out)]) == 0
    assert cv2.imread(str(out), cv2.IMREAD_UNCHANGED).max() == 2


@pytest.mark.parametrize("content, what", [
    (b"\x89PNG\r\n\x1a\n garbage", "corrupt"),
    (b"", "empty"),
])
def test_corrupt_image_fails_cleanly(tmp_path, capsys, content, what):
    bad = tmp_path / "bad.png"
    bad.write_bytes(content)
    assert main([str(bad), "--out", str(tmp_path / "o.png")]) == 1
    assert "not a readable image" in capsys.readouterr().err
    assert not (tmp_path / "o.png").exists()


@pytest.mark.parametrize("yaml_text, match", [
    ("image: nothere.pgm\nresolution: 0.05\norigin: [0, 0, 0]\n", "no such file"),
    ("resolution: 0.05\n", "image"),
    ("image: house.pgm\nresolution: -1\n", "resolution"),
    ("image: house.pgm\nresolution: 0.05\nmode: fancy\n", "mode"),
    ("image: house.pgm\nresolution: 0.05\norigin: 5\n", "origin"),
    ("[unclosed", "YAML"),
    ("- a\n- b\n", "mapping"),
])
def test_bad_yaml_fails_with_a_message(map_files, capsys, yaml_text, match):
    _g, _yaml, _pgm, tmp = map_files
    y = tmp / "bad.yaml"
    y.write_text(yaml_text)
    assert main([str(y), "--out", str(tmp / "o.png")]) == 1
    assert match in capsys.readouterr().err


def test_wrong_encodings_and_arguments(map_files, capsys):
    _g, yaml, _pgm, tmp = map_files
    deep = tmp / "deep.png"
    cv2.imwrite(str(deep), np.zeros((10, 10), np.uint16))
    assert main([str(deep), "--out", str(tmp / "o.png")]) == 1
    assert "8-bit" in capsys.readouterr().err
    assert main([str(yaml), "--out", str(tmp / "o.jpg")]) == 2
    assert main([str(yaml), "--out", str(tmp / "o.png"), "--tau", "-1"]) == 2
    assert main([str(yaml)]) == 2                              # --out missing
    assert main([str(tmp / "missing.pgm"), "--out", str(tmp / "o.png")]) == 1
    assert main([str(yaml), "--out", str(tmp / "no" / "dir" / "o.png")]) == 1
