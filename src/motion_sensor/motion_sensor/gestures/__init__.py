"""Gesture recognition on hand frames: static poses and dynamic (DTW) gestures.

Its modules:

- ``gesture_frame``: the frame the recognizers read, and gesture events;
- ``static_poses``: fist, pinch, open palm, second hand, hold still;
- ``gesture_features``: path features of a gesture;
- ``dtw_classifier``: DTW template classification (dtaidistance);
- ``gesture_spotter``: spotting gestures in a continuous stream;
- ``gesture_templates``: template files and datasets;
- ``gesture_recognizer``: static and dynamic recognizers together, as the node runs them.
"""

from importlib import import_module as _import_module

# Public name -> the module of this subpackage that defines it.
_PUBLIC = {
    "GestureFrame": "gesture_frame",
    "GestureEvent": "gesture_frame",
    "frames_from_recording": "gesture_frame",
    "StaticPoseDetector": "static_poses",
    "FeatureConfig": "gesture_features",
    "DTWClassifier": "dtw_classifier",
    "GestureSpotter": "gesture_spotter",
    "save_template": "gesture_templates",
    "load_templates": "gesture_templates",
    "load_dataset": "gesture_templates",
    "GestureRecognizer": "gesture_recognizer",
    "load_classifier": "gesture_recognizer",
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
