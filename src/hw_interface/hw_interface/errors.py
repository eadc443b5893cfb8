"""The one exception type of the hw_interface package."""


class HwInterfaceError(Exception):
    """A driver, controller or request problem; the message says what to do about it.

    ``result`` is the commander.srv result code the server answers with.
    """

    def __init__(self, message: str, result: int = 10):
        super().__init__(message)
        self.result = result
