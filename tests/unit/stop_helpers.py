"""Shared by the STOP tests: run a blocking move in a thread and stop it from another. The
code is tests/nodes/stop_trial.py, which the rostest STOP check and bench/stop_bench.py
run too."""

import os
import sys

sys.path.insert(0, os.path.normpath(os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "nodes")))
from stop_trial import MoveInThread, stop_during, wait_for  # noqa: E402

__all__ = ["MoveInThread", "stop_during", "wait_for"]
