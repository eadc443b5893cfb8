"""The one declaration of a node: its parameters, and the topics and services it uses.

Every node of the framework is declared once, as a ``NodeInterface`` in its package's
``interfaces.py``: the ``ParamSchema`` of its private parameters (default, unit, range,
doc) and every topic it publishes or subscribes and every service it serves or calls, with
the ROS type and a line of documentation. From that one object come:

- the checked, typed parameters the node runs with (``params.validate``; the Python API
  builds its config objects from the same schema, so both get the same defaults);
- the publishers, subscribers and services of the node (``motion_common.ros_interface``
  looks each name up here, so a node cannot use a name it does not declare);
- ``docs/interfaces.md`` (``interfaces_markdown``; a test fails when the file is stale);
- the check that a running node advertises what it declares (the rostest
  ``interface_check``).

Names are relative (``joint_states``, ``motion_sensor/raw_hand``) or private
(``~finished``), never absolute: a launch file puts a whole stack under a namespace
(``left/``, ``right/``) and remaps what it must. No ROS import.
"""

from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field

from .params import ParamSchema

__all__ = ["Topic", "Service", "NodeInterface", "interfaces_markdown", "resolve", "graph_mismatches", "GRAPH_IGNORED"]


@dataclass(frozen=True)
class Topic:
    """One topic a node publishes or subscribes.

    ``name`` is relative or private; ``type`` is the ROS type (``pkg/Msg``); ``latched``
    for a latched publisher; ``optional`` when the node uses it only in some
    configurations (e.g. a device's clutch output), so a running node may lack it.
    """

    name: str
    type: str
    doc: str = ""
    latched: bool = False
    optional: bool = False

    def __post_init__(self):
        if self.name.startswith("/"):
            raise ValueError(f"topic {self.name!r}: declare relative or private names; launch files remap")
        if "/" not in self.type:
            raise ValueError(f"topic {self.name!r}: type {self.type!r} must be 'package/Message'")


@dataclass(frozen=True)
class Service:
    """One service a node serves or calls (``type`` is ``pkg/Srv``)."""

    name: str
    type: str
    doc: str = ""
    optional: bool = False

    def __post_init__(self):
        if self.name.startswith("/"):
            raise ValueError(f"service {self.name!r}: declare relative or private names; launch files remap")
        if "/" not in self.type:
            raise ValueError(f"service {self.name!r}: type {self.type!r} must be 'package/Service'")


@dataclass(frozen=True)
class NodeInterface:
    """Everything a node exposes: parameters, topics and services (see the module doc)."""

    package: str
    node: str
    doc: str
    params: ParamSchema = field(default_factory=lambda: ParamSchema([]))
    publishes: tuple[Topic, ...] = ()
    subscribes: tuple[Topic, ...] = ()
    serves: tuple[Service, ...] = ()
    calls: tuple[Service, ...] = ()

    def __post_init__(self):
        for kind, entries in (
            ("publishes", self.publishes),
            ("subscribes", self.subscribes),
            ("serves", self.serves),
            ("calls", self.calls),
        ):
            names = [entry.name for entry in entries]
            twice = sorted({name for name in names if names.count(name) > 1})
            if twice:
                raise ValueError(f"{self.package}/{self.node}: {kind} declares {twice} twice")

    @property
    def key(self) -> str:
        """``package/node``, the name the docs and the checks use."""
        return f"{self.package}/{self.node}"

    def _find(self, entries: Sequence, name: str, kind: str):
        for entry in entries:
            if entry.name == name:
                return entry
        declared = [entry.name for entry in entries]
        raise KeyError(f"{self.key} does not declare that it {kind} {name!r}; declared: {declared}")

    def published(self, name: str) -> Topic:
        """The declared published topic ``name``; KeyError if the node does not declare it."""
        return self._find(self.publishes, name, "publishes")

    def subscribed(self, name: str) -> Topic:
        """The declared subscribed topic ``name``."""
        return self._find(self.subscribes, name, "subscribes")

    def served(self, name: str) -> Service:
        """The declared served service ``name``."""
        return self._find(self.serves, name, "serves")

    def called(self, name: str) -> Service:
        """The declared called service ``name``."""
        return self._find(self.calls, name, "calls")

    def markdown(self, root: str = "") -> str:
        """This node's section of docs/interfaces.md; a default path under ``root`` is
        shown as ``<project>/...`` so the text is the same in every clone."""
        lines = [f"### `{self.node}` ({self.package})", "", self.doc.strip(), ""]
        for title, entries in (
            ("Publishes", self.publishes),
            ("Subscribes", self.subscribes),
            ("Serves", self.serves),
            ("Calls", self.calls),
        ):
            if not entries:
                continue
            lines += [f"{title}:", "", "| name | type | |", "|---|---|---|"]
            for entry in entries:
                notes = [
                    text
                    for text, on in (("latched", getattr(entry, "latched", False)), ("optional", entry.optional))
                    if on
                ]
                doc = entry.doc + (f" ({', '.join(notes)})" if notes else "")
                lines.append(f"| `{entry.name}` | `{entry.type}` | {_cell(doc)} |")
            lines.append("")
        if self.params.params:
            lines += [
                "Parameters (private, `~name`):",
                "",
                "| name | default | unit | range | |",
                "|---|---|---|---|---|",
            ]
            for param in self.params.params.values():
                default = repr(param.default).replace(root, "<project>") if root else repr(param.default)
                lines.append(
                    f"| `{param.name}` | `{default}` | {param.unit} | {_cell(_range(param))} | {_cell(param.doc)} |"
                )
            lines.append("")
        return "\n".join(lines)


def _cell(text: str) -> str:
    return str(text).replace("|", "\\|").replace("\n", " ")


def _range(param) -> str:
    if param.choices:
        return " \\| ".join(param.choices)
    if param.low is None and param.high is None:
        return ""
    low = "-inf" if param.low is None else f"{param.low:g}"
    high = "inf" if param.high is None else f"{param.high:g}"
    return f"{'(' if param.low_open else '['}{low}, {high}]"


def resolve(name: str, namespace: str, node_name: str) -> str:
    """The graph name ``name`` resolves to for a node ``node_name`` (fully qualified) in
    ``namespace``, as rospy resolves it (no remapping)."""
    if name.startswith("/"):
        return name
    if name.startswith("~"):
        return node_name.rstrip("/") + "/" + name[1:].lstrip("/")
    return namespace.rstrip("/") + "/" + name


def interfaces_markdown(interfaces: Iterable[NodeInterface], title: str = "Node interfaces", root: str = "") -> str:
    """docs/interfaces.md: every node, grouped by package, generated from the declarations."""
    by_package: dict[str, list[NodeInterface]] = {}
    for interface in interfaces:
        by_package.setdefault(interface.package, []).append(interface)
    lines = [
        f"# {title}",
        "",
        "Generated from each package's `interfaces.py` by `scripts/gen_interfaces`; do not edit by hand "
        "(`tests/unit` fails when this file is stale). Names are relative: a session launched under a "
        "namespace (e.g. `left/`) prefixes every one of them; `~name` is private to the node.",
        "",
    ]
    for package in sorted(by_package):
        lines += [f"## {package}", ""]
        for interface in sorted(by_package[package], key=lambda i: i.node):
            lines += [interface.markdown(root), ""]
    return "\n".join(lines).rstrip() + "\n"


#: Graph names a running node has that are not its own interface: /rosout, tf (global by
#: design: frames, not topic names, tell robots apart), and rospy's and tf2's own services.
GRAPH_IGNORED = ("/rosout", "/tf", "/tf_static")
# Services every rospy node (its logger levels) or a tf2 listener (its frame list) serves.
_INFRASTRUCTURE_SERVICES = ("/get_loggers", "/set_logger_level", "/tf2_frames")


def graph_mismatches(interface: NodeInterface, node_name: str, system_state, remaps=None) -> list[str]:
    """What a running node ``node_name`` (fully qualified, e.g. ``/left/sequencer``) does
    differently from its declaration, given the master's ``getSystemState()`` answer
    (publishers, subscribers, services: lists of [name, [node, ...]]) and the launch
    file's ``remaps`` of that node ({declared name: target}). Empty when they agree: every
    topic and service it has is declared, and every declared one that is not optional is
    there. Service clients are not visible to the master and are not compared."""
    remaps = remaps or {}
    namespace = node_name.rsplit("/", 1)[0] or "/"
    problems = []
    for kind, state, entries in (
        ("publishes", system_state[0], interface.publishes),
        ("subscribes", system_state[1], interface.subscribes),
        ("serves", system_state[2], interface.serves),
    ):
        actual = {
            name
            for name, nodes in state
            if node_name in nodes and name not in GRAPH_IGNORED and not name.endswith(_INFRASTRUCTURE_SERVICES)
        }
        expected = {resolve(remaps.get(entry.name, entry.name), namespace, node_name): entry for entry in entries}
        undeclared = sorted(actual - set(expected))
        missing = sorted(name for name, entry in expected.items() if not entry.optional and name not in actual)
        if undeclared:
            problems.append(f"{node_name} {kind} {undeclared}, which {interface.key} does not declare")
        if missing:
            problems.append(f"{node_name} does not {kind[:-1]} {missing}, which {interface.key} declares")
    return problems
