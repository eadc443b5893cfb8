"""Gesture recognition on hand frames: static poses, dynamic (DTW) gestures on paths,
and hand-skeleton gestures (a small temporal network, run as ONNX).

Its modules:

- ``gesture_frame``: the frame the recognizers read, and gesture events;
- ``static_poses``: fist, pinch, open palm, second hand, hold still;
- ``gesture_features``: path features of a gesture;
- ``dtw_classifier``: DTW template classification (dtaidistance);
- ``gesture_spotter``: spotting gestures in a continuous stream;
- ``gesture_templates``: template files and datasets;
- ``gesture_recognizer``: static and dynamic recognizers together, as the node runs them;
- ``skeleton_dataset``: SHREC'17-layout skeleton files (.npz), checked, class names;
- ``skeleton_features``: DD-Net features of a skeleton sequence (joint distances, motion);
- ``skeleton_classifier``: the shipped skeleton model through onnxruntime;
- ``skeleton_network``: the network in torch (training only);
- ``skeleton_training``: training, augmentation and ONNX export (torch, training only);
- ``skeleton_negatives``: motion that is no gesture (real Leap runs, transitions between
  gestures), which the training teaches the network to reject;
- ``skeleton_spotted_windows``: training windows cut from streams the way the spotter cuts
  them (training only; off in the shipped recipe);
- ``train_skeleton_gestures``: the training command (user-independent estimate, export);
- ``skeleton_eval``: ``gesture_eval --skeleton``, the shipped model on a .npz;
- ``skeleton_spotter``: online spotting of skeleton gestures (motion between two rests);
- ``skeleton_stream``: continuous streams of segmented gestures with idle gaps.
"""

from motion_common.lazy_exports import lazy_exports

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
    "SkeletonDataset": "skeleton_dataset",
    "load_skeleton_dataset": "skeleton_dataset",
    "SkeletonClassifier": "skeleton_classifier",
    "SkeletonResult": "skeleton_classifier",
}
__all__ = list(_PUBLIC)

__getattr__, __dir__ = lazy_exports(__name__, _PUBLIC, globals())
