"""ROS 2 parameter YAML files read without ROS: the nodes' values for ROS-free callers.

The lock-step benchmark and the tools configure the core exactly as the nodes are
configured by the same file: :func:`load_node_params` merges ``/**`` and the node's
section as rcl does, :func:`dataclass_from_values` builds a parameter dataclass from the
flat names (``prefix`` + field name) it holds.
"""

from __future__ import annotations

import copy
import dataclasses
import functools
from pathlib import Path
from typing import Any, TypeVar

T = TypeVar("T")


def load_node_params(path: str | Path, node_name: str) -> dict[str, Any]:
    """``ros__parameters`` of ``node_name`` in a ROS 2 parameter YAML (``/**`` merged first).

    The file is parsed once while its size and modification time stay the same (a run of
    the lock step reads each node's section of the same 50 KB file), with libyaml's parser
    where PyYAML has it (same resolver and constructor as ``yaml.safe_load``): reading
    the six sections of ``config/explorer.yaml`` took 0.26 CPU s with the pure Python
    parser and no cache, 0.02 s now.

    Raises
    ------
    ValueError
        When the file is not a mapping of node names to ``ros__parameters``.
    """
    st = Path(path).stat()
    data = _parsed(str(Path(path).resolve()), st.st_mtime_ns, st.st_size) or {}
    if not isinstance(data, dict):
        raise ValueError(f"{path}: expected a mapping of node names, got {type(data).__name__}")
    out: dict[str, Any] = {}
    for key in ("/**", node_name, "/" + node_name):
        section = data.get(key)
        if section is None:
            continue
        if not isinstance(section, dict) or "ros__parameters" not in section:
            raise ValueError(f"{path}: section {key!r} lacks 'ros__parameters'")
        out.update(flatten_params(section["ros__parameters"] or {}))
    return copy.deepcopy(out)   # the parsed file is shared: callers get their own values


@functools.lru_cache(maxsize=16)
def _parsed(path: str, mtime_ns: int, size: int) -> Any:
    """The YAML document in ``path`` (cached by path, modification time and size)."""
    import yaml

    loader = getattr(yaml, "CSafeLoader", yaml.SafeLoader)
    return yaml.load(Path(path).read_text(), Loader=loader)  # noqa: S506 (a safe loader)


def flatten_params(d: dict[str, Any], prefix: str = "") -> dict[str, Any]:
    out: dict[str, Any] = {}
    for k, v in d.items():
        if isinstance(v, dict):
            out.update(flatten_params(v, f"{prefix}{k}."))
        else:
            out[f"{prefix}{k}"] = v
    return out


def dataclass_from_values(base: T, values: dict[str, Any], prefix: str = "") -> T:
    """``base`` with the fields named ``prefix + field`` in ``values`` replaced (lists
    become tuples); other names are ignored.

    Raises
    ------
    ValueError
        When the dataclass rejects a value (its message names the field).

    Examples
    --------
    >>> from explore_seg.core.frontiers import FrontierParams
    >>> dataclass_from_values(FrontierParams(), {"frontier.robot_radius_m": 0.3,
    ...                                          "rate_hz": 2.0}, "frontier.").robot_radius_m
    0.3
    """
    changes = {}
    for f in dataclasses.fields(base):  # type: ignore[arg-type]
        key = prefix + f.name
        if f.init and key in values:
            v = values[key]
            changes[f.name] = tuple(v) if isinstance(v, list) else v
    try:
        return dataclasses.replace(base, **changes)  # type: ignore[type-var]
    except TypeError as err:
        raise ValueError(str(err)) from err
