"""Test doubles shipped with hw_interface, for dry runs without hardware.

``fake_rtde``: a fake of ur_rtde's control, receive and IO interfaces (``FakeUR``) that
records every call and simulates the arm in real time, and ``fake_ur_driver``, the UR driver wired
to it (the registry name ``ur_rtde_fake``); ``fake_simple_message``: a byte-level simulated
ROS-Industrial controller serving simple_message on two TCP ports
(``FakeSimpleMessageController``), and ``fake_simple_message_driver``, the simple_message
driver wired to it (``simple_message_fake``). Both simulated controllers share
``fault_injection`` (a fault halts the arm until cleared) and both fake drivers
``fake_parameters`` (the start pose on top of the driver's parameters). Production code
never imports this package: the fake is selected by that name.

The names in ``__all__`` are imported from their module on first use.
"""

from motion_common.lazy_exports import lazy_exports

# Public name -> the submodule that defines it.
_PUBLIC = {
    "FakeUR": "fake_rtde",
    "AsyncOperationStatus": "fake_rtde",
    "fake_ur_driver": "fake_rtde",
    "FakeSimpleMessageController": "fake_simple_message",
    "fake_simple_message_driver": "fake_simple_message",
}
__all__ = list(_PUBLIC)

__getattr__, __dir__ = lazy_exports(__name__, _PUBLIC, globals())
