"""Registration of a device to the robot base: the rotation, scale and offset that map hand
motion into the base frame.

Its modules:

- ``device_registration``: the fit (Umeyama on DTW-aligned paths) and its YAML file.
"""

from importlib import import_module as _import_module

# Public name -> the module of this subpackage that defines it.
_PUBLIC = {
    "Registration": "device_registration",
    "register": "device_registration",
}
__all__ = list(_PUBLIC)


def __getattr__(name):
    """Imports the submodule that defines ``name`` on first use (PEP 562)."""
    module = _PUBLIC.get(name)
    if module is None:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    value = getattr(_import_module(f"{__name__}.{module}"), name)
    globals()[name] = value  # the next look-up finds it without this function
    return value


def __dir__():
    return sorted(set(globals()) | set(__all__))
