"""A device class of one's own, named ``module:Class`` (``device:=module:Class``).

The generic ``device_node`` runs whatever HandDevice subclass this returns, so a device
needs no executable of its own (examples/circle_device.py on PYTHONPATH).
"""

import importlib

from motion_sensor.devices.device import HandDevice
from motion_sensor.errors import MotionSensorError

__all__ = ["device_class"]


def device_class(spec: str) -> type:
    """The HandDevice subclass named ``module:Class``; MotionSensorError saying why not."""
    module_name, _, attribute = spec.partition(":")
    if not module_name or not attribute:
        raise MotionSensorError(f"give the device as module:Class, got {spec!r}")
    try:
        cls = getattr(importlib.import_module(module_name), attribute)
    except ImportError as exc:
        raise MotionSensorError(f"cannot import {module_name!r} ({exc}); is it on PYTHONPATH?") from None
    except AttributeError:
        raise MotionSensorError(f"module {module_name!r} has no {attribute!r}") from None
    if not (isinstance(cls, type) and issubclass(cls, HandDevice)):
        raise MotionSensorError(f"{spec} is not a HandDevice subclass")
    return cls
