"""MotionControllerClient: a persistent, thread-safe Python client of /motion_controller.

This module is the package's ROS edge for scripts (it imports rospy); the caller must have
called rospy.init_node. Every method raises HwInterfaceError, carrying the commander.srv
result code, when the server refuses or fails a command.
"""

import threading

import rospy

from motion_commander.srv import commander, commanderRequest

from .errors import HwInterfaceError
from .protocol import CommandIndex, Result


class MotionControllerClient:
    """Keeps one persistent connection to the service and re-opens it if it drops."""

    def __init__(self, service: str = "motion_controller", timeout: float = 10.0):
        self.service = service
        try:
            rospy.wait_for_service(service, timeout=timeout)
        except rospy.ROSInterruptException:
            # rospy raises this (a ROSException) when the node is shut down while waiting: the
            # session is ending, and "did not appear within N s" would blame the wrong thing.
            raise HwInterfaceError(f"shut down while waiting for service {service}", Result.NOT_CONNECTED) from None
        except rospy.ROSException:
            raise HwInterfaceError(
                f"service {service} did not appear within {timeout:.0f} s; "
                "is motion_controller_server running (launch/hw_sim.launch)?",
                Result.NOT_CONNECTED,
            ) from None
        self._proxy = rospy.ServiceProxy(service, commander, persistent=True)
        # One persistent connection carries one request at a time; callers on several
        # threads (subscribers, timers, service handlers) take turns.
        self._lock = threading.Lock()

    def call(
        self,
        command_index: int,
        position=(),
        orientation=(),
        joints=(),
        frame_id: str = "",
        stamp=None,
        check: bool = True,
        times=(),
    ):
        """Send one request; return the response (raise on a non-SUCCESS result if ``check``)."""
        request = commanderRequest(
            command_index=int(command_index),
            position=list(position),
            orientation=list(orientation),
            joints=list(joints),
            times=list(times),
        )
        request.header.frame_id = frame_id
        if stamp is not None:
            request.header.stamp = stamp
        if command_index == CommandIndex.STOP:
            # STOP must never wait behind this client's own blocking MOVE_J/MOVE_L on the
            # persistent connection: it goes on a connection of its own, at once.
            response = rospy.ServiceProxy(self.service, commander)(request)
        else:
            with self._lock:
                try:
                    response = self._proxy(request)
                except (rospy.ServiceException, rospy.ROSException):
                    # A persistent connection dies with the server; one fresh try is enough.
                    self._proxy = rospy.ServiceProxy(self.service, commander, persistent=True)
                    response = self._proxy(request)
        if check and response.result != Result.SUCCESS:
            raise HwInterfaceError(
                f"{CommandIndex(command_index).name if command_index in set(CommandIndex) else command_index} "
                f"refused: {Result(response.result).name}: {response.header.frame_id}",
                response.result,
            )
        return response

    def close(self):
        """Close the persistent connection."""
        self._proxy.close()

    def get_robots(self):
        """[(name, dof)] of the robots the server drives."""
        response = self.call(CommandIndex.GET_ROBOTS)
        return list(zip(response.header.frame_id.split(","), [int(d) for d in response.joints]))

    def login(self, url: str):
        """Connect the server's driver to ``url``."""
        self.call(CommandIndex.LOGIN, frame_id=url)

    def get_joints(self):
        """Measured joints (rad)."""
        return list(self.call(CommandIndex.GET_ROBOT_JOINTS).joints)

    def get_pose(self):
        """Measured tool (position, quaternion x, y, z, w)."""
        response = self.call(CommandIndex.GET_ROBOT_CARTESIAN_POSITION)
        return list(response.position), list(response.orientation)

    def set_joints(self, joints, stamp=None):
        """Stream a joint target (returns at once)."""
        return self.call(CommandIndex.SET_JOINTS, joints=joints, stamp=stamp)

    def move_j(self, joints):
        """Joint-interpolated move; blocks until done."""
        return self.call(CommandIndex.MOVE_J, joints=joints)

    def move_l(self, position, orientation):
        """Straight-line tool move; blocks until done."""
        return self.call(CommandIndex.MOVE_L, position=position, orientation=orientation)

    def follow_path(self, times, joints) -> float:
        """Send a timed joint path (``times`` s from its start; ``joints`` one row per
        time); blocks until the robot arrived at its end; return when it started
        (wall-clock s, on the clock of joint_states' stamps)."""
        flat = [float(v) for row in joints for v in row]
        return self.call(CommandIndex.FOLLOW_PATH, joints=flat, times=[float(t) for t in times]).header.stamp.to_sec()

    def stop(self):
        """Stop all motion at once."""
        return self.call(CommandIndex.STOP)

    def set_gripper(self, closed: bool):
        """Grip (True) or release (False)."""
        return self.call(CommandIndex.SET_GRIPPER, joints=[1.0 if closed else 0.0])

    def set_digital_output(self, output: int, value: bool):
        """Set a digital output of the controller."""
        return self.call(CommandIndex.SET_DIGITAL_OUTPUT, joints=[float(output), 1.0 if value else 0.0])
