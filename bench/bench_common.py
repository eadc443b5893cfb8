"""Shared by the benchmark scripts: where results go and how they are written."""

import json
import os
import sys

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), ".."))
RESULTS = os.path.join(ROOT, "bench", "results")
sys.path.insert(0, os.path.join(ROOT, "src", "motion_common"))

from motion_common.atomic_file import write_atomic  # noqa: E402


def write_results(name: str, results: dict, show: bool = True) -> str:
    """Write ``results`` to bench/results/NAME.json, print them, and return the path."""
    # Atomically: an interrupted run leaves the last good results as they were.
    path = write_atomic(os.path.join(RESULTS, f"{name}.json"), json.dumps(results, indent=2) + "\n")
    if show:
        print(json.dumps(results, indent=2))
    print(f"written to {path}")
    return path
