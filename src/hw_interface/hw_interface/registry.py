"""Drivers are found by name: built-ins here, plus any installed Python package that
declares an entry point in the ``hw_interface.drivers`` group (the paper's "driver update"
pattern: a new robot plugs in without touching this package)."""

from collections.abc import Callable
from importlib import import_module
from importlib.metadata import entry_points

from .errors import HwInterfaceError

ENTRY_POINT_GROUP = "hw_interface.drivers"

# name -> "module:attribute"; imported lazily so a missing optional dependency of one
# driver never stops the others from loading.
_BUILTIN = {
    "pybullet": "hw_interface.sim_driver:PybulletSimDriver",
    "ur_rtde": "hw_interface.ur_driver:URRtdeDriver",
    # The UR driver on a simulated controller (dry runs, tests): injected, not a flag.
    "ur_rtde_fake": "hw_interface.testing.fake_rtde:fake_ur_driver",
    # ROS-Industrial controllers (Stäubli, ABB, Fanuc, Motoman) over simple_message, and the
    # same driver on a byte-level simulated controller.
    "simple_message": "hw_interface.industrial_driver:SimpleMessageDriver",
    "simple_message_fake": "hw_interface.testing.fake_simple_message:fake_simple_message_driver",
}
_registered: dict[str, Callable] = {}


def register_driver(name: str, factory: Callable) -> None:
    """Register a driver factory (a RobotDriver subclass or a callable) under ``name``."""
    _registered[name] = factory


def available_drivers():
    """Sorted names of every driver that can be created."""
    plugins = {ep.name for ep in entry_points(group=ENTRY_POINT_GROUP)}
    return sorted(set(_BUILTIN) | set(_registered) | plugins)


def _load(target: str) -> Callable:
    module_name, _, attribute = target.partition(":")
    return getattr(import_module(module_name), attribute)


def driver_factory(name: str) -> Callable:
    """The factory of driver ``name``: a registered name, or ``module:attribute`` of any
    module on the Python path (a driver of one's own, without packaging it); raises
    HwInterfaceError naming the known drivers."""
    if ":" in name:
        module_name, _, attribute = name.partition(":")
        try:
            return getattr(import_module(module_name), attribute)
        except ImportError as exc:
            raise HwInterfaceError(
                f"driver {name!r}: cannot import {module_name!r} ({exc}); is it on PYTHONPATH?"
            ) from None
        except AttributeError:
            raise HwInterfaceError(f"driver {name!r}: module {module_name!r} has no {attribute!r}") from None
    if name in _registered:
        return _registered[name]
    if name in _BUILTIN:
        return _load(_BUILTIN[name])
    for ep in entry_points(group=ENTRY_POINT_GROUP):
        if ep.name == name:
            return ep.load()
    raise HwInterfaceError(
        f"no robot driver named {name!r}; available: {available_drivers()}, or module:Class of your own"
    )


def driver_parameters(name: str):
    """The ParamSchema of driver ``name``'s driver_params, or None when it declares none."""
    return getattr(driver_factory(name), "PARAMETERS", None)


def stream_lag_s(name: str, driver_params: dict | None = None) -> float:
    """How long (s) driver ``name``'s arm trails a streamed target beyond the simulation's
    follower: its ``STREAM_LAG_PARAM`` from ``driver_params``, else that parameter's
    declared default; 0 for a driver that declares none."""
    factory = driver_factory(name)
    key = getattr(factory, "STREAM_LAG_PARAM", None)
    if key is None:
        return 0.0
    schema = getattr(factory, "PARAMETERS", None)
    values = {**(schema.defaults() if schema is not None else {}), **(driver_params or {})}
    return float(values.get(key, 0.0))


def create_driver(name: str, **params):
    """Create driver ``name`` with its parameters."""
    factory = driver_factory(name)
    try:
        return factory(**params)
    except TypeError as exc:
        raise HwInterfaceError(f"bad parameters for driver {name!r}: {exc}") from None
