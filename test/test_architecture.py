"""Imports flow one way: nodes -> convert -> core; sim_bridge -> core; core imports no ROS."""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
ROS_MODULES = ("rclpy", "rcl_interfaces", "builtin_interfaces", "std_msgs", "std_srvs",
               "geometry_msgs", "nav_msgs", "sensor_msgs", "visualization_msgs",
               "diagnostic_msgs", "rosgraph_msgs", "ament_index_python", "action_msgs")
#: sim_bridge's ROS side: the node and the action status/cancel it serves.
SIM_ROS_FILES = ("node.py", "nav_action.py")


def _imports(path: Path) -> set[str]:
    tree = ast.parse(path.read_text(), filename=str(path))
    mods: set[str] = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            mods.update(a.name for a in node.names)
        elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            mods.add(node.module)
    return mods


def _files(sub: str) -> list[Path]:
    return sorted((ROOT / sub).rglob("*.py"))


@pytest.mark.parametrize("path", _files("explore_seg/core"), ids=lambda p: p.name)
def test_core_imports_no_ros_and_nothing_outside_core(path):
    for mod in _imports(path):
        top = mod.split(".")[0]
        assert top not in ROS_MODULES, f"{path.name} imports {mod}"
        assert top != "sim_bridge", f"{path.name} imports the simulator ({mod})"
        if top == "explore_seg":
            assert mod.startswith("explore_seg.core"), f"{path.name} imports {mod}"


@pytest.mark.parametrize("path", [p for p in _files("sim_bridge") if p.name not in SIM_ROS_FILES],
                         ids=lambda p: p.name)
def test_sim_engine_is_ros_free(path):
    for mod in _imports(path):
        assert mod.split(".")[0] not in ROS_MODULES, f"{path.name} imports {mod}"


@pytest.mark.parametrize("path", _files("explore_seg"), ids=lambda p: p.name)
def test_package_never_imports_the_simulator(path):
    for mod in _imports(path):
        assert mod.split(".")[0] != "sim_bridge", f"{path} imports {mod}"


def test_only_convert_builds_arrays_from_message_buffers():
    offenders = []
    for path in _files("explore_seg") + _files("sim_bridge"):
        if path.name == "convert.py":
            continue
        text = path.read_text()
        if "np.frombuffer(msg" in text or "frombuffer(msg.data" in text:
            offenders.append(str(path.relative_to(ROOT)))
    assert offenders == []


# ------------------------------------------------------------ circles, size, one decision core

PROJECT_PACKAGES = ("explore_seg", "sim_bridge", "bench")
#: Longest file allowed in the package and the simulator.
MAX_LINES = 600
#: Names of the decision loop's pieces: outside the core's selection package and its
#: decision API only ``explore_seg.core.explorer.Explorer`` wires them.
WIRING_NAMES = {"PathGraphs", "GoalManager", "frontier_distances", "select_goal"}
WIRING_HOMES = ("explore_seg/core/selection/", "explore_seg/core/explorer.py")


def _module_name(path: Path) -> str:
    rel = path.relative_to(ROOT).with_suffix("")
    parts = rel.parts[:-1] if rel.name == "__init__" else rel.parts
    return ".".join(parts)


def _project_modules() -> dict[str, Path]:
    out = {}
    for pkg in PROJECT_PACKAGES:
        for path in _files(pkg):
            out[_module_name(path)] = path
    return out


def _all_imports(path: Path) -> set[str]:
    """Every absolute import target of a file, top-level and inside functions alike
    (``from a.b import c`` counts as ``a.b`` and, when it is a module, ``a.b.c``); imports
    under ``if TYPE_CHECKING:`` do not run and are left out."""
    tree = ast.parse(path.read_text(), filename=str(path))
    skip: set[int] = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.If) and "TYPE_CHECKING" in ast.unparse(node.test):
            skip.update(id(n) for stmt in node.body for n in ast.walk(stmt))
    mods: set[str] = set()
    for node in ast.walk(tree):
        if id(node) in skip:
            continue
        if isinstance(node, ast.Import):
            mods.update(a.name for a in node.names)
        elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            mods.add(node.module)
            mods.update(f"{node.module}.{a.name}" for a in node.names)
    return mods


def _import_graph() -> dict[str, set[str]]:
    """module -> project modules it imports (a package's ``__init__`` runs before its
    submodules, so importing ``a.b.c`` also imports ``a.b`` and ``a``; a module's own
    ancestor packages are already importing, so they are not edges)."""
    modules = _project_modules()
    graph: dict[str, set[str]] = {m: set() for m in modules}
    for mod, path in modules.items():
        own = {".".join(mod.split(".")[:k]) for k in range(1, mod.count(".") + 1)}
        if path.name == "__init__.py":
            own.add(mod)
        for target in _all_imports(path):
            parts = target.split(".")
            for k in range(1, len(parts) + 1):
                pre = ".".join(parts[:k])
                if pre in modules and pre not in own and pre != mod:
                    graph[mod].add(pre)
    return graph


def _cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """Strongly connected components with more than one module (Tarjan)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on: set[str] = set()
    out: list[list[str]] = []

    def visit(v: str) -> None:
        index[v] = low[v] = len(index)
        stack.append(v)
        on.add(v)
        for w in sorted(graph[v]):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                out.append(sorted(comp))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return out


def test_no_import_circles_not_even_through_function_level_imports():
    assert _cycles(_import_graph()) == []


def test_the_circle_finder_finds_a_circle_hidden_in_a_function():
    graph = {"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}
    assert _cycles(graph) == [["a", "b", "c"]]
    assert _cycles({"a": {"b"}, "b": set()}) == []


def test_function_level_imports_are_seen(tmp_path):
    f = tmp_path / "m.py"
    f.write_text("import os\n\ndef g():\n    from explore_seg.core import grid\n"
                 "from typing import TYPE_CHECKING\nif TYPE_CHECKING:\n    import sim_bridge\n")
    assert {"explore_seg.core", "explore_seg.core.grid", "os"} <= _all_imports(f)
    assert "sim_bridge" not in _all_imports(f)


@pytest.mark.parametrize("path", _files("explore_seg") + _files("sim_bridge"),
                         ids=lambda p: str(p.relative_to(ROOT)))
def test_files_stay_small(path):
    n = len(path.read_text().splitlines())
    assert n <= MAX_LINES, f"{path.relative_to(ROOT)} has {n} lines (at most {MAX_LINES})"


def _used_names(path: Path) -> set[str]:
    tree = ast.parse(path.read_text(), filename=str(path))
    names: set[str] = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Name):
            names.add(node.id)
        elif isinstance(node, ast.Attribute):
            names.add(node.attr)
        elif isinstance(node, ast.ImportFrom):
            names.update(a.name for a in node.names)
    return names


@pytest.mark.parametrize("path", [p for pkg in PROJECT_PACKAGES + ("scripts",)
                                  for p in _files(pkg)
                                  if not str(p.relative_to(ROOT)).startswith(WIRING_HOMES)],
                         ids=lambda p: str(p.relative_to(ROOT)))
def test_decision_loop_is_wired_only_by_the_core_explorer(path):
    """Frontiers -> distances -> goal manager are wired once, in core/explorer.py: the
    selector node, the lock step and the benchmarks call Explorer.step."""
    used = _used_names(path) & WIRING_NAMES
    assert not used, (f"{path.relative_to(ROOT)} wires {sorted(used)} by hand: call "
                      "explore_seg.core.explorer.Explorer.step instead")


@pytest.mark.parametrize("path", _files("explore_seg") + _files("sim_bridge"),
                         ids=lambda p: str(p.relative_to(ROOT)))
def test_package_and_simulator_never_import_bench_or_scripts(path):
    """bench/ and scripts/ sit on top: they import the package and the simulator, never
    the reverse (function-level imports included)."""
    for mod in _all_imports(path):
        assert mod.split(".")[0] not in ("bench", "scripts"), f"{path} imports {mod}"


# ------------------------------------------------------------------ function size and arity

#: Longest function body, in lines from ``def`` to its end without the docstring.
MAX_FUNCTION_LINES = 80
#: Most parameters of a function (self/cls not counted; keyword-only, *args, **kwargs are).
MAX_FUNCTION_PARAMS = 8
#: Functions allowed over a limit, as "path::qualified name" (none: keep it that way).
LONG_FUNCTION_ALLOWLIST: set[str] = set()


def _functions(tree: ast.AST, prefix: str = ""):
    """(qualified name, node) of every function in ``tree``, nested ones included."""
    for node in ast.iter_child_nodes(tree):
        if isinstance(node, ast.ClassDef):
            yield from _functions(node, f"{prefix}{node.name}.")
        elif isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
            yield f"{prefix}{node.name}", node
            yield from _functions(node, f"{prefix}{node.name}.")
        else:
            yield from _functions(node, prefix)


def _body_lines(fn: ast.FunctionDef | ast.AsyncFunctionDef) -> int:
    """Lines from the ``def`` line to the function's end, less its docstring's."""
    first = fn.body[0]
    doc = (first.end_lineno - first.lineno + 1
           if isinstance(first, ast.Expr) and isinstance(first.value, ast.Constant)
           and isinstance(first.value.value, str) else 0)
    return fn.end_lineno - fn.lineno + 1 - doc


def _param_count(fn: ast.FunctionDef | ast.AsyncFunctionDef) -> int:
    a = fn.args
    names = [x.arg for x in a.posonlyargs + a.args + a.kwonlyargs]
    n = len(names) + (a.vararg is not None) + (a.kwarg is not None)
    return n - 1 if names and names[0] in ("self", "cls") else n


def _oversized(paths: list[Path]) -> dict[str, str]:
    """"path::name" -> what is over the limits, for every function over one."""
    out = {}
    for path in paths:
        rel = path.relative_to(ROOT) if path.is_relative_to(ROOT) else path
        for name, fn in _functions(ast.parse(path.read_text(), filename=str(path))):
            lines, params = _body_lines(fn), _param_count(fn)
            over = ([f"{lines} lines"] if lines > MAX_FUNCTION_LINES else []) + \
                ([f"{params} parameters"] if params > MAX_FUNCTION_PARAMS else [])
            if over:
                out[f"{rel}::{name}"] = ", ".join(over)
    return out


def test_functions_stay_short_and_take_few_parameters():
    found = _oversized(_files("explore_seg") + _files("sim_bridge"))
    new = {k: v for k, v in found.items() if k not in LONG_FUNCTION_ALLOWLIST}
    assert not new, ("functions over the limits (split them along their jobs; group "
                     "parameters in a small frozen dataclass): "
                     + "; ".join(f"{k} ({v})" for k, v in sorted(new.items())))
    fixed = LONG_FUNCTION_ALLOWLIST - set(found)
    assert not fixed, ("remove from LONG_FUNCTION_ALLOWLIST (within the limits now): "
                       f"{sorted(fixed)}")


def test_the_size_check_counts_lines_without_the_docstring_and_parameters_without_self(
        tmp_path):
    body = "\n".join(f"    x{i} = {i}" for i in range(MAX_FUNCTION_LINES - 1))
    doc = '    """Doc\n\n    more doc.\n    """\n'
    f = tmp_path / "m.py"
    f.write_text(f"def fits():\n{doc}{body}\n\n\n"
                 f"def too_long():\n{doc}{body}\n    x = 0\n\n\n"
                 "def star(a, b, c, d, e, f, g, h, *args):\n    pass\n\n\n"
                 "class C:\n    def m(self, a, b, c, d, e, f, g, *args):\n        pass\n\n"
                 "    def n(self, a, b, c, d, e, f, g, *, h, **kw):\n"
                 "        def inner(p, q, r, s, t, u, v, w, y):\n            pass\n")
    assert _oversized([f]) == {f"{f}::too_long": f"{MAX_FUNCTION_LINES + 1} lines",
                               f"{f}::star": "9 parameters",
                               f"{f}::C.n": "9 parameters",
                               f"{f}::C.n.inner": "9 parameters"}
