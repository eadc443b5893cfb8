"""Test doubles shipped with hw_interface, for dry runs without hardware.

``fake_rtde``: a fake of ur_rtde's control, receive and IO interfaces (``FakeUR``) that
records every call and simulates the arm in real time, and ``fake_ur_driver``, the UR driver wired
to it (the registry name ``ur_rtde_fake``). Production code never imports this package:
the fake is selected by that name.

The names in ``__all__`` are imported from their module on first use.
"""

from importlib import import_module as _import_module

# Public name -> the submodule that defines it.
_PUBLIC = {
    "FakeUR": "fake_rtde",
    "AsyncOperationStatus": "fake_rtde",
    "fake_ur_driver": "fake_rtde",
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
