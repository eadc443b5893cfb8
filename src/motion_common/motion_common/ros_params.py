"""Reads a node's private parameters from the ROS parameter server through a ParamSchema.

The ROS edge of ``motion_common.params``: a node calls ``load_private_params(schema)``
once at start-up; a bad or unknown key logs a fatal message naming the file (the
``~config_file`` parameter the launch file sets, else the node's namespace) and exits.
"""

import rospy

from .errors import ParameterError
from .params import ParamSchema

# Keys roslaunch or our launch files set on every node; never a node's own parameter.
LAUNCH_KEYS = ("config_file",)


def parameter_source() -> str:
    """What to name in messages: the YAML the launch file loaded, or the node's namespace."""
    return rospy.get_param("~config_file", "") or f"parameters of node {rospy.get_name()}"


def load_private_params(schema: ParamSchema, node_name: str = ""):
    """The node's checked private parameters; on a bad one, log fatal and exit with 1."""
    source = parameter_source()
    try:
        values = rospy.get_param("~", {})
        return schema.validate({k: v for k, v in values.items() if k not in LAUNCH_KEYS}, source)
    except ParameterError as exc:
        rospy.logfatal("%s: %s", node_name or rospy.get_name(), exc)
        raise SystemExit(1) from None
