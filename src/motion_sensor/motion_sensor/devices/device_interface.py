"""The declaration of a hand-device node: what every device node shares (the wrapper's
parameters and topics), merged with the device class's own parameters.

``device_interface(LeapDevice, "leap_driver")`` is the one declaration of the leap_driver
node; ``device_node`` runs it and ``interfaces`` lists it for the docs and the checks. No
ROS import.
"""

import dataclasses

from motion_common.interface import NodeInterface, Topic
from motion_common.params import Param, ParamSchema

__all__ = ["WRAPPER_PARAMS", "RAW_HAND", "RAW_HAND_SKELETON", "SESSION_READY", "node_schema", "device_interface"]

WRAPPER_PARAMS = ParamSchema(
    [
        Param("frame_id", "", doc="header.frame_id of the samples; empty: the device's default"),
        Param(
            "wait_for_ready",
            False,
            doc="stream only once True arrives on session_ready (the launch file remaps it "
            "to the core's or the teach node's ready topic)",
        ),
        Param(
            "min_subscribers", 0, low=0, doc="streaming starts once motion_sensor/raw_hand has this many subscribers"
        ),
        Param(
            "start_delay", 0.0, unit="s", low=0, doc="extra wait after readiness (compatibility; prefer wait_for_ready)"
        ),
        Param("backoff_initial_s", 0.25, unit="s", low=0, low_open=True, doc="first reconnect delay"),
        Param("backoff_max_s", 5.0, unit="s", low=0, low_open=True, doc="longest reconnect delay"),
        Param("backoff_factor", 2.0, low=1, doc="reconnect delay growth per failed attempt"),
        Param("diagnostics_period_s", 1.0, unit="s", low=0, low_open=True, doc="diagnostics period"),
        Param(
            "queue_size",
            0,
            low=0,
            doc="publisher queue size; 0: the device thread writes each message to its subscribers itself "
            "(no hand-off to rospy's writer thread: ~0.1-0.3 ms less latency per hop, bench/e2e_latency)",
        ),
    ]
)

RAW_HAND = Topic("motion_sensor/raw_hand", "motion_sensor/hand", "the device's hand frames, stamped at capture")
RAW_HAND_SKELETON = Topic(
    "motion_sensor/raw_hand_skeleton",
    "motion_sensor/HandSkeleton",
    "the whole skeleton of each hand seen (canonical 22 joints), same stamp as the frame's raw_hand",
)
SESSION_READY = Topic(
    "session_ready", "std_msgs/Bool", "streaming starts once True arrives (wait_for_ready)", optional=True
)
_DIAGNOSTICS = Topic("diagnostics", "diagnostic_msgs/DiagnosticArray", "device counters and connection state")
_FINISHED = Topic("~finished", "std_msgs/Bool", "False at start, True when a finite source has played", latched=True)


def node_schema(device_cls) -> ParamSchema:
    """The device's parameters and the wrapper's, with the device's wrapper defaults."""
    wrapper = ParamSchema(
        [
            dataclasses.replace(p, default=device_cls.wrapper_defaults[p.name])
            if p.name in device_cls.wrapper_defaults
            else p
            for p in WRAPPER_PARAMS.params.values()
        ]
    )
    return device_cls.params.merged(wrapper)


def device_interface(device_cls, node: str, doc: str = "") -> NodeInterface:
    """The declaration of the node that runs ``device_cls``."""
    publishes = [RAW_HAND, _DIAGNOSTICS]
    if getattr(device_cls, "publishes_skeletons", False):
        publishes.append(RAW_HAND_SKELETON)
    publishes += [
        Topic(name, "std_msgs/Bool", f"the device's {key} output", latched=True)
        for key, name in sorted(device_cls.bool_outputs.items())
    ]
    if device_cls.finite:
        publishes.append(_FINISHED)
    subscribes = [SESSION_READY] + list(getattr(device_cls, "subscribes", ()))
    return NodeInterface(
        "motion_sensor",
        node,
        doc or (device_cls.__doc__ or "").split("\n\n")[0],
        node_schema(device_cls),
        publishes=tuple(publishes),
        subscribes=tuple(subscribes),
    )
