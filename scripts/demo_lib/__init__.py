"""The parts of ``scripts/demo.py`` (the headless demo), one concern each:

* :mod:`~scripts.demo_lib.config`: :class:`DemoConfig`, :class:`DemoError`;
* :mod:`~scripts.demo_lib.processes`: the children's command lines, a started child;
* :mod:`~scripts.demo_lib.monitor`: the monitor node and its progress line;
* :mod:`~scripts.demo_lib.run`: one run (:func:`run_demo`) and its stop flag;
* :mod:`~scripts.demo_lib.outputs`: the pictures, animation and metrics written.
"""

from scripts.demo_lib.config import GIF_SIDE_PX, ROOT, DemoConfig, DemoError
from scripts.demo_lib.monitor import Monitor, boxes_from_markers, metrics_from_diagnostics, \
    nav_outcomes, progress_line
from scripts.demo_lib.outputs import write_outputs
from scripts.demo_lib.processes import Child, explorer_command, ros_value, sim_command
from scripts.demo_lib.run import STOP, child_env, run_demo, start_monitor, stop_monitor, \
    wait_for_explorer

__all__ = ["GIF_SIDE_PX", "ROOT", "STOP", "Child", "DemoConfig", "DemoError", "Monitor",
           "boxes_from_markers", "child_env", "start_monitor", "stop_monitor", "explorer_command", "metrics_from_diagnostics",
           "nav_outcomes", "progress_line", "ros_value", "run_demo", "sim_command", "wait_for_explorer",
           "write_outputs"]
