"""The parameters a fake driver (``ur_rtde_fake``, ``simple_message_fake``) takes on top of
its driver's: the start pose of the simulated arm, and the fake's own settings."""

from motion_common.params import Param, ParamSchema

__all__ = ["INITIAL_JOINTS_PARAM", "fake_driver_parameters"]

#: Where the simulated arm starts (a session passes the robot's start pose).
INITIAL_JOINTS_PARAM = Param(
    "initial_joints",
    None,
    "rad",
    "start pose of the simulated arm (motion_common/config/robots/<robot>.yaml)",
    kind=list,
    nullable=True,
)


def fake_driver_parameters(driver_schema: ParamSchema, *own: Param) -> ParamSchema:
    """A fake driver's schema: its driver's parameters, ``initial_joints``, then ``own``."""
    return driver_schema.merged(ParamSchema([INITIAL_JOINTS_PARAM, *own]))
