"""The explorer nodes' parameters as one object, read from ``config/explorer.yaml``.

The lock-step runs (:mod:`sim_bridge.lockstep`) configure the core with the same values
the ROS nodes get from the same file.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from pathlib import Path

from explore_seg.core.frontiers import FrontierParams
from explore_seg.core.objects import ObjectCostmapNodeParams
from explore_seg.core.param_files import dataclass_from_values, load_node_params
from explore_seg.core.rrt import RrtParams
from explore_seg.core.scan_overlay import ScanOverlayParams
from explore_seg.core.segmentation import SegmentationNodeParams
from explore_seg.core.selection import SelectorNodeParams


@dataclass(frozen=True)
class ExplorerParams:
    """The explorer nodes' parameters (what ``config/explorer.yaml`` sets)."""

    frontier: FrontierParams = field(default_factory=FrontierParams)
    selection: SelectorNodeParams = field(default_factory=SelectorNodeParams)
    segmentation: SegmentationNodeParams = field(default_factory=SegmentationNodeParams)
    objects: ObjectCostmapNodeParams = field(default_factory=ObjectCostmapNodeParams)
    rrt: RrtParams = field(default_factory=RrtParams)
    overlay: ScanOverlayParams = field(default_factory=ScanOverlayParams)


#: ExplorerParams field -> (node whose section sets it, parameter prefix). The frontier
#: parameters are the target selector's ``frontier.*`` (from ``/**`` in explorer.yaml).
_SECTIONS = {"frontier": ("target_selector", "frontier."),
             "selection": ("target_selector", ""),
             "segmentation": ("segmentation", ""),
             "objects": ("object_costmap", ""),
             "rrt": ("target_selector", "rrt."),
             "overlay": ("target_selector", "scan_overlay.")}


def default_explorer_params_file() -> Path | None:
    """``config/explorer.yaml`` of the source tree, when present."""
    cand = Path(__file__).resolve().parents[1] / "config" / "explorer.yaml"
    return cand if cand.is_file() else None


def load_explorer_params(path: str | Path | None = None) -> ExplorerParams:
    """Explorer parameters from a ROS 2 parameter YAML (``/**`` merged first, then each
    node's section, as rcl does); fields the file does not set keep the dataclass defaults
    and parameters of other bindings (``detector.*``, ``use_sim_time``) are ignored.

    Parameters
    ----------
    path : str or Path, optional
        Default :func:`default_explorer_params_file`; without a file the defaults.

    Raises
    ------
    ValueError
        When the file is malformed or a value is rejected by its dataclass.
    """
    p = Path(path) if path else default_explorer_params_file()
    out = ExplorerParams()
    if p is None:
        return out
    for attr, (node, prefix) in _SECTIONS.items():
        values = load_node_params(p, node)
        try:
            out = replace(out, **{attr: dataclass_from_values(getattr(out, attr), values,
                                                             prefix)})
        except ValueError as err:
            raise ValueError(f"{p}: {node}: {err}") from err
    return out
