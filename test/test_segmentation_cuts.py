"""Cut sets and their choice (explore_seg.core.segmentation.cuts)."""

from __future__ import annotations

import numpy as np

from explore_seg.core.segmentation import DudeSettings, cuts
from explore_seg.core.segmentation.rings import Notch, Ring


def test_cut_sets_no_duplicate_when_nothing_resolves_a_notch(monkeypatch):
    """A notch whose cuts to two other notches resolve nothing keeps its best single cut
    once: it is among the single cuts already (this used to compare the cut sets' numpy
    end points with ``in`` and raise "truth value of an array is ambiguous" in a maze)."""
    ring = Ring(np.array([[0.0, 0.0], [10.0, 0.0], [10.0, 10.0], [0.0, 10.0]]),
                np.zeros((4, 1, 2), np.int32), False)
    notches = [Notch(0, k, np.array(p, float), 1.0)
               for k, p in enumerate([(0.0, 0.0), (10.0, 0.0), (10.0, 10.0)])]
    far = [cuts.End(np.array([10.0, 0.0]), 0, 10.0, 1, 10.0),    # weight 1/10
           cuts.End(np.array([10.0, 10.0]), 0, 20.0, 2, 5.0)]    # weight 1/5: the best
    monkeypatch.setattr(cuts, "far_ends",
                        lambda v, vi, *a: (list(far), []) if vi == 0 else ([], []))
    monkeypatch.setattr(cuts, "segments_clear", lambda vis, border, P0, P1, *a:
                        np.ones(len(P1), bool))
    monkeypatch.setattr(cuts, "resolves", lambda v, ends, tau: False)
    st = DudeSettings(tau_px=2.0, simplify_eps_px=1.0, min_hole_area_px=1.0,
                      min_component_px=1, max_rounds=1)
    sets = cuts.cut_sets(notches, [ring], np.ones((12, 12), bool), np.zeros((12, 12), bool), st)
    assert [(s.owner, s.far, round(s.weight, 3)) for s in sets] == [(0, {1}, 0.1), (0, {2}, 0.2)]
