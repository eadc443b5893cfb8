"""The arguments a launch file accepts, and ``name:=value`` command lines checked against them.

roslaunch ignores an argument that no ``<arg>`` declares, so ``speed_ration:=0.5`` runs at
the default ratio and nobody is told. The session scripts check every ``name:=value`` here
first and refuse an unknown name with the closest declared ones. Plain Python: the launch
XML is read directly, no roslaunch and no master.

A launch file accepts its own ``<arg>`` elements that have no fixed ``value``, plus those of
every file it includes with ``pass_all_args="true"`` (which receives all of its parent's
arguments), recursively.
"""

import difflib
import os
import re
import xml.etree.ElementTree as ET
from dataclasses import dataclass

from .errors import ParameterError

__all__ = ["LaunchArg", "declared_args", "parse_assignments", "unknown_args", "suggestion"]

_ASSIGNMENT = re.compile(r"^([A-Za-z_][A-Za-z0-9_]*):=(.*)$", re.DOTALL)


@dataclass(frozen=True)
class LaunchArg:
    """One settable argument: its name, default (None when required), doc and the file
    that declares it."""

    name: str
    default: str | None
    doc: str
    file: str


def _included_file(path: str, include: ET.Element) -> str | None:
    """The file an ``<include>`` names, when it is relative to the including file
    (``$(dirname)``); other substitutions (``$(find ...)``) are not followed."""
    target = include.get("file", "")
    if "$(dirname)" not in target or "$(" in target.replace("$(dirname)", ""):
        return None
    return os.path.normpath(target.replace("$(dirname)", os.path.dirname(os.path.abspath(path))))


def declared_args(path: str) -> dict[str, LaunchArg]:
    """Every argument ``path`` accepts from the command line, by name.

    Raises ParameterError when the file is missing or is not XML."""
    return _declared(os.path.abspath(path), set())


def _declared(path: str, seen: set) -> dict[str, LaunchArg]:
    if path in seen:
        return {}
    seen.add(path)
    try:
        root = ET.parse(path).getroot()
    except FileNotFoundError:
        raise ParameterError(f"launch file {path} does not exist") from None
    except ET.ParseError as exc:
        raise ParameterError(f"launch file {path} is not valid XML: {exc}") from None
    args: dict[str, LaunchArg] = {}
    for element in root:
        if element.tag == "arg" and element.get("value") is None and element.get("name"):
            name = element.get("name")
            args[name] = LaunchArg(name, element.get("default"), element.get("doc", ""), path)
    for include in root.iter("include"):
        if include.get("pass_all_args", "false").lower() != "true":
            continue
        target = _included_file(path, include)
        if target and os.path.exists(target):
            for name, arg in _declared(target, seen).items():
                args.setdefault(name, arg)
    return args


def parse_assignments(argv) -> dict[str, str]:
    """``name:=value`` words as a dict; anything else raises ParameterError saying why."""
    values: dict[str, str] = {}
    for word in argv:
        match = _ASSIGNMENT.match(word)
        if not match:
            hint = " (write name:=value)" if "=" in word and ":=" not in word else ""
            raise ParameterError(f"argument {word!r} is not of the form name:=value{hint}")
        name, value = match.groups()
        if name in values and values[name] != value:
            raise ParameterError(f"argument {name!r} given twice: {values[name]!r} and {value!r}")
        values[name] = value
    return values


def suggestion(name: str, known) -> str:
    """`` (did you mean 'x'?)`` for the closest known names, or an empty string."""
    close = difflib.get_close_matches(name, sorted(known), n=2, cutoff=0.6)
    if not close:
        return ""
    return " (did you mean " + " or ".join(repr(c) for c in close) + "?)"


def unknown_args(values: dict, declared: dict) -> list[str]:
    """One message per name in ``values`` that ``declared`` does not know."""
    return [f"unknown argument {name!r}{suggestion(name, declared)}" for name in sorted(values) if name not in declared]
