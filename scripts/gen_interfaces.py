"""Collects every node's declaration (each package's ``interfaces.py``) and writes
docs/interfaces.md from them. ``scripts/gen_interfaces`` runs it; the unit tests import
``all_interfaces`` and fail when the file is stale.

Usage: scripts/gen_interfaces [--check]   (--check: exit 1 when docs/interfaces.md is stale)
"""

import importlib
import os
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
DOC = os.path.join(ROOT, "docs", "interfaces.md")
# Lowest layer first, as docs/interfaces.md lists them.
PACKAGES = ("motion_sensor", "hw_interface", "motion_commander", "motion_apps", "kitting", "dashboard")


def all_interfaces():
    """Every declared node of the framework."""
    nodes = []
    for package in PACKAGES:
        nodes += importlib.import_module(f"{package}.interfaces").all_interfaces()
    return nodes


def render() -> str:
    """The text docs/interfaces.md must hold."""
    from motion_common.interface import interfaces_markdown

    text = interfaces_markdown(all_interfaces())
    # Defaults that are paths in this clone are shown from the project root, so the file is
    # the same in every clone (catkin_ws/src/PKG is a link to src/PKG).
    for root in {ROOT, os.path.realpath(ROOT)}:
        text = text.replace(os.path.join(root, "catkin_ws", "src") + os.sep, "<project>/src/")
        text = text.replace(root + os.sep, "<project>/")
    return text


def main(argv) -> int:
    text = render()
    if "--check" in argv:
        with open(DOC, encoding="utf-8") as stream:
            stale = stream.read() != text
        if stale:
            print(f"{DOC} is stale: run scripts/gen_interfaces", file=sys.stderr)
        return 1 if stale else 0
    from motion_common.atomic_file import write_atomic

    write_atomic(DOC, text)
    print(f"wrote {DOC} ({len(all_interfaces())} nodes)")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
