"""The one exception type of the motion_commander package."""


class MotionCommanderError(Exception):
    """A robot model, parameter or command the core cannot use; the message says what to do."""
