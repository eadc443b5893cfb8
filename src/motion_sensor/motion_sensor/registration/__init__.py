"""Registration of a device to the robot base: the rotation, scale and offset that map hand
motion into the base frame.

Its modules:

- ``device_registration``: the fit (Umeyama on DTW-aligned paths) and its YAML file.
"""

from motion_common.lazy_exports import lazy_exports

# Public name -> the module of this subpackage that defines it.
_PUBLIC = {
    "Registration": "device_registration",
    "register": "device_registration",
}
__all__ = list(_PUBLIC)

__getattr__, __dir__ = lazy_exports(__name__, _PUBLIC, globals())
