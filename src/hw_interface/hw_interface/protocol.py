"""The commander.srv command and result tables as Python enums.

They mirror the constants of motion_commander/srv/commander.srv so that the pure-Python
dispatcher needs no generated ROS code; a unit test checks the two stay identical.
"""

import enum


class CommandIndex(enum.IntEnum):
    """commander.srv command_index values."""

    GET_ROBOTS = 1
    LOGIN = 2
    GET_ROBOT_JOINTS = 3
    GET_ROBOT_CARTESIAN_POSITION = 4
    SET_JOINTS = 5
    MOVE_L = 6
    MOVE_J = 7
    STOP = 8
    SET_GRIPPER = 9
    SET_DIGITAL_OUTPUT = 10
    FOLLOW_PATH = 11


class Result(enum.IntEnum):
    """commander.srv result codes."""

    SUCCESS = 0
    UNKNOWN_COMMAND = 1
    WRONG_LENGTH = 2
    NOT_FINITE = 3
    JOINT_LIMIT = 4
    OUT_OF_WORKSPACE = 5
    UNREACHABLE = 6
    TOO_FAR = 7
    NOT_CONNECTED = 8
    LOGIN_FAILED = 9
    DRIVER_FAULT = 10
    PROTECTIVE_STOP = 11
    BUSY = 12
    TIMEOUT = 13
    BAD_ORIENTATION = 14
    INTERRUPTED = 15  # a blocking move cut short: STOP, latched stop, fault, protective stop
    LATCHED_STOP = 16  # refused: a latched stop is active until released
    NOT_SUPPORTED = 17  # the driver cannot do this command (FOLLOW_PATH on a driver without timed paths)
