"""Shared by the benchmark scripts: where results go and how they are written."""

import json
import os

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), ".."))
RESULTS = os.path.join(ROOT, "bench", "results")


def write_results(name: str, results: dict, show: bool = True) -> str:
    """Write ``results`` to bench/results/NAME.json, print them, and return the path."""
    os.makedirs(RESULTS, exist_ok=True)
    path = os.path.join(RESULTS, f"{name}.json")
    with open(path, "w", encoding="utf-8") as fh:
        json.dump(results, fh, indent=2)
    if show:
        print(json.dumps(results, indent=2))
    print(f"written to {path}")
    return path
