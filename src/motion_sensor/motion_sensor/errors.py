"""The one exception type of the motion_sensor package."""


class MotionSensorError(Exception):
    """A device frame, recording or parameter the motion-sensing layer cannot use.

    The message always says what was wrong and what to do about it.
    """


class DeviceUnavailable(MotionSensorError):
    """The device cannot be reached now (refused, unplugged, dropped); a reconnect may cure it."""


class EndOfStream(Exception):
    """A finite source (a recording) has no more samples."""
