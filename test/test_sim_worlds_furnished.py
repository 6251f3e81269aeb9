"""Furnished floor plans for the segmentation evaluation (sim_bridge.worlds.furnished)."""

from __future__ import annotations

import numpy as np
import pytest

from scipy import ndimage

from sim_bridge.worlds.furnished import MAP_KINDS, REAL_KINDS, furnished_map, furnished_set
from sim_bridge.worlds.raster_furniture import REAL_ROOM_KINDS, furnish_real_room


@pytest.mark.parametrize("seed, kind", [(0, "office"), (1, "open_office"), (2, "home")])
def test_furnished_map_invariants(seed, kind):
    m = furnished_map(seed, kind)
    plain, furn = m.plain.data, m.furnished.data
    assert plain.shape == furn.shape == m.plain_rooms.shape == m.furnished_rooms.shape
    # plain: every inside cell free and labelled with a room
    assert ((m.plain_rooms > 0) == (plain == 0)).all()
    # furnished: labels only on free cells, the plain labels there
    assert ((m.furnished_rooms > 0) == (furn == 0)).all()
    free = furn == 0
    assert (m.furnished_rooms[free] == m.plain_rooms[free]).all()
    # furniture is drawn: occupied cells where the plain map is free, unknown inside
    assert ((furn == 100) & (plain == 0)).sum() > 200
    assert ((furn == -1) & (plain == 0)).any()
    assert set(m.room_kinds.values()) - {"corridor"}
    assert len(np.unique(m.plain_rooms)) - 1 >= 4


def test_furnished_map_is_seeded():
    a, b = furnished_map(4, "open_office"), furnished_map(4, "open_office")
    assert np.array_equal(a.furnished.data, b.furnished.data)
    assert not np.array_equal(a.furnished.data, furnished_map(7, "open_office").furnished.data)


def test_furnished_set_cycles_kinds():
    s = furnished_set(30)
    assert len(s) == 30 and {k for _s, k in s} == set(MAP_KINDS)
    with pytest.raises(ValueError):
        furnished_map(0, "castle")


def test_real_office_is_drawn_like_the_real_plans():
    """real_office: furniture drawn into the plan, nothing unknown inside, every room
    furnished with a kind of REAL_ROOM_KINDS; the default set leaves it out."""
    m = furnished_map(1000, "real_office")
    plain, furn = m.plain.data, m.furnished.data
    assert ((m.furnished_rooms > 0) == (furn == 0)).all()
    assert not ((furn == -1) & (plain == 0)).any()
    assert set(m.room_kinds.values()) <= set(REAL_ROOM_KINDS)
    drawn = (furn == 100) & (plain == 0)
    assert drawn.sum() > 0.05 * (plain == 0).sum()
    assert np.array_equal(furn, furnished_map(1000, "real_office").furnished.data)
    assert "real_office" not in {k for _s, k in furnished_set(30)}
    assert {k for _s, k in furnished_set(4, 1000, REAL_KINDS)} == set(REAL_KINDS)
    with pytest.raises(ValueError, match="kinds must be"):
        furnished_set(3, 0, ("castle",))


def _real_room(kind: str, w_m: float = 8.0, h_m: float = 6.0, seed: int = 3) -> np.ndarray:
    res = 0.05
    occ = np.zeros((round(h_m / res), round(w_m / res)), bool)
    furnish_real_room(np.random.default_rng(seed), occ, (0, 0) + occ.shape,
                      np.zeros(occ.shape, bool), kind, res)
    return occ


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_real_meeting_room_is_a_ring_round_a_table_block(seed):
    """The free space round the table block is one ring: it touches all four walls'
    margins, and the block stands off every wall by at least 0.8 m."""
    occ = _real_room("meeting", seed=seed)
    rows, cols = np.nonzero(occ[round(1.0 / 0.05):-round(1.0 / 0.05),
                                round(1.0 / 0.05):-round(1.0 / 0.05)])
    assert rows.size > 0                                  # a block in the middle
    lab = ndimage.label(~occ)[0]
    margin = np.concatenate([lab[16, 16:-16], lab[-17, 16:-16], lab[16:-16, 16],
                             lab[16:-16, -17]])
    assert len(set(margin.tolist()) - {0}) == 1           # one ring of free space


@pytest.mark.parametrize("seed", [0, 1, 2, 3, 4])
def test_real_lab_has_table_rows_with_aisles_and_a_walkway(seed):
    """Rows of tables along the longer side (x) fill the room, ~1 m aisles of free rows
    between them, a free walkway across the rows at one end."""
    occ = _real_room("lab", 8.0, 6.0, seed=seed)
    used = np.flatnonzero(occ.any(axis=1))
    assert used.size and (used[-1] - used[0]) * 0.05 >= 3.0      # rows over the room
    free_rows = np.flatnonzero(~occ[used[0]:used[-1]].any(axis=1))
    runs = np.split(free_rows, np.flatnonzero(np.diff(free_rows) > 1) + 1)
    aisles = [r for r in runs if r.size * 0.05 >= 0.85]
    assert len(aisles) >= 1
    # every row reaches a side wall at one end, a walkway of free columns at the other
    assert occ[:, 0].any() != occ[:, -1].any()
    free_cols = np.flatnonzero(~occ.any(axis=0))
    assert free_cols.size * 0.05 >= 0.85


def test_real_store_room_is_a_comb_of_shelves():
    occ = _real_room("store", 8.0, 4.0, seed=1)
    stubs = ndimage.label(occ)[1]
    assert stubs >= 3
    assert occ[0].any() and not occ[round(1.7 / 0.05):].any()
    with pytest.raises(ValueError, match="real room kind"):
        _real_room("castle")
