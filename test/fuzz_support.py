"""Fuzz helpers: named malformed and random ROS messages of any type, and a driver that
feeds them to a node's own subscription callbacks and timers while recording what the
node logs and how much it allocates (issue 24's fuzz suite, test/test_fuzz_nodes.py).

Messages are built through the rosidl type description (``SLOT_TYPES``), so every field
of every subscribed type is covered without a list per type. Values are drawn from
extremes (NaN, +-inf, 1e300, the integer type's bounds, empty and odd strings, sequences
of the wrong length) and plain random numbers; setters that reject a value (rclpy checks
types and integer ranges) simply leave that field as it was. Everything is seeded.
"""

from __future__ import annotations

import array
import copy
import importlib
import math
import time
import tracemalloc
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable

import numpy as np
from rosidl_parser.definition import (AbstractGenericString, AbstractNestedType,
                                      AbstractSequence, Array, BasicType, NamespacedType)

FLOATS = (0.0, -0.0, 1.0, -1.0, 0.5, 1e-300, 1e-9, 1e9, 1e300, -1e300, 1.7e308,
          math.nan, math.inf, -math.inf)
STRINGS = ("", "/", "map", "/map", "odom", "//map", " ", "a" * 300, "ünï/cödé", "\t\n")
_INT_BOUNDS = {"int8": (-2**7, 2**7 - 1), "uint8": (0, 2**8 - 1), "char": (0, 2**8 - 1),
               "int16": (-2**15, 2**15 - 1), "uint16": (0, 2**16 - 1),
               "int32": (-2**31, 2**31 - 1), "uint32": (0, 2**32 - 1),
               "int64": (-2**63, 2**63 - 1), "uint64": (0, 2**64 - 1)}
_TYPECODES = {"int8": "b", "uint8": "B", "int16": "h", "uint16": "H", "int32": "i",
              "uint32": "I", "int64": "q", "uint64": "Q", "float": "f", "double": "d"}
_NP_DTYPES = {"int8": np.int8, "uint8": np.uint8, "int16": np.int16, "uint16": np.uint16,
              "int32": np.int32, "uint32": np.uint32, "int64": np.int64,
              "uint64": np.uint64, "float": np.float32, "double": np.float64}
#: Longest random sequence (elements): big enough to mismatch any claimed size, small
#: enough that a few hundred messages stay cheap.
MAX_SEQ = 5000
_RSS_PAGE = 4096


def _msg_class(t: NamespacedType) -> type:
    return getattr(importlib.import_module(".".join(t.namespaces)), t.name)


def _scalar(t: BasicType, rng: np.random.Generator) -> Any:
    name = t.typename
    if name in ("float", "double"):
        if rng.random() < 0.6:
            return float(FLOATS[rng.integers(len(FLOATS))])
        return float(rng.normal() * 10.0 ** rng.integers(-3, 6))
    if name == "boolean":
        return bool(rng.integers(2))
    if name in ("octet", "byte"):
        return bytes([int(rng.integers(256))])
    lo, hi = _INT_BOUNDS.get(name, (0, 255))
    pick = rng.integers(5)
    if pick == 0:
        return lo
    if pick == 1:
        return hi
    if pick == 2:
        return int(rng.integers(-3, 4)) if lo < 0 else int(rng.integers(0, 4))
    return int(rng.integers(lo, hi, dtype=np.int64 if hi < 2**63 else np.uint64))


def _sequence(t: AbstractNestedType, rng: np.random.Generator, current: Any) -> Any:
    """A random value for a sequence/array field (fixed arrays keep their size)."""
    vt = t.value_type
    if isinstance(t, Array):
        n = t.size
    else:
        cur = len(current) if current is not None else 0
        choices = (0, 1, 3, cur, cur + 1, max(0, cur - 1), int(rng.integers(0, 2 * cur + 8)))
        n = min(MAX_SEQ, choices[rng.integers(len(choices))])
        if isinstance(t, AbstractSequence) and getattr(t, "maximum_size", None):
            n = min(n, t.maximum_size)
    if isinstance(vt, BasicType) and vt.typename in _NP_DTYPES:
        dt = _NP_DTYPES[vt.typename]
        if vt.typename in ("float", "double"):
            vals = np.where(rng.random(n) < 0.1, np.nan, rng.normal(size=n) * 100).astype(dt)
        else:
            info = np.iinfo(dt)
            vals = rng.integers(max(info.min, -200), min(info.max, 200), size=n,
                                endpoint=True).astype(dt)
        return vals if isinstance(t, Array) else array.array(_TYPECODES[vt.typename],
                                                             vals.tobytes())
    if isinstance(vt, NamespacedType):
        cls = _msg_class(vt)
        return [random_message(cls, rng, depth=1) for _ in range(min(n, 3))]
    if isinstance(vt, AbstractGenericString):
        return [STRINGS[rng.integers(len(STRINGS))] for _ in range(min(n, 4))]
    return [_scalar(vt, rng) for _ in range(min(n, 16))]


def _value(t: Any, rng: np.random.Generator, current: Any, depth: int) -> Any:
    if isinstance(t, NamespacedType):
        return random_message(_msg_class(t), rng, depth + 1)
    if isinstance(t, AbstractNestedType):
        return _sequence(t, rng, current)
    if isinstance(t, AbstractGenericString):
        return STRINGS[rng.integers(len(STRINGS))]
    return _scalar(t, rng)


def _set(obj: Any, name: str, value: Any) -> bool:
    try:
        setattr(obj, name, value)
        return True
    except (AssertionError, TypeError, ValueError, OverflowError):
        return False            # rclpy's setter rejects it: the field keeps its value


def random_message(cls: type, rng: np.random.Generator, depth: int = 0) -> Any:
    """A message of type ``cls`` with every field random (nested ones too, 3 levels)."""
    msg = cls()
    if depth > 3:
        return msg
    for name, t in zip(msg.__slots__, cls.SLOT_TYPES):
        _set(msg, name[1:], _value(t, rng, getattr(msg, name[1:]), depth))
    return msg


def _leaves(msg: Any, depth: int = 0) -> list[tuple[Any, str, Any]]:
    """(owner, field name, rosidl type) of every field, nested messages included."""
    out = []
    for slot, t in zip(msg.__slots__, type(msg).SLOT_TYPES):
        name = slot[1:]
        out.append((msg, name, t))
        if isinstance(t, NamespacedType) and depth < 4:
            out += _leaves(getattr(msg, name), depth + 1)
        elif (isinstance(t, AbstractNestedType) and isinstance(t.value_type, NamespacedType)
              and depth < 4):
            for item in list(getattr(msg, name))[:3]:
                out += _leaves(item, depth + 1)
    return out


def mutate(good: Any, rng: np.random.Generator, n_fields: int = 2) -> Any:
    """A copy of ``good`` with ``n_fields`` random fields set to extreme/random values."""
    msg = copy.deepcopy(good)
    leaves = _leaves(msg)
    for k in rng.choice(len(leaves), size=min(n_fields, len(leaves)), replace=False):
        owner, name, t = leaves[int(k)]
        _set(owner, name, _value(t, rng, getattr(owner, name), 2))
    return msg


def _edit(good: Any, fn: Callable[[Any, str, Any], bool]) -> Any | None:
    """A copy of ``good`` where ``fn(owner, name, type)`` edited some field, else None."""
    msg = copy.deepcopy(good)
    changed = [fn(o, n, t) for o, n, t in _leaves(msg)]
    return msg if any(changed) else None


def _float_fields(value: float) -> Callable[[Any, str, Any], bool]:
    def fn(o, n, t):
        if isinstance(t, BasicType) and t.typename in ("float", "double"):
            return _set(o, n, value)
        return False
    return fn


def _named(names: tuple[str, ...], value: Any) -> Callable[[Any, str, Any], bool]:
    return lambda o, n, t: n in names and _set(o, n, value)


#: Named malformed cases: edits that apply to any message with such fields.
NAMED_EDITS: dict[str, Callable[[Any, str, Any], bool]] = {
    "negative_stamp": _named(("sec",), -5),
    "far_future_stamp": _named(("sec",), 2**31 - 1),
    "frame_other": _named(("frame_id",), "odom"),
    "frame_leading_slash": _named(("frame_id",), "/map"),
    "frame_empty": _named(("frame_id",), ""),
    "all_floats_nan": _float_fields(math.nan),
    "all_floats_inf": _float_fields(math.inf),
    "all_floats_huge": _float_fields(1e300),
    "all_floats_zero": _float_fields(0.0),
    "all_floats_negative": _float_fields(-1.0),
    "huge_claimed_size": _named(("width", "height"), 100_000),
    "max_claimed_size": _named(("width", "height", "step"), 2**32 - 1),
    "zero_size": _named(("width", "height"), 0),
    "empty_data": lambda o, n, t: (isinstance(t, AbstractSequence) and len(getattr(o, n)) > 0
                                   and _set(o, n, [])),
    "bad_encoding": _named(("encoding",), "bogus16"),
    "quaternion_zero": lambda o, n, t: (type(o).__name__ == "Quaternion" and
                                        all(_set(o, c, 0.0) for c in "xyzw")),
}


def named_cases(good: Any) -> dict[str, Any]:
    """The :data:`NAMED_EDITS` that apply to ``good``'s type (plus the default message)."""
    out = {"default_constructed": type(good)()}
    for name, fn in NAMED_EDITS.items():
        msg = _edit(good, fn)
        if msg is not None:
            out[name] = msg
    return out


class LogCapture:
    """Records what a node's logger actually emits (after rclpy's own throttling)."""

    def __init__(self, node: Any) -> None:
        from rclpy.impl import rcutils_logger

        # rclpy keys its per-call-site throttling on the first caller outside its own
        # files: the wrapper below must count as one of them.
        here = str(Path(__file__).resolve())
        if here not in rcutils_logger._internal_callers:       # noqa: SLF001
            rcutils_logger._internal_callers.append(here)      # noqa: SLF001
        self.lines: list[tuple[int, str]] = []
        logger = node.get_logger()
        orig = logger.log

        def log(message, severity, **kwargs):
            emitted = orig(message, severity, **kwargs)
            if emitted:
                self.lines.append((int(severity), str(message)))
            return emitted

        logger.log = log


def rss_mb() -> float:
    """This process's resident memory (MB)."""
    return int(Path("/proc/self/statm").read_text().split()[1]) * _RSS_PAGE / 2**20


@dataclass
class FuzzReport:
    """What one fuzz run delivered and what the node did meanwhile."""

    messages: int = 0
    ticks: int = 0
    wall_s: float = 0.0
    peak_alloc_mb: float = 0.0
    rss_growth_mb: float = 0.0
    per_topic: dict[str, int] = field(default_factory=dict)


def fuzz_node(node: Any, good: dict[str, Any], rng: np.random.Generator,
              per_topic: int = 200, tick_every: int = 10,
              skip: tuple[str, ...] = ()) -> FuzzReport:
    """Feed every subscription of ``node`` its named malformed cases and ``per_topic``
    random messages (mutations of ``good[topic]``, a third fully random), calling the
    node's timer callbacks every ``tick_every`` messages (0: never, e.g. for the
    simulator, whose tick steps the world on the wall clock). ``good`` maps topic names
    (without the leading '/') to a valid message; topics in ``skip`` are left out.
    Exceptions propagate (EXPLORE_SEG_STRICT=1 in the tests): a crash fails the test."""
    # (topic, type, callback) taken now: a node may destroy and remake subscriptions
    # while it runs (DoneGate), the callbacks stay the same.
    subs = [(s.topic_name.lstrip("/"), s.msg_type, s.callback) for s in node.subscriptions]
    subs = [s for s in subs if s[0] not in skip + ("clock", "parameter_events")]
    # Warm-up with the good messages: one-time tables (e.g. the path graph's block
    # look-up tables) and lazy imports are not allocation per message.
    for topic, _, callback in subs:
        if topic in good:
            callback(good[topic])
    tick(node, 1 if tick_every else 0)
    rep = FuzzReport()
    rss0 = rss_mb()
    tracemalloc.start()
    base = tracemalloc.get_traced_memory()[0]
    t0 = time.perf_counter()
    try:
        for topic, msg_type, callback in subs:
            base_msg = good.get(topic, msg_type())
            msgs = list(named_cases(base_msg).values())
            for i in range(per_topic):
                msgs.append(random_message(msg_type, rng) if i % 3 == 2
                            else mutate(base_msg, rng, int(rng.integers(1, 4))))
            for msg in msgs:
                callback(msg)
                rep.messages += 1
                if tick_every and rep.messages % tick_every == 0:
                    for timer in list(node.timers):
                        timer.callback()
                    rep.ticks += 1
            rep.per_topic[topic] = len(msgs)
    finally:
        rep.wall_s = time.perf_counter() - t0
        rep.peak_alloc_mb = (tracemalloc.get_traced_memory()[1] - base) / 2**20
        tracemalloc.stop()
        rep.rss_growth_mb = rss_mb() - rss0
    return rep


def tick(node: Any, n: int = 1) -> None:
    """Call every timer callback of ``node`` ``n`` times (no clock, no spinning)."""
    for _ in range(n):
        for timer in list(node.timers):
            timer.callback()
