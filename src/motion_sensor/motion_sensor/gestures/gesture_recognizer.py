"""One object a gesture node (or the teach mode) feeds frame by frame: static poses plus
spotted dynamic gestures, from a template folder.

    recognizer = GestureRecognizer.from_params(params)      # params: RECOGNIZER_PARAMS
    for frame in frames:                                     # GestureFrame per hand message
        for event in recognizer.update(frame):               # GestureEvent(name, confidence, stamp)
            ...

Event names: the static ones of ``static_poses`` (fist, pinch, open_palm, second_hand,
hold_still and their ``*_end``) and the labels of the dynamic templates (the shipped set:
swipe_right, swipe_left, swipe_up, swipe_down, circle).
"""

import os

from motion_common.params import Param, ParamSchema
from motion_sensor.gestures.dtw_classifier import CLASSIFIER_PARAMS, DTWClassifier
from motion_sensor.gestures.gesture_frame import GestureEvent, GestureFrame
from motion_sensor.gestures.gesture_spotter import SPOTTER_PARAMS, GestureSpotter
from motion_sensor.gestures.gesture_templates import load_templates, templates_to_samples
from motion_sensor.gestures.static_poses import STATIC_PARAMS, StaticPoseDetector

DEFAULT_TEMPLATES = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", "..", "config", "gestures"))

RECOGNIZER_PARAMS = ParamSchema(
    [
        Param("templates", DEFAULT_TEMPLATES, "", "template folder <dir>/<label>/<n>.csv ('' = no dynamic gestures)"),
        Param(
            "reject_percentile",
            99.0,
            "%",
            "percentile of template-to-template distances for the rejection threshold",
            low=50.0,
            high=100.0,
        ),
        Param("reject_margin", 1.3, "", "rejection threshold = percentile x margin", low=0.5, high=5.0),
        Param("static", {}, "", "static pose parameters (static_poses.STATIC_PARAMS)", schema=STATIC_PARAMS),
        Param("spotter", {}, "", "spotting parameters (gesture_spotter.SPOTTER_PARAMS)", schema=SPOTTER_PARAMS),
        Param("classifier", {}, "", "DTW parameters (dtw_classifier.CLASSIFIER_PARAMS)", schema=CLASSIFIER_PARAMS),
    ]
)


def load_classifier(
    folder: str, classifier_params: dict | None = None, reject_percentile: float = 99.0, reject_margin: float = 1.3
) -> DTWClassifier:
    """DTWClassifier of a template folder, rejection calibrated unless set explicitly."""
    classifier = DTWClassifier.from_params(classifier_params or {})
    files, _ = load_templates(folder)
    classifier.fit(templates_to_samples(files))
    if classifier.reject_distance is None and len(classifier):
        classifier.calibrate_rejection(reject_percentile, reject_margin)
    return classifier


class GestureRecognizer:
    """StaticPoseDetector + GestureSpotter behind one ``update``."""

    def __init__(self, static: StaticPoseDetector, spotter: GestureSpotter | None):
        self.static = static
        self.spotter = spotter

    @classmethod
    def from_params(cls, values: dict | None = None, source: str = "gesture_recognizer") -> "GestureRecognizer":
        """Build from a parameter dict (RECOGNIZER_PARAMS); loads the template folder."""
        p = RECOGNIZER_PARAMS.validate(values or {}, source)
        spotter = None
        if p["templates"]:
            classifier = load_classifier(
                os.path.expanduser(p["templates"]), p["classifier"], p["reject_percentile"], p["reject_margin"]
            )
            spotter = GestureSpotter(classifier, p["spotter"], source)
        return cls(StaticPoseDetector(p["static"], source), spotter)

    def update(self, frame: GestureFrame) -> list[GestureEvent]:
        """Events completed by this frame (static first, then a dynamic gesture)."""
        events = self.static.update(frame)
        if self.spotter is not None:
            events.extend(self.spotter.update(frame))
        return events
