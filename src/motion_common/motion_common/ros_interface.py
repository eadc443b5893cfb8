"""The ROS edge of ``motion_common.interface``: publishers, subscribers, services and
parameters made from a node's one declaration.

A node asks for ``publisher(NODE, "joint_states", queue_size=10)``: the name, the message
type and the latch come from the declaration, so a node can neither use a name it does not
declare nor disagree with the docs about a type. Names stay relative; the launch file's
namespace and remaps place them.
"""

from __future__ import annotations

import math
import warnings

import roslib.message
import rospy

from .frame_tap import FrameTap
from .interface import NodeInterface
from .ros_log_link import install as _install_log_link
from .ros_params import load_private_params

_install_log_link()

__all__ = ["load_params", "publisher", "subscriber", "service", "service_proxy", "message_class", "frame_taps"]


def message_class(type_name: str):
    """The generated Python class of ``pkg/Msg``; a clear error if its package is not built."""
    cls = roslib.message.get_message_class(type_name)
    if cls is None:
        raise ImportError(f"message type {type_name!r} not found (is its package built and sourced?)")
    return cls


def _service_class(type_name: str):
    cls = roslib.message.get_service_class(type_name)
    if cls is None:
        raise ImportError(f"service type {type_name!r} not found (is its package built and sourced?)")
    return cls


def load_params(node: NodeInterface) -> dict:
    """The node's checked private parameters (a bad or unknown key: fatal log and exit 1)."""
    return load_private_params(node.params, node.node)


def publisher(node: NodeInterface, name: str, queue_size=10, **kwargs) -> rospy.Publisher:
    """A publisher of the declared topic ``name`` (type and latch from the declaration)."""
    topic = node.published(name)
    if queue_size is not None:
        return rospy.Publisher(
            topic.name, message_class(topic.type), queue_size=queue_size, latch=topic.latched, **kwargs
        )
    # queue_size=None is rospy's synchronous publishing, chosen on purpose on the hot path
    # (the caller's thread writes to the subscribers itself); rospy warns about it as if
    # the argument had been forgotten, on every run.
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", message=".*queue_size.*", category=SyntaxWarning)
        return rospy.Publisher(topic.name, message_class(topic.type), queue_size=None, latch=topic.latched, **kwargs)


def subscriber(node: NodeInterface, name: str, callback, queue_size=10, **kwargs) -> rospy.Subscriber:
    """A subscriber of the declared topic ``name``."""
    topic = node.subscribed(name)
    return rospy.Subscriber(topic.name, message_class(topic.type), callback, queue_size=queue_size, **kwargs)


def service(node: NodeInterface, name: str, handler) -> rospy.Service:
    """The declared service ``name``, served by ``handler``."""
    entry = node.served(name)
    return rospy.Service(entry.name, _service_class(entry.type), handler)


def service_proxy(node: NodeInterface, name: str, **kwargs) -> rospy.ServiceProxy:
    """A proxy of the declared called service ``name``."""
    entry = node.called(name)
    return rospy.ServiceProxy(entry.name, _service_class(entry.type), **kwargs)


# The frame period a dataset recorder announces (latched std_msgs/Float64, s) and the taps
# it reads instead of the fast streams themselves (motion_common.frame_tap).
FRAME_CLOCK = "frames/clock"


def frame_taps(node: NodeInterface, names, pairs: bool = True, at_instant=None) -> dict:
    """A ``FrameTap`` for each declared tap topic in ``names`` (``frames/<stream>``), all
    following the period latched on ``frames/clock``; feed each with ``add(stamp, msg)``
    right where the stream itself is published. ``pairs=False``: the first message after
    each frame's instant only (a stream the recorder takes as it is). ``at_instant``: one
    message a frame, made by it from the two samples around the instant (``FrameTap``)."""
    taps = {}
    for name in names:
        pub = publisher(node, name, queue_size=4)
        taps[name] = FrameTap(
            lambda msg, pub=pub: _publish_unless_closing(pub, msg),
            lambda pub=pub: pub.get_num_connections() > 0,
            pairs=pairs,
            at_instant=at_instant,
        )

    def on_clock(msg):
        period = float(msg.data)
        for tap in taps.values():
            tap.period = period if period > 0 and math.isfinite(period) else None

    subscriber(node, FRAME_CLOCK, on_clock, queue_size=1)
    return taps


def _publish_unless_closing(pub: rospy.Publisher, msg) -> None:
    """rospy closes topics in its shutdown hooks before is_shutdown() turns true: a tap fed
    from a timer then finds its topic closed, which is not an error."""
    try:
        pub.publish(msg)
    except rospy.ROSException:
        if not (rospy.is_shutdown() or rospy.core.is_shutdown_requested()):
            raise
