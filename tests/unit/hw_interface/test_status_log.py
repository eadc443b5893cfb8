"""Driver status changes reach the console by their weight: faults and protective stops
as errors, their clearing and connection changes as info, motion and gripper as debug."""

from hw_interface.robot_hw import DriverStatus
from hw_interface.status_log import status_change


def test_first_status_and_connection_changes_are_info():
    assert status_change(None, DriverStatus(connected=True)) == ("info", "driver connected")
    assert status_change(DriverStatus(connected=True), DriverStatus()) == ("info", "driver not connected")


def test_motion_and_gripper_are_debug():
    idle = DriverStatus(connected=True)
    for new in (DriverStatus(connected=True, moving=True), DriverStatus(connected=True, gripper="part")):
        level, message = status_change(idle, new)
        assert level == "debug" and "driver status" in message


def test_faults_and_protective_stops_are_errors_and_their_clearing_info():
    idle = DriverStatus(connected=True)
    fault = DriverStatus(connected=True, fault="joint 3 overcurrent")
    assert status_change(idle, fault) == ("error", "driver fault: joint 3 overcurrent")
    assert status_change(fault, DriverStatus(connected=True, fault="joint 3 overcurrent", moving=True))[0] == "debug"
    assert status_change(fault, idle) == ("info", "driver fault cleared")
    stopped = DriverStatus(connected=True, protective_stop=True, safety_mode="PROTECTIVE_STOP")
    assert status_change(idle, stopped) == ("error", "protective stop (safety mode PROTECTIVE_STOP)")
    assert status_change(stopped, idle) == ("info", "protective stop cleared")
