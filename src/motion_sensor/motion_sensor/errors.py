"""The one exception type of the motion_sensor package."""


class MotionSensorError(Exception):
    """A device frame, recording or parameter the motion-sensing layer cannot use.

    The message always says what was wrong and what to do about it.
    """
