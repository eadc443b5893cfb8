"""The driver parameters that the drivers of real controllers (``ur_rtde``,
``simple_message``) declare alike, declared once so their names, units, ranges and
defaults cannot drift apart: the arming pair, the reconnect backoff and the arrival
tolerances of a move checked on the measured arm. ``positive_param`` declares the
commonest kind of driver parameter (a strictly positive number with an upper bound) in
one line.

A parameter whose name is shared but whose meaning is not (``settle_time``: how long a
finished UR move may take to arrive, but how long a still simple_message arm may wait
short of its goal) stays with its driver.
"""

from motion_common.params import Param

__all__ = ["ARMING_PARAMS", "RECONNECT_PARAMS", "GOAL_TOLERANCE_PARAMS", "positive_param"]


def positive_param(name: str, default: float, unit: str, doc: str, high: float) -> Param:
    """A number in (0, ``high``]: speeds, timeouts, tolerances."""
    return Param(name, default, unit, doc, low=0.0, high=high, low_open=True)


#: Where the controller is, and the switch without which the driver never connects to it.
ARMING_PARAMS = (
    Param("robot_ip", "", doc="controller address; empty: never connect"),
    Param("armed", False, doc="must be true to connect and move the robot"),
)

#: How often and how patiently the driver (re)connects; the waits double each time.
RECONNECT_PARAMS = (
    Param("reconnect_attempts", 3, "", "connection attempts before giving up", low=1, high=20),
    Param("reconnect_backoff", 0.5, "s", "first wait between attempts, doubled each time", low=0.0, high=10.0),
)

#: How close the MEASURED arm must come for a MoveJ / MoveL to answer SUCCESS.
GOAL_TOLERANCE_PARAMS = (
    positive_param(
        "goal_tolerance",
        0.002,
        "rad",
        "largest joint error (MoveJ) / orientation error (MoveL) of the measured arm for SUCCESS",
        0.1,
    ),
    positive_param(
        "goal_position_tolerance", 0.002, "m", "largest measured tool position error for a MoveL SUCCESS", 0.05
    ),
)
