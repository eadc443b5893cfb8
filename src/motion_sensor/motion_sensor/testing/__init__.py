"""Test doubles of the sensing layer, for tests and benchmarks only (no production code
imports them, as ``hw_interface.testing``).

Its modules:

- ``synthetic_depth``: a synthetic hand rendered as depth images;
- ``skeleton_depth``: a real hand rendered as depth images from its tracked skeleton;
- ``varied_hands``: that hand's bones, shape, tilt and distance varied per sequence.
"""

from motion_common.lazy_exports import lazy_exports

# Public name -> the module of this subpackage that defines it.
_PUBLIC = {
    "HandPose": "synthetic_depth",
    "render_hand": "synthetic_depth",
    "hand_path": "synthetic_depth",
    "HandModel": "skeleton_depth",
    "SensorNoise": "skeleton_depth",
    "render_skeleton": "skeleton_depth",
    "place_in_view": "skeleton_depth",
    "HandVariation": "varied_hands",
    "vary_sequence": "varied_hands",
}
__all__ = list(_PUBLIC)

__getattr__, __dir__ = lazy_exports(__name__, _PUBLIC, globals())
