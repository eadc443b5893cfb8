"""Exceptions of the foundation layer."""


class RobotModelError(Exception):
    """A URDF, tool frame or robot model the framework cannot use; the message says what to do."""


class ParameterError(Exception):
    """A node parameter (or parameter file) that fails its check; the message names the file,
    the key and what is allowed."""
