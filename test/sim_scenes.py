"""Hand-built simulator worlds (rooms, chairs, desks) shared by the engine tests."""

from __future__ import annotations

from sim_bridge.world import Primitive, World


WALL_T = 0.15
WALL_H = 2.5


def box(obj: str, cls: str, part: str, x: float, y: float, sx: float, sy: float,
        zmin: float, zmax: float) -> Primitive:
    return Primitive(obj, cls, part, "box", x, y, 0.0, (sx, sy), zmin, zmax)


def cyl(obj: str, cls: str, part: str, x: float, y: float, r: float, zmin: float,
        zmax: float) -> Primitive:
    return Primitive(obj, cls, part, "cylinder", x, y, 0.0, (r,), zmin, zmax)


def walls_around(x0: float, y0: float, x1: float, y1: float, name: str = "wall"
                 ) -> list[Primitive]:
    """Four wall boxes whose inner faces are the rectangle's sides."""
    t = WALL_T
    w, h = x1 - x0, y1 - y0
    return [box(f"{name}_s", "wall", "wall", (x0 + x1) / 2, y0 - t / 2, w + 2 * t, t, 0, WALL_H),
            box(f"{name}_n", "wall", "wall", (x0 + x1) / 2, y1 + t / 2, w + 2 * t, t, 0, WALL_H),
            box(f"{name}_w", "wall", "wall", x0 - t / 2, (y0 + y1) / 2, t, h, 0, WALL_H),
            box(f"{name}_e", "wall", "wall", x1 + t / 2, (y0 + y1) / 2, t, h, 0, WALL_H)]


def room_world(extra: list[Primitive], size=(6.0, 4.0), start=(1.0, 2.0, 0.0)) -> World:
    w, h = size
    return World(name="room", bounds=(-0.5, -0.5, w + 0.5, h + 0.5), start_pose=start,
                 primitives=walls_around(0.0, 0.0, w, h) + list(extra))


def chair(x: float, y: float) -> list[Primitive]:
    """Seat 0.5 x 0.5 m at 0.42-0.47 m on four 0.02 m legs, backrest on the +x side."""
    legs = [cyl("chair_1", "chair", "leg", x + dx, y + dy, 0.02, 0.0, 0.42)
            for dx in (-0.23, 0.23) for dy in (-0.23, 0.23)]
    return legs + [box("chair_1", "chair", "seat", x, y, 0.5, 0.5, 0.42, 0.47),
                   box("chair_1", "chair", "back", x + 0.23, y, 0.04, 0.5, 0.47, 0.9)]


def narrowing_corridor_world() -> World:
    """An 8 x 4 m room whose east wall opens (0.6 m) into a 1 m corridor that narrows to
    0.34 m (narrower than the 0.44 m robot) for 6 m: the narrow part's far end is seen
    only from the corridor's passable mouth, more than a frontier search radius away."""
    t = WALL_T
    L, W, X1, X2 = 8.0, 4.0, 9.0, 15.0
    yl, yh, nl, nh = 1.7, 2.3, 1.83, 2.17
    prims = [box("wall_s", "wall", "wall", L / 2, -t / 2, L + 2 * t, t, 0, WALL_H),
             box("wall_n", "wall", "wall", L / 2, W + t / 2, L + 2 * t, t, 0, WALL_H),
             box("wall_w", "wall", "wall", -t / 2, W / 2, t, W, 0, WALL_H),
             box("wall_e1", "wall", "wall", L + t / 2, yl / 2, t, yl, 0, WALL_H),
             box("wall_e2", "wall", "wall", L + t / 2, (yh + W) / 2, t, W - yh, 0, WALL_H),
             box("cor_s", "wall", "wall", (L + X1) / 2, yl - t / 2, X1 - L, t, 0, WALL_H),
             box("cor_n", "wall", "wall", (L + X1) / 2, yh + t / 2, X1 - L, t, 0, WALL_H),
             box("step_s", "wall", "wall", X1 + t / 2, (yl + nl) / 2, t, nl - yl, 0, WALL_H),
             box("step_n", "wall", "wall", X1 + t / 2, (nh + yh) / 2, t, yh - nh, 0, WALL_H),
             box("nar_s", "wall", "wall", (X1 + X2) / 2, nl - t / 2, X2 - X1, t, 0, WALL_H),
             box("nar_n", "wall", "wall", (X1 + X2) / 2, nh + t / 2, X2 - X1, t, 0, WALL_H),
             box("nar_e", "wall", "wall", X2 + t / 2, 2.0, t, nh - nl + 2 * t, 0, WALL_H)]
    return World(name="narrowing_corridor", bounds=(-0.5, -0.5, X2 + 0.5, W + 0.5),
                 start_pose=(1.0, 2.0, 0.0), primitives=prims)


FAST = dict(compute_coverage=False, lidar_noise_std_m=0.0)
