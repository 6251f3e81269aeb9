"""Furnished floor plans for the segmentation evaluation (sim_bridge.worlds.furnished)."""

from __future__ import annotations

import numpy as np
import pytest

from sim_bridge.worlds.furnished import MAP_KINDS, furnished_map, furnished_set


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
