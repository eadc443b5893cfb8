"""The code keeps to the project's ruff configuration (pyproject.toml, [tool.ruff]):
`ruff check` and `ruff format --check` on the whole project report nothing.

ruff is pinned in requirements-dev.txt and installed into .venv by `scripts/setup --test`
(scripts/test runs it first); without it in .venv the tests skip and say so. ruff runs from
the project root so it finds pyproject.toml, and writes no cache into the tree.
"""

import os
import subprocess

import pytest


def _project_root() -> str:
    """The folder holding pyproject.toml above this file (the file may move between folders)."""
    here = os.path.dirname(os.path.abspath(__file__))
    while not os.path.isfile(os.path.join(here, "pyproject.toml")):
        parent = os.path.dirname(here)
        if parent == here:
            raise RuntimeError(f"no pyproject.toml above {__file__}")
        here = parent
    return here


ROOT = _project_root()
RUFF = os.path.join(ROOT, ".venv", "bin", "ruff")


def run_ruff(*args: str) -> subprocess.CompletedProcess:
    if not os.access(RUFF, os.X_OK):
        pytest.skip(f"ruff is not installed in the venv ({RUFF}); `scripts/setup --test` installs requirements-dev.txt")
    return subprocess.run([RUFF, *args, "--no-cache", "."], cwd=ROOT, capture_output=True, text=True, timeout=300)


def report(what: str, result: subprocess.CompletedProcess, hint: str) -> str:
    return f"`{what}` exited {result.returncode} ({hint}):\n{result.stdout}{result.stderr}"


def test_ruff_check_reports_nothing():
    result = run_ruff("check", "--output-format", "concise")
    if result.returncode != 0:
        hint = "`.venv/bin/ruff check --fix` repairs the [*] ones"
        pytest.fail(report("ruff check", result, hint), pytrace=False)


def test_ruff_format_would_change_nothing():
    result = run_ruff("format", "--check", "--output-format", "concise")
    if result.returncode != 0:
        hint = "`.venv/bin/ruff format --diff` shows the changes, `.venv/bin/ruff format` makes them"
        pytest.fail(report("ruff format --check", result, hint), pytrace=False)
