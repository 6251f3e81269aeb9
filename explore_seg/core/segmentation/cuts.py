"""Cut candidates, their weights and the greedy choice of cuts (DuDe spec
shared/docs/dude.md §8-§9)."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
import numpy.typing as npt

from explore_seg.core.segmentation.params import DudeSettings
from explore_seg.core.segmentation.polygon import crosses_any, seg_dist_xy
from explore_seg.core.segmentation.rings import Notch, Ring

_TWO_PI = 2.0 * math.pi
#: Angular slack (rad) when testing whether a cut direction lies inside a wedge.
_ANGLE_EPS = 1e-6
#: Sample spacing (px) of the raster visibility test of a cut.
_SAMPLE_STEP_PX = 0.5
#: A cut whose interior samples are on the piece border for more than this fraction
#: runs along the boundary and separates nothing.
_MAX_BORDER_FRACTION = 0.5


def wedge(notch: Notch, ring: Ring, feats: list[int]) -> bool:
    """Set the feature wedge p-v-n of a notch; False when it is not reflex."""
    n = len(ring.pts)
    if len(feats) >= 3:
        arr = np.asarray(feats)
        pos = int(np.searchsorted(arr, notch.idx))
        nxt = int(arr[(pos + 1) % len(arr)]) if pos < len(arr) and arr[pos] == notch.idx \
            else int(arr[pos % len(arr)])
        prv = int(arr[pos - 1])
    else:
        nxt, prv = (notch.idx + 1) % n, (notch.idx - 1) % n
    notch.p = ring.pts[prv]
    notch.n = ring.pts[nxt]
    dn = notch.n - notch.pt
    dp = notch.p - notch.pt
    notch.a_n = math.atan2(dn[1], dn[0])
    notch.interior = (math.atan2(dp[1], dp[0]) - notch.a_n) % _TWO_PI
    return notch.interior > math.pi + _ANGLE_EPS


def resolves(v: Notch, ends: list[npt.NDArray[np.float64]], tau: float) -> bool:
    """True when cuts from ``v`` to ``ends`` (one or two points) resolve ``v`` (§8.2)."""
    vx, vy = float(v.pt[0]), float(v.pt[1])
    rel = []
    for u in ends:
        ux, uy = float(u[0]), float(u[1])
        w = (math.atan2(uy - vy, ux - vx) - v.a_n) % _TWO_PI
        if w <= _ANGLE_EPS or w >= v.interior - _ANGLE_EPS:
            return False
        rel.append((w, ux, uy))
    rel.sort(key=lambda t: t[0])
    bounds = ([(0.0, float(v.n[0]), float(v.n[1]))] + rel
              + [(v.interior, float(v.p[0]), float(v.p[1]))])
    for (w0, x0, y0), (w1, x1, y1) in zip(bounds[:-1], bounds[1:]):
        if w1 - w0 >= math.pi and seg_dist_xy(vx, vy, x0, y0, x1, y1) > tau:
            return False
    return True


def segments_clear(vis: npt.NDArray[np.bool_], border: npt.NDArray[np.bool_],
                    p0: npt.NDArray[np.float64], p1: npt.NDArray[np.float64],
                    min_len: float, code: npt.NDArray[np.uint8] | None = None
                    ) -> npt.NDArray[np.bool_]:
    """Raster test of segments p0-p1 (N, 2): inside ``vis`` and not along its border.

    Every segment is sampled every half pixel. Segments shorter than ``min_len`` and
    segments one of whose every ``_COARSE``-th samples is outside ``vis`` fail without
    the full sampling. ``code`` (optional) is ``vis + 2 * border`` as uint8, when the
    caller has it.
    """
    n = len(p0)
    out = np.zeros(n, dtype=bool)
    if n == 0:
        return out
    if code is None:
        code = vis.astype(np.uint8) | (border.astype(np.uint8) << 1)
    dx = p1[:, 0] - p0[:, 0]
    dy = p1[:, 1] - p0[:, 1]
    length = np.hypot(dx, dy)
    ns = np.maximum(2, np.ceil(length / _SAMPLE_STEP_PX).astype(np.int64))
    todo = np.flatnonzero(length >= min_len)
    if todo.size == 0:
        return out
    # coarse pass: a sample outside the piece fails the segment
    nc = (ns[todo] + _COARSE - 1) // _COARSE
    got, start = _samples(code, p0[todo], dx[todo], dy[todo], ns[todo], nc, _COARSE)
    bad = np.add.reduceat((got & 1) == 0, start, dtype=np.int64) > 0
    todo = todo[~bad]
    if todo.size == 0:
        return out
    nsel = ns[todo]
    got, start = _samples(code, p0[todo], dx[todo], dy[todo], nsel, nsel, 1)
    outside = np.add.reduceat((got & 1) == 0, start, dtype=np.int64)
    onb = np.add.reduceat(got >> 1, start, dtype=np.int64) / nsel
    out[todo] = (outside == 0) & (onb <= _MAX_BORDER_FRACTION)
    return out


#: Sample stride of the coarse pass of :func:`segments_clear`.
_COARSE = 8


def _samples(code: npt.NDArray[np.uint8], p0: npt.NDArray[np.float64],
             dx: npt.NDArray[np.float64], dy: npt.NDArray[np.float64],
             ns: npt.NDArray[np.int64], count: npt.NDArray[np.int64], stride: int
             ) -> tuple[npt.NDArray[np.uint8], npt.NDArray[np.int64]]:
    """``code`` at samples k = 0, stride, ... (``count`` per segment) of the segments'
    ``ns`` samples at t = (k + 0.5) / ns; the flat values and each segment's start."""
    seg = np.repeat(np.arange(len(ns)), count)
    start = np.cumsum(count) - count
    k = (np.arange(int(count.sum())) - np.repeat(start, count)) * stride
    t = (k + 0.5) / ns[seg]
    x = p0[seg, 0] + t * dx[seg]
    y = p0[seg, 1] + t * dy[seg]
    c = np.clip(np.rint(x).astype(np.int64), 0, code.shape[1] - 1)
    r = np.clip(np.rint(y).astype(np.int64), 0, code.shape[0] - 1)
    r *= code.shape[1]
    r += c
    return code.ravel()[r], start


@dataclass
class End:
    pt: npt.NDArray[np.float64]
    ring: int
    arc: float                 # arc position on its ring
    notch: int                 # index into the notch list, -1 for a plain point
    length: float = 0.0


@dataclass
class CutSet:
    owner: int
    cuts: list[tuple[npt.NDArray[np.float64], npt.NDArray[np.float64]]]
    resolves: set[int]
    weight: float
    far: set[int] = field(default_factory=set)     # notches at the far ends


class _Boundary:
    """All ring vertices and edges of a piece in flat arrays (built once per round)."""

    def __init__(self, rings: list[Ring]) -> None:
        sizes = np.array([len(r.pts) for r in rings])
        self.pts = np.concatenate([r.pts for r in rings])
        self.ring = np.repeat(np.arange(len(rings)), sizes)
        first = np.cumsum(sizes) - sizes
        self.idx = np.arange(len(self.pts)) - np.repeat(first, sizes)
        self.arc = np.concatenate([r.arc for r in rings])
        self.size = np.repeat(sizes, sizes)
        nxt_i = np.arange(1, len(self.pts) + 1)
        nxt_i[np.cumsum(sizes) - 1] = first          # each ring's last vertex -> its first
        nxt = self.pts[nxt_i]
        self.ab = nxt - self.pts
        self.den = np.einsum("ij,ij->i", self.ab, self.ab)
        self.len = np.sqrt(self.den)
        self.perimeter = np.array([r.perimeter for r in rings])


class _NotchTable:
    """Every notch against every boundary point, in (notches, points) arrays (built once
    per round): notch-to-notch distances, and the plain cut ends of :func:`far_ends`
    (ring vertices, then feet of perpendiculars) with their validity, ring, arc position
    and distance."""

    def __init__(self, notches: list[Notch], rings: list[Ring],
                 bd: _Boundary | None = None, st: DudeSettings | None = None) -> None:
        self.pts = np.array([u.pt for u in notches], dtype=np.float64).reshape(-1, 2)
        self.arc = [float(rings[u.ring].arc[u.idx]) for u in notches]
        vx, vy = self.pts[:, 0:1], self.pts[:, 1:2]
        self.dist = np.hypot(self.pts[None, :, 0] - vx, self.pts[None, :, 1] - vy).tolist()
        if bd is None or st is None:
            self.tips = None
            return
        vr = np.array([u.ring for u in notches], dtype=bd.ring.dtype)[:, None]
        vi = np.array([u.idx for u in notches], dtype=bd.idx.dtype)[:, None]
        same = bd.ring == vr
        near_v = same & (((bd.idx - vi) % bd.size <= 1) | ((vi - bd.idx) % bd.size <= 1))
        # perpendicular feet on edges facing v (v on the interior = left side)
        rx = vx - bd.pts[:, 0]
        ry = vy - bd.pts[:, 1]
        ok = bd.den > 1e-12
        t = np.where(ok, (rx * bd.ab[:, 0] + ry * bd.ab[:, 1]) / np.where(ok, bd.den, 1.0),
                     -1.0)
        cross = bd.ab[:, 0] * ry - bd.ab[:, 1] * rx
        own_edge = same & ((bd.idx == vi) | ((bd.idx + 1) % bd.size == vi))
        sel = ok & (t > 0.0) & (t < 1.0) & (cross > 0) & ~own_edge
        k, nb = t.shape
        px = np.concatenate([np.broadcast_to(bd.pts[:, 0], (k, nb)),
                             bd.pts[:, 0] + t * bd.ab[:, 0]], axis=1)
        py = np.concatenate([np.broadcast_to(bd.pts[:, 1], (k, nb)),
                             bd.pts[:, 1] + t * bd.ab[:, 1]], axis=1)
        ring = np.concatenate([bd.ring, bd.ring])
        arc = np.concatenate([np.broadcast_to(bd.arc, (k, nb)), bd.arc + t * bd.len], axis=1)
        dist = np.hypot(px - vx, py - vy)
        # sliver cuts (ends close along the notch's own ring, §9.2) are no candidates
        per = np.array([float(rings[u.ring].perimeter) for u in notches])[:, None]
        va = np.array(self.arc)[:, None]
        dd = np.where(per > 0, np.abs(arc - va) % np.where(per > 0, per, 1.0), 0.0)
        not_sliver = (ring != vr) | (np.minimum(dd, per - dd) > st.sliver_factor * st.tau_px)
        valid = np.concatenate([~near_v, sel], axis=1) & (dist >= 1.0) & not_sliver
        self.tips = (valid, px, py, ring, arc, dist)


def far_ends(v: Notch, vi: int, notches: list[Notch], rings: list[Ring],
              bd: _Boundary, st: DudeSettings, nt: _NotchTable | None = None
              ) -> tuple[list[End], list[End]]:
    """Candidate far ends of cuts from notch ``v`` (``notches[vi]``): other notches and
    plain points.

    Plain points are the ring vertices and the feet of the perpendiculars from ``v`` on
    the ring edges that face it; the ``max_tip_candidates`` nearest are returned. Ends
    whose cut would be a sliver cut (§9.2) are skipped.
    """
    tau = st.tau_px
    if nt is None or nt.tips is None:
        nt = _NotchTable(notches, rings, bd, st)
    assert nt.tips is not None
    per = float(rings[v.ring].perimeter)
    va = float(rings[v.ring].arc[v.idx])
    limit = st.sliver_factor * tau

    def not_sliver1(ring: int, arc: float) -> bool:
        if ring != v.ring:
            return True
        dd = abs(arc - va) % per if per > 0 else 0.0
        return min(dd, per - dd) > limit

    dist = nt.dist[vi]
    cand = [(dist[j], j) for j, u in enumerate(notches)
            if not (j == vi or (u.ring == v.ring and u.idx == v.idx))]
    cand.sort(key=lambda t: t[0])
    notch_ends = []
    for length, j in cand[:st.max_notch_candidates]:
        u = notches[j]
        if not_sliver1(u.ring, nt.arc[j]):
            notch_ends.append(End(u.pt, u.ring, nt.arc[j], j, length))
    valid, px, py, ring, arc, dist_all = nt.tips
    at = np.flatnonzero(valid[vi])
    L = dist_all[vi, at]
    k = st.max_tip_candidates
    if len(L) > k:
        part = np.argpartition(L, k)[:k]
        at, L = at[part], L[part]
    order = np.argsort(L, kind="stable")
    at = at[order]
    X, Y = px[vi, at], py[vi, at]
    tips = [End(np.array([x, y]), r, a, -1, d) for x, y, r, a, d in
            zip(X.tolist(), Y.tolist(), ring[at].tolist(), arc[vi, at].tolist(),
                L[order].tolist())]
    return notch_ends, tips


def cut_sets(notches: list[Notch], rings: list[Ring], vis: npt.NDArray[np.bool_],
             border: npt.NDArray[np.bool_], st: DudeSettings) -> list[CutSet]:
    """Cut sets of every notch with their weights (§8.2)."""
    sets: list[CutSet] = []
    for vi, vis_ends in enumerate(_visible_ends(notches, rings, vis, border, st)):
        if vis_ends:
            sets += _notch_cut_sets(vi, notches, vis_ends, st.tau_px)
    return sets


def _visible_ends(notches: list[Notch], rings: list[Ring], vis: npt.NDArray[np.bool_],
                  border: npt.NDArray[np.bool_], st: DudeSettings) -> list[list[End]]:
    """Per notch, the far ends of its cuts (to notches, then tips) whose cut is clear:
    the far ends of every notch, then one raster test of all their cuts."""
    bd = _Boundary(rings)
    nt = _NotchTable(notches, rings, bd, st)
    all_ends = []
    for vi, v in enumerate(notches):
        notch_ends, tips = far_ends(v, vi, notches, rings, bd, st, nt)
        all_ends.append(notch_ends + tips)
    counts = [len(e) for e in all_ends]
    if sum(counts) == 0:
        return [[] for _ in notches]
    P1 = np.array([e.pt for ends in all_ends for e in ends])
    P0 = np.repeat(nt.pts, counts, axis=0)
    code = vis.astype(np.uint8) | (border.astype(np.uint8) << 1)
    clear_all = segments_clear(vis, border, P0, P1, 1.5, code).tolist()
    out: list[list[End]] = []
    first = 0
    for ends in all_ends:
        clear = clear_all[first:first + len(ends)]
        first += len(ends)
        out.append([e for e, c in zip(ends, clear) if c])
    return out


def _cut_weight(vi: int, notches: list[Notch], cut_ends: list[End], res_v: bool,
                tau: float) -> tuple[set[int], float]:
    """The notches a cut set of notch ``vi`` resolves and its weight: the resolved
    notches' concavity (half for one not resolved) per length of its cuts."""
    v = notches[vi]
    resolved = {vi} if res_v else set()
    total = v.conc if res_v else 0.5 * v.conc
    length = 0.0
    for e in cut_ends:
        length += max(e.length, 1.0)
        if e.notch >= 0:
            u = notches[e.notch]
            if resolves(u, [v.pt], tau):
                resolved.add(e.notch)
                total += u.conc
            else:
                total += 0.5 * u.conc
    return resolved, total / length


def _notch_cut_sets(vi: int, notches: list[Notch], vis_ends: list[End], tau: float
                    ) -> list[CutSet]:
    """The cut sets of notch ``vi`` over its clear cuts: every single cut to a notch and
    the shortest resolving cut to a tip; else the shortest pair that resolves it jointly;
    else the single cut with the best weight."""
    v = notches[vi]
    sets: list[CutSet] = []
    singles_res = [(resolves(v, [e.pt], tau), e) for e in vis_ends]
    best_tip = None
    any_res = False
    for res, e in singles_res:
        if e.notch >= 0:
            resolved, w = _cut_weight(vi, notches, [e], res, tau)
            sets.append(CutSet(vi, [(v.pt, e.pt)], resolved, w, {e.notch}))
            any_res |= res
        elif res and (best_tip is None or e.length < best_tip.length):
            best_tip = e
    if best_tip is not None:
        resolved, w = _cut_weight(vi, notches, [best_tip], True, tau)
        sets.append(CutSet(vi, [(v.pt, best_tip.pt)], resolved, w))
        any_res = True
    if any_res:
        return sets
    # pairs of cuts: the shortest pair that resolves v jointly
    short = sorted(vis_ends, key=lambda e: e.length)[:8]
    best_pair = None
    for i in range(len(short)):
        for j in range(i + 1, len(short)):
            e1, e2 = short[i], short[j]
            tot = e1.length + e2.length
            if best_pair is not None and tot >= best_pair[0]:
                continue
            if resolves(v, [e1.pt, e2.pt], tau):
                best_pair = (tot, e1, e2)
    if best_pair is not None:
        resolved, w = _cut_weight(vi, notches, [best_pair[1], best_pair[2]], True, tau)
        far = {e.notch for e in best_pair[1:] if e.notch >= 0}
        sets.append(CutSet(vi, [(v.pt, best_pair[1].pt), (v.pt, best_pair[2].pt)],
                           resolved, w, far))
        return sets
    # nothing resolves v: keep the single cut with the best weight anyway (a cut to a
    # notch is in ``sets`` already, with this weight: every single resolved nothing)
    best, best_end = None, None
    for res, e in singles_res:
        resolved, w = _cut_weight(vi, notches, [e], False, tau)
        if best is None or w > best.weight:
            best = CutSet(vi, [(v.pt, e.pt)], resolved, w,
                          {e.notch} if e.notch >= 0 else set())
            best_end = e
    if best is not None and best_end is not None and best_end.notch < 0:
        sets.append(best)
    return sets


def choose_cuts(sets: list[CutSet]) -> list[tuple[np.ndarray, np.ndarray]]:
    """Greedy choice of cut sets (§8.3, the recommended simplification of the knapsack).

    Highest weight first, a set is accepted when it resolves a still unresolved notch,
    is not a second set of an accepted owner and crosses no accepted cut; then every
    notch still unresolved gets its best non-crossing set; finally sets whose notches
    are all resolved by others are removed, lowest weight first.
    """
    order = sorted(range(len(sets)), key=lambda i: -sets[i].weight)
    accepted: list[int] = []
    resolved: set[int] = set()

    acc_cuts: list[tuple[np.ndarray, np.ndarray]] = []

    def conflicts(i: int) -> bool:
        # same owner; a cut ending at the notch of an accepted set (that cut is one of
        # that notch's own sets too); crossing cuts
        si = sets[i]
        for j in accepted:
            sj = sets[j]
            if si.owner == sj.owner or sj.owner in si.far or si.owner in sj.far:
                return True
        if not acc_cuts:
            return False
        b0 = np.array([c[0] for c in acc_cuts])
        b1 = np.array([c[1] for c in acc_cuts])
        return any(crosses_any(a0, a1, b0, b1) for a0, a1 in si.cuts)

    def accept(i: int) -> None:
        accepted.append(i)
        acc_cuts.extend(sets[i].cuts)

    for i in order:
        s = sets[i]
        if not (s.resolves - resolved) or conflicts(i):
            continue
        accept(i)
        resolved |= s.resolves
    for i in order:
        s = sets[i]
        if s.owner in resolved or conflicts(i):
            continue
        accept(i)
        resolved |= s.resolves | {s.owner}
    for i in sorted(accepted, key=lambda k: sets[k].weight):
        others = set()
        for j in accepted:
            if j != i:
                others |= sets[j].resolves
        if sets[i].resolves and sets[i].resolves <= others:
            accepted.remove(i)
    cuts: list[tuple[np.ndarray, np.ndarray]] = []
    seen: set[tuple] = set()
    for i in accepted:
        for a, b in sets[i].cuts:
            key = tuple(sorted([(round(a[0], 3), round(a[1], 3)),
                                (round(b[0], 3), round(b[1], 3))]))
            if key in seen:
                continue
            seen.add(key)
            cuts.append((a, b))
    return cuts

