"""What the rostest check scripts of this folder share: waiting for a condition, and the
gripper value of the motion controller's status.

A check script finds this module through its own folder, which it puts first on
``sys.path`` (catkin runs the script through a relay in the devel space, so the folder is
not there by itself)::

    sys.path.insert(0, os.path.dirname(os.path.realpath(__file__)))
    from check_helpers import wait_until
"""

import time

import rospy
from diagnostic_msgs.msg import DiagnosticStatus

__all__ = ["wait_until", "gripper_status"]


def wait_until(condition, timeout, what="", period=0.05, notified=None):
    """Wait until ``condition()`` returns a truthy value, and return that value.

    It is checked every ``period`` s, or, with ``notified`` (a ``threading.Condition`` the
    subscribers notify when their data changes), whenever notified, for up to ``timeout`` s
    of wall-clock time or until ROS shuts down. On timeout it returns False, or with
    ``what`` fails: AssertionError "timed out after N s waiting for WHAT".
    """
    deadline = time.monotonic() + timeout
    if notified is None:
        while True:
            value = condition()
            if value:
                return value
            left = deadline - time.monotonic()
            if left <= 0 or rospy.is_shutdown():
                break
            time.sleep(min(period, left))
    else:
        with notified:
            while True:
                value = condition()
                if value:
                    return value
                left = deadline - time.monotonic()
                if left <= 0 or rospy.is_shutdown():
                    break
                notified.wait(left)
    if what:
        raise AssertionError(f"timed out after {timeout:g} s waiting for {what}")
    return False


def gripper_status(expected, timeout=5.0):
    """The gripper value of /motion_controller/status once it reports ``expected`` (the
    status is published at 2 Hz), or the last value seen after ``timeout`` s."""
    deadline = rospy.get_time() + timeout
    while True:
        status = rospy.wait_for_message("/motion_controller/status", DiagnosticStatus, timeout=timeout)
        value = {kv.key: kv.value for kv in status.values}["gripper"]
        if value == expected or rospy.get_time() > deadline:
            return value
