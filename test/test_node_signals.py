"""Stopping a node executable with SIGINT / SIGTERM (explore_seg/node_util.py ``run``).

``run`` turns rclpy's signal handler off and stops on a flag, so the teardown runs in order
on the main thread; a second SIGINT interrupts at once.
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import pytest

from explore_seg.node_util import StopFlag

ROOT = Path(__file__).resolve().parents[1]


def test_stop_flag_catches_sigint_then_restores_the_default():
    before = signal.getsignal(signal.SIGINT)
    flag = StopFlag()
    try:
        os.kill(os.getpid(), signal.SIGINT)
        time.sleep(0.05)
        assert flag.is_set()
        # the first SIGINT put the default handler back: a second one interrupts
        with pytest.raises(KeyboardInterrupt):
            os.kill(os.getpid(), signal.SIGINT)
            time.sleep(0.5)
    finally:
        flag.restore()
    assert signal.getsignal(signal.SIGINT) is before


def test_stop_flag_catches_sigterm():
    flag = StopFlag()
    try:
        os.kill(os.getpid(), signal.SIGTERM)
        time.sleep(0.05)
        assert flag.is_set()
    finally:
        flag.restore()


_CHILD = textwrap.dedent("""
    import sys
    from rclpy.node import Node
    from explore_seg.node_util import run

    class Ticker(Node):
        def __init__(self):
            super().__init__("ticker")
            self.create_timer(0.01, lambda: None)

        def destroy_node(self):
            print("destroyed", flush=True)
            return super().destroy_node()

    sys.exit(run([Ticker, Ticker], num_threads=int(sys.argv[1])))
""")


@pytest.mark.parametrize("threads", [1, 2])
@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM])
def test_run_exits_cleanly_on_a_stop_signal(sig, threads):
    env = dict(os.environ, ROS_AUTOMATIC_DISCOVERY_RANGE="LOCALHOST",
               ROS_DOMAIN_ID=os.environ.get("ROS_DOMAIN_ID", "77"),
               PYTHONPATH=str(ROOT) + os.pathsep + os.environ.get("PYTHONPATH", ""))
    proc = subprocess.Popen([sys.executable, "-c", _CHILD, str(threads)], env=env,
                            stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    try:
        deadline = time.monotonic() + 60
        lines = []
        while time.monotonic() < deadline:
            line = proc.stdout.readline()
            lines.append(line)
            if "Ctrl-C to stop" in line or not line:
                break
        assert any("Ctrl-C to stop" in ln for ln in lines), "".join(lines)
        time.sleep(0.3)
        proc.send_signal(sig)
        out, _ = proc.communicate(timeout=15)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    assert proc.returncode == 0, "".join(lines) + out
    assert out.count("destroyed") == 2, out
