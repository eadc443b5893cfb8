"""The one declaration of every node of the motion-sensing layer (see
``motion_common.interface``): parameters with default, unit and range, and the topics and
services each node uses, all with relative names.

The device nodes share one wrapper (``device_interface``); the device classes are imported
only by ``device_nodes()``, so a node that needs one declaration does not load every
device's libraries. No ROS import.
"""

from motion_common.interface import NodeInterface, Topic
from motion_common.params import Param, ParamSchema
from motion_sensor.devices.device import HandDevice
from motion_sensor.devices.device_interface import device_interface
from motion_sensor.gestures.gesture_recognizer import RECOGNIZER_PARAMS
from motion_sensor.gestures.skeleton_spotter import SKELETON_SPOTTER_PARAMS
from motion_sensor.sequencing.sequencer import SEQUENCER_PARAMS

__all__ = [
    "SEQUENCER",
    "GESTURE_RECOGNIZER",
    "SKELETON_GESTURE_SPOTTER",
    "RECORD_HANDS",
    "REGISTRATION_TF",
    "device_nodes",
    "all_interfaces",
]

_HAND = "motion_sensor/hand"
_SKELETON = "motion_sensor/HandSkeleton"

SEQUENCER = NodeInterface(
    "motion_sensor",
    "sequencer",
    "Cleans the device hand streams (validation, device binding, timing, trims, jump rejection, filter) and "
    "publishes the motion commands. One input `~input` by default (remapped to `motion_sensor/raw_hand`); "
    "with `~inputs`, one subscription per listed device topic instead.",
    SEQUENCER_PARAMS,
    publishes=(
        Topic("motion_sensor/hand", _HAND, "the filtered hand, sensor stamp kept, gesture fields passed through"),
        Topic("motion_states", "geometry_msgs/Pose", "the paper's output: the filtered palm pose"),
        Topic(
            "motion_states_stamped",
            "geometry_msgs/PoseStamped",
            "the same pose with the sensor stamp (the core's input)",
        ),
        Topic("motion_sensor/active_device", "std_msgs/String", "the device that drives", latched=True),
        Topic("motion_sensor/filter", "std_msgs/String", "the active filter", latched=True),
        Topic("diagnostics", "diagnostic_msgs/DiagnosticArray", "counters by drop reason and latency, 1 Hz"),
        Topic(
            "motion_sensor/hand_skeleton",
            _SKELETON,
            "the skeletons whose palm frame passed (the same drop rules), device stamp kept",
        ),
        Topic("frames/hand", _HAND, "the filtered hand around each recorded frame's instant"),
        Topic("frames/hand_skeleton", _SKELETON, "the skeletons around each recorded frame's instant"),
    ),
    subscribes=(
        Topic(
            "frames/clock",
            "std_msgs/Float64",
            "a dataset recorder's frame period (s): starts the frames/ taps",
            optional=True,
        ),
        Topic("~input", _HAND, "the device stream (when `~inputs` is unset)", optional=True),
        Topic(
            "motion_sensor/raw_hand_skeleton",
            _SKELETON,
            "the devices' skeletons, paired with their palm frames by stamp",
            optional=True,
        ),
        Topic(
            "motion_controller/trace",
            "motion_commander/CommandTrace",
            "commands the robot accepted: older frames are outdated",
        ),
        Topic("motion_sensor/set_filter", "std_msgs/String", "switch the filter live (output kept continuous)"),
    ),
)

GESTURE_RECOGNIZER = NodeInterface(
    "motion_sensor",
    "gesture_recognizer",
    "Recognises static poses and dynamic (DTW template) gestures in the filtered hand stream.",
    RECOGNIZER_PARAMS,
    publishes=(Topic("motion_sensor/gesture", "motion_sensor/Gesture", "every recognised gesture, sensor stamp"),),
    subscribes=(Topic("motion_sensor/hand", _HAND, "the filtered hand stream"),),
)

SKELETON_GESTURE_SPOTTER = NodeInterface(
    "motion_sensor",
    "skeleton_gesture_spotter",
    "Spots hand-skeleton gestures (motion between two rests, classified by the shipped ONNX model; confidence, "
    "duration and extent gates, refractory period) in the sequenced skeleton stream; publishes each with its "
    "start and end.",
    SKELETON_SPOTTER_PARAMS.merged(
        ParamSchema(
            [
                Param("model", "", doc="ONNX model (empty: the shipped data/skeleton_gestures.onnx)"),
                Param("hand", "", choices=("", "left", "right"), doc="follow only this hand (empty: the first seen)"),
            ]
        )
    ),
    publishes=(
        Topic(
            "motion_sensor/gesture",
            "motion_sensor/Gesture",
            "every spotted gesture: 14-class name, confidence, stamp = end, start and end",
        ),
    ),
    subscribes=(Topic("motion_sensor/hand_skeleton", _SKELETON, "the sequenced skeleton stream"),),
)

RECORD_HANDS = NodeInterface(
    "motion_sensor",
    "record_hands",
    "Records hand streams to a rosbag until shutdown (`~topics`, relative names).",
    ParamSchema(
        [
            Param("output", "hands.bag", doc="rosbag path (~ expanded); its folder is created"),
            Param(
                "topics",
                ["motion_sensor/raw_hand", "motion_sensor/hand"],
                item_kind=str,
                doc="motion_sensor/hand topics recorded",
            ),
            Param(
                "skeleton_topics",
                ["motion_sensor/raw_hand_skeleton", "motion_sensor/hand_skeleton"],
                item_kind=str,
                doc="motion_sensor/HandSkeleton topics recorded (the replay plays raw_hand_skeleton with raw_hand)",
            ),
        ]
    ),
    subscribes=(
        Topic("motion_sensor/raw_hand", _HAND, "recorded (default `~topics`)", optional=True),
        Topic("motion_sensor/hand", _HAND, "recorded (default `~topics`)", optional=True),
        Topic("motion_sensor/raw_hand_skeleton", _SKELETON, "recorded (default `~skeleton_topics`)", optional=True),
        Topic("motion_sensor/hand_skeleton", _SKELETON, "recorded (default `~skeleton_topics`)", optional=True),
    ),
)

REGISTRATION_TF = NodeInterface(
    "motion_sensor",
    "registration_tf",
    "Publishes a device registration (register_device's YAML) as a static tf from the robot base to the device frame.",
    ParamSchema(
        [
            Param("registration_file", "", doc="register_device's YAML (required)"),
            Param("parent", "base_link", doc="robot base frame"),
            Param("child", "leap", doc="device frame"),
        ]
    ),
)


class _AnyDevice(HandDevice):
    """What the generic device_node declares: any device, which may end (a recording)."""

    name = "device"
    finite = True


def device_nodes():
    """The declarations of the device nodes (imports every device class)."""
    from dataclasses import replace

    from motion_sensor.devices.depth_device import DepthTopicDevice
    from motion_sensor.devices.kinect import FakenectKinectDevice
    from motion_sensor.devices.leap_client import LeapDevice
    from motion_sensor.devices.replay import ReplayDevice
    from motion_sensor.devices.shrec_stream import ShrecStreamDevice
    from motion_sensor.devices.spacemouse import SpaceMouseDevice
    from motion_sensor.devices.webcam_device import WebcamHandDevice

    kinect = device_interface(
        FakenectKinectDevice,
        "kinect_driver",
        "A Kinect v1 through libfreenect, or a fakenect dump (`~fakenect_dump`, finite).",
    )
    kinect = replace(
        kinect, publishes=tuple(replace(t, optional=True) if t.name == "~finished" else t for t in kinect.publishes)
    )
    webcam = device_interface(WebcamHandDevice, "webcam_hand_driver")
    spacemouse = device_interface(SpaceMouseDevice, "spacemouse_driver")
    spacemouse = replace(
        spacemouse,
        publishes=tuple(replace(t, optional=True) if t.name == "~finished" else t for t in spacemouse.publishes),
    )
    generic = device_interface(
        _AnyDevice,
        "device_node",
        "Any HandDevice class of one's own, given as `module:Class` (`device:=module:Class`; "
        "examples/circle_device.py): the shared device wrapper's parameters and topics, plus the class's own "
        "parameters.",
    )
    generic = replace(
        generic, publishes=tuple(replace(t, optional=True) if t.name == "~finished" else t for t in generic.publishes)
    )
    webcam = replace(
        webcam, publishes=tuple(replace(t, optional=True) if t.name == "~finished" else t for t in webcam.publishes)
    )
    return [
        device_interface(LeapDevice, "leap_driver"),
        spacemouse,
        webcam,
        device_interface(DepthTopicDevice, "depth_hand_driver"),
        kinect,
        device_interface(ReplayDevice, "hand_replay"),
        device_interface(ShrecStreamDevice, "shrec_stream_driver"),
        generic,
    ]


def all_interfaces():
    """Every node of this package."""
    return [SEQUENCER, GESTURE_RECOGNIZER, SKELETON_GESTURE_SPOTTER, RECORD_HANDS, REGISTRATION_TF] + device_nodes()
