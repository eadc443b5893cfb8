"""A package's public names, imported from their module on first use (PEP 562).

Every package of the framework re-exports its public names this way, so that importing a
package loads none of its heavy dependencies (pybullet, cv2, mediapipe, onnxruntime,
pinocchio, rospy) until a name that needs them is used. A package's ``__init__`` names each
public name's submodule and binds the two hooks::

    _PUBLIC = {"Sequencer": "sequencing.sequencer", ...}
    __all__ = list(_PUBLIC)
    __getattr__, __dir__ = lazy_exports(__name__, _PUBLIC, globals())
"""

from importlib import import_module

__all__ = ["lazy_exports"]


def lazy_exports(package: str, public: dict, namespace: dict):
    """(``__getattr__``, ``__dir__``) for ``package``: a public name is imported from its
    submodule (``public[name]``, relative to the package) when first looked up, then kept in
    ``namespace`` (the package's globals) so the next look-up does not come here."""

    def __getattr__(name):
        module = public.get(name)
        if module is None:
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        value = getattr(import_module(f"{package}.{module}"), name)
        namespace[name] = value
        return value

    def __dir__():
        return sorted(set(namespace) | set(public))

    return __getattr__, __dir__
