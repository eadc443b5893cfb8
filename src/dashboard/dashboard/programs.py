"""The taught programs in the programs folder: list them, delete one (names only: nothing
outside the folder can be named)."""

import os
from dataclasses import dataclass

from motion_commander.program import ProgramError, load_program, program_path  # noqa: F401 (re-exported: the page names files by it)


@dataclass
class ProgramInfo:
    """One program file as the page lists it."""

    name: str  # file name without .yaml
    modified: float  # s since the epoch
    robot: str = ""
    waypoints: int = 0
    error: str = ""  # why it cannot be read (then it can only be deleted)


def list_programs(folder: str) -> list[ProgramInfo]:
    """Every *.yaml program in ``folder``, newest first; unreadable ones carry their error."""
    if not os.path.isdir(folder):
        return []
    found = []
    for entry in os.scandir(folder):
        if not entry.is_file() or not entry.name.endswith(".yaml"):
            continue
        info = ProgramInfo(entry.name[: -len(".yaml")], entry.stat().st_mtime)
        try:
            program = load_program(entry.path)
            info.robot, info.waypoints = program.robot, len(program.waypoints)
        except ProgramError as exc:
            info.error = str(exc)
        found.append(info)
    return sorted(found, key=lambda p: (-p.modified, p.name))


def delete_program(folder: str, name: str) -> str | None:
    """Remove program ``name``; return None when done, else why not."""
    try:
        path = program_path(folder, name)
    except ValueError as exc:
        return str(exc)
    try:
        os.remove(path)
    except FileNotFoundError:
        return f"{name}: no such program in {folder}"
    except OSError as exc:
        return f"{name}: {exc.strerror}"
    return None
