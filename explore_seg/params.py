"""ROS parameters backed by a frozen dataclass (defaults live only in the dataclass).

Every node keeps its parameters in one frozen dataclass of the core whose
``__post_init__`` validates values and raises ``ValueError``. :class:`ParamBinding`
declares one ROS parameter per field (description from ``field(metadata={"doc": ...,
"unit": ...})``), rejects a ``ros2 param set`` whose candidate dataclass does not validate
(the error text is the rejection reason), and swaps ``binding.params`` after a successful
set. Parameters the binding does not own (``use_sim_time``, other bindings) pass through.
"""

from __future__ import annotations

import dataclasses
import typing
from typing import Any, Callable, Generic, TypeVar

from rcl_interfaces.msg import (FloatingPointRange, IntegerRange, ParameterDescriptor,
                                SetParametersResult)
from rclpy.node import Node
from rclpy.parameter import Parameter

from explore_seg.core.param_files import flatten_params, load_node_params  # noqa: F401 (API)

T = TypeVar("T")


def _field_kind(hint: Any) -> str:
    """'bool' | 'int' | 'float' | 'str' | 'list[<elem>]' for a field's type hint."""
    origin = typing.get_origin(hint)
    if origin is typing.Union or str(origin) == "<class 'types.UnionType'>":
        args = [a for a in typing.get_args(hint) if a is not type(None)]
        return _field_kind(args[0]) if args else "str"
    if origin in (list, tuple, typing.Sequence):
        args = [a for a in typing.get_args(hint) if a is not Ellipsis]
        elem = _field_kind(args[0]) if args else "float"
        return f"list[{elem}]"
    if hint is bool:
        return "bool"
    if hint is int:
        return "int"
    if hint is float:
        return "float"
    if hint is str:
        return "str"
    return "unsupported"


_SCALARS = {"bool": bool, "int": int, "float": float, "str": str}


def coerce_value(kind: str, name: str, value: Any, as_tuple: bool = False) -> Any:
    """Convert a ROS parameter value to the field's Python type; ValueError when impossible."""
    if kind.startswith("list["):
        elem = kind[5:-1]
        if value is None:
            value = []
        if isinstance(value, (str, bytes)) or not hasattr(value, "__iter__"):
            raise ValueError(f"parameter {name!r} expects a list of {elem}, got {value!r}")
        out = [coerce_value(elem, name, v) for v in value]
        return tuple(out) if as_tuple else out
    if kind == "bool":
        if isinstance(value, bool):
            return value
        raise ValueError(f"parameter {name!r} expects a bool, got {value!r}")
    if kind == "int":
        if isinstance(value, bool) or not isinstance(value, int):
            raise ValueError(f"parameter {name!r} expects an int, got {value!r}")
        return int(value)
    if kind == "float":
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise ValueError(f"parameter {name!r} expects a number, got {value!r}")
        return float(value)
    if kind == "str":
        if not isinstance(value, str):
            raise ValueError(f"parameter {name!r} expects a string, got {value!r}")
        return value
    raise ValueError(f"parameter {name!r} has an unsupported type")


def ros_fields(cls: type) -> list[tuple[dataclasses.Field, str]]:
    """(field, kind) for every field of a params dataclass exposed as a ROS parameter.

    Fields with ``metadata={"ros": False}`` or of unsupported types (dicts, objects) are
    not exposed.
    """
    hints = typing.get_type_hints(cls)
    out = []
    for f in dataclasses.fields(cls):
        if not f.init or f.name.startswith("_") or f.metadata.get("ros", True) is False:
            continue
        kind = _field_kind(hints.get(f.name, str))
        if kind == "unsupported" or kind == "list[unsupported]":
            continue
        out.append((f, kind))
    return out


def field_doc(f: dataclasses.Field) -> str:
    """Human description of a field: ``doc`` plus ``[unit]`` from its metadata."""
    doc = str(f.metadata.get("doc", ""))
    unit = f.metadata.get("unit")
    return f"{doc} [{unit}]" if unit else doc


def descriptor(f: dataclasses.Field, kind: str) -> ParameterDescriptor:
    """The ROS descriptor of a field: description (doc + unit), read-only flag and, where
    the field's metadata has a ``range``, a ``FloatingPointRange`` (float fields) or
    ``IntegerRange`` (int fields), so out-of-range sets are rejected by rclpy itself."""
    desc = ParameterDescriptor(description=field_doc(f), dynamic_typing=True,
                               read_only=bool(f.metadata.get("read_only", False)))
    rng = f.metadata.get("range")
    if rng is not None and kind == "float":
        step = float(rng[2]) if len(rng) > 2 else 0.0
        desc.floating_point_range = [FloatingPointRange(
            from_value=float(rng[0]), to_value=float(rng[1]), step=step)]
    elif rng is not None and kind == "int":
        step = int(rng[2]) if len(rng) > 2 else 0
        desc.integer_range = [IntegerRange(from_value=int(rng[0]), to_value=int(rng[1]),
                                           step=step)]
    return desc


class ParamBinding(Generic[T]):
    """Declare, validate and track a node's parameters from a frozen dataclass.

    Parameters
    ----------
    node : rclpy.node.Node
    defaults : dataclass instance
        Default values (normally ``MyParams()``).
    prefix : str
        Prepended to every parameter name (``"detector."``) so several bindings can share
        one node.

    Raises
    ------
    ValueError
        When the initial values (defaults + overrides) do not validate.
    """

    def __init__(self, node: Node, defaults: T, prefix: str = "") -> None:
        if not dataclasses.is_dataclass(defaults):
            raise TypeError(f"defaults must be a dataclass instance, got {type(defaults)}")
        self._node = node
        self._prefix = prefix
        self._cls = type(defaults)
        self._fields = {prefix + f.name: (f, kind) for f, kind in ros_fields(self._cls)}
        self._callbacks: list[Callable[[T, T], None]] = []
        values: dict[str, Any] = {}
        for name, (f, kind) in self._fields.items():
            default = getattr(defaults, f.name)
            ros_default = list(default) if isinstance(default, tuple) else default
            if kind.startswith("list[") and len(ros_default) == 0:
                ptype = {"list[str]": Parameter.Type.STRING_ARRAY,
                         "list[int]": Parameter.Type.INTEGER_ARRAY,
                         "list[bool]": Parameter.Type.BOOL_ARRAY}.get(
                             kind, Parameter.Type.DOUBLE_ARRAY)
                ros_default = Parameter(name, ptype, []).value
            desc = descriptor(f, kind)
            param = node.declare_parameter(name, ros_default, desc)
            values[f.name] = self._coerce(f, kind, name, param.value)
        self.params: T = dataclasses.replace(defaults, **values)
        self._pending: T | None = None
        node.add_on_set_parameters_callback(self._on_set)
        node.add_post_set_parameters_callback(self._post_set)

    @staticmethod
    def _coerce(f: dataclasses.Field, kind: str, name: str, value: Any) -> Any:
        hint_tuple = isinstance(f.default, tuple) or (
            f.default_factory is not dataclasses.MISSING  # type: ignore[misc]
            and isinstance(f.default_factory(), tuple))  # type: ignore[misc]
        return coerce_value(kind, name, value, as_tuple=hint_tuple)

    def on_change(self, callback: Callable[[T, T], None]) -> None:
        """Call ``callback(old, new)`` after every accepted change."""
        self._callbacks.append(callback)

    def _on_set(self, params: list[Parameter]) -> SetParametersResult:
        changes: dict[str, Any] = {}
        for p in params:
            entry = self._fields.get(p.name)
            if entry is None:
                continue  # not ours (use_sim_time, other bindings)
            f, kind = entry
            try:
                changes[f.name] = self._coerce(f, kind, p.name, p.value)
            except ValueError as err:
                return SetParametersResult(successful=False, reason=str(err))
        if not changes:
            return SetParametersResult(successful=True)
        try:
            self._pending = dataclasses.replace(self.params, **changes)
        except (ValueError, TypeError) as err:
            self._pending = None
            return SetParametersResult(successful=False, reason=str(err))
        return SetParametersResult(successful=True)

    def _post_set(self, params: list[Parameter]) -> None:
        if self._pending is None or not any(p.name in self._fields for p in params):
            return
        old, self.params, self._pending = self.params, self._pending, None
        for cb in self._callbacks:
            cb(old, self.params)


def overrides_from_dict(values: dict[str, Any]) -> list[Parameter]:
    """rclpy ``parameter_overrides`` from a flat name -> value mapping."""
    return [Parameter(k, value=v) for k, v in values.items()]
