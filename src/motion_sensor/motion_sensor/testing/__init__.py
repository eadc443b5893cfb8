"""Test doubles of the sensing layer, for tests and benchmarks only (no production code
imports them, as ``hw_interface.testing``).

Its modules:

- ``synthetic_depth``: a synthetic hand rendered as depth images.
"""

from importlib import import_module as _import_module

# Public name -> the module of this subpackage that defines it.
_PUBLIC = {
    "HandPose": "synthetic_depth",
    "render_hand": "synthetic_depth",
    "hand_path": "synthetic_depth",
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
