"""The one parameter validator of every node: a schema of typed, ranged, unit-carrying
parameters, checked once at start-up (as moveit_servo checks its YAML).

A node declares its parameters as a ``ParamSchema`` of ``Param`` entries; ``validate``
takes the dict the node was given (its private ROS parameters, or a YAML file's content)
and returns a complete dict with defaults filled in. Anything wrong stops the node with a
``ParameterError`` that names the file, the key and what is allowed; an unknown key is an
error too, listing the valid keys, so a misspelt safety setting never silently leaves its
default in force. No ROS import: ``motion_common.ros_params`` reads the parameter server.
"""

import copy
import dataclasses
import math
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from typing import Any, Optional

from .errors import ParameterError

_KINDS = (bool, int, float, str, list, dict)


@dataclass(frozen=True)
class Param:
    """One parameter: name, default, unit and the values it accepts.

    ``kind`` is taken from the default unless given (needed when the default is None).
    Numbers (and the items of a numeric list) must lie in [``low``, ``high``]; with
    ``low_open`` the lower bound is excluded (a strictly positive value). ``choices``
    restricts a string; ``length`` fixes a list's length; ``item_kind`` is the type of a
    list's items (float by default); ``schema`` checks a dict's keys; ``nullable`` accepts
    None as "not set".
    """

    name: str
    default: Any
    unit: str = ""
    doc: str = ""
    low: float | None = None
    high: float | None = None
    low_open: bool = False
    choices: tuple[str, ...] | None = None
    length: int | None = None
    item_kind: type = float
    kind: type | None = None
    schema: Optional["ParamSchema"] = None
    nullable: bool = False

    @property
    def value_kind(self) -> type:
        """The Python type the value must have."""
        if self.kind is not None:
            return self.kind
        for kind in _KINDS:  # bool before int: a bool is an int in Python
            if isinstance(self.default, kind):
                return kind
        raise TypeError(f"parameter {self.name!r}: give kind= for default {self.default!r}")

    def describe(self) -> str:
        """One line for --help and error messages: name, unit, range, default."""
        parts = [self.name]
        if self.unit:
            parts.append(f"[{self.unit}]")
        if self.choices:
            parts.append("one of " + "|".join(self.choices))
        elif self.low is not None or self.high is not None:
            low = "-inf" if self.low is None else f"{self.low:g}"
            high = "inf" if self.high is None else f"{self.high:g}"
            parts.append(f"{'(' if self.low_open else '['}{low}, {high}]")
        parts.append(f"default {self.default!r}")
        text = " ".join(parts)
        return f"{text}: {self.doc}" if self.doc else text

    def check(self, value, source: str):
        """The value converted to its kind; raise ParameterError naming source and key."""
        where = f"{source}: parameter '{self.name}'" + (f" ({self.unit})" if self.unit else "")
        if value is None and (self.nullable or self.default is None):
            return None
        kind = self.value_kind
        if kind is bool:
            if not isinstance(value, bool):
                raise ParameterError(f"{where} must be true or false, got {value!r}")
            return value
        if kind in (int, float):
            return self._check_number(value, kind, where)
        if kind is str:
            if not isinstance(value, str):
                raise ParameterError(f"{where} must be a string, got {value!r}")
            if self.choices and value not in self.choices:
                raise ParameterError(f"{where} must be one of {list(self.choices)}, got {value!r}")
            return value
        if kind is list:
            return self._check_list(value, where)
        if kind is dict:
            if not isinstance(value, dict):
                raise ParameterError(f"{where} must be a mapping, got {value!r}")
            if self.schema is None:
                return dict(value)
            return self.schema.validate(value, f"{source}: '{self.name}'")
        raise ParameterError(f"{where}: unsupported kind {kind}")

    def _check_number(self, value, kind, where):
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise ParameterError(f"{where} must be a number, got {value!r}")
        if kind is int and not float(value).is_integer():
            raise ParameterError(f"{where} must be a whole number, got {value!r}")
        if not math.isfinite(value):
            raise ParameterError(f"{where} must be finite, got {value!r}")
        self._check_range(value, where)
        return int(value) if kind is int else float(value)

    def _check_range(self, value, where):
        too_low = self.low is not None and (value <= self.low if self.low_open else value < self.low)
        too_high = self.high is not None and value > self.high
        if too_low or too_high:
            low = "-inf" if self.low is None else f"{self.low:g}"
            high = "inf" if self.high is None else f"{self.high:g}"
            bracket = "(" if self.low_open else "["
            raise ParameterError(f"{where} must be in {bracket}{low}, {high}], got {value!r}")

    def _check_list(self, value, where):
        if not isinstance(value, (list, tuple)):
            raise ParameterError(f"{where} must be a list, got {value!r}")
        if self.length is not None and len(value) != self.length:
            raise ParameterError(f"{where} must have {self.length} values, got {len(value)}: {value!r}")
        if self.item_kind in (int, float):
            items = []
            for item in value:
                if isinstance(item, bool) or not isinstance(item, (int, float)) or not math.isfinite(item):
                    raise ParameterError(f"{where} must hold finite numbers, got {value!r}")
                self._check_range(item, where)
                items.append(self.item_kind(item))
            return items
        if self.item_kind is dict:
            if not all(isinstance(item, dict) for item in value):
                raise ParameterError(f"{where} must be a list of mappings, got {value!r}")
            return [dict(item) for item in value]
        if not all(isinstance(item, self.item_kind) for item in value):
            raise ParameterError(f"{where} must hold {self.item_kind.__name__} values, got {value!r}")
        return list(value)


class ParamSchema:
    """The parameters of one node (or one nested mapping), checked together.

    ``ignore`` names keys that may be present but are not this schema's (e.g. a launch
    file's bookkeeping); they are dropped from the result.
    """

    def __init__(self, params: Sequence[Param], ignore: Iterable[str] = ()):
        self.params: dict[str, Param] = {}
        for param in params:
            if param.name in self.params:
                raise ValueError(f"parameter {param.name!r} declared twice")
            param.value_kind  # noqa: B018 - fails now, at import, on a schema bug
            self.params[param.name] = param
        self.ignore = frozenset(ignore)

    def defaults(self) -> dict[str, Any]:
        """Every parameter at its default."""
        return {name: param.default for name, param in self.params.items()}

    def validate(self, values: dict | None, source: str) -> dict[str, Any]:
        """Checked values with defaults filled in; raise ParameterError on anything wrong."""
        values = {} if values is None else values
        if not isinstance(values, dict):
            raise ParameterError(f"{source}: expected a mapping of parameters, got {values!r}")
        unknown = sorted(set(values) - set(self.params) - self.ignore)
        if unknown:
            raise ParameterError(
                f"{source}: unknown parameter '{unknown[0]}'"
                + (f" (and {unknown[1:]})" if len(unknown) > 1 else "")
                + f"; valid keys: {sorted(self.params)}"
            )
        result = self.defaults()
        for name, value in values.items():
            if name in self.params:
                result[name] = self.params[name].check(value, source)
        return result

    def default(self, name: str):
        """A fresh copy of parameter ``name``'s declared default."""
        return copy.deepcopy(self.params[name].default)

    def field(self, name: str):
        """A dataclass field whose default is parameter ``name``'s declared default, so a
        typed config built from Python gets exactly what a launched node gets (no second
        copy of the value in the dataclass)."""
        return dataclasses.field(default_factory=lambda: self.default(name))

    def check_fields(self, config, source: str, names: dict[str, str] | None = None) -> None:
        """Check a typed config's fields against their declarations (ParameterError naming
        ``source`` and the key). ``names`` maps a field to its parameter where they differ;
        fields that are not parameters are skipped."""
        names = names or {}
        for item in dataclasses.fields(config):
            key = names.get(item.name, item.name)
            if key in self.params:
                setattr(config, item.name, self.params[key].check(getattr(config, item.name), source))

    def describe(self) -> str:
        """Every parameter, one line each, for --help."""
        return "\n".join("  " + param.describe() for param in self.params.values())

    def merged(self, other: "ParamSchema") -> "ParamSchema":
        """A schema with this one's parameters and ``other``'s."""
        return ParamSchema(list(self.params.values()) + list(other.params.values()), self.ignore | other.ignore)


def read_yaml_file(path: str):
    """The content of a YAML parameter file; ParameterError naming the file if it cannot be
    read or parsed (a node then stops with that message)."""
    import yaml  # here, not at the top: the validator itself needs no YAML

    try:
        with open(path, encoding="utf-8") as stream:
            return yaml.safe_load(stream)
    except OSError as exc:
        raise ParameterError(f"{path}: cannot read: {exc.strerror or exc}") from None
    except yaml.YAMLError as exc:
        raise ParameterError(f"{path}: not valid YAML: {exc}") from None


def check_ordered(values: dict, pairs, source: str) -> None:
    """Hysteresis and other cross-checks: for each (lower key, upper key) the first value
    must not exceed the second; ParameterError naming both keys and the file otherwise
    (inverted thresholds make a state chatter on and off every frame)."""
    for low, high in pairs:
        if values[low] > values[high]:
            raise ParameterError(
                f"{source}: parameter '{low}' ({values[low]!r}) must not exceed '{high}' ({values[high]!r})"
            )
