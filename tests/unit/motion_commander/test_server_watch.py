"""A lost robot server is a stop, and its return is a fresh start: ServerWatch (failed
calls, stale joint_states, probes with backoff) and TeleopCore.set_server_lost."""

import numpy as np
import pytest

from motion_commander.errors import MotionCommanderError
from motion_commander.server_watch import ServerState, ServerWatch
from motion_commander.teleop_core import TeleopStatus

from ..conftest import HOME
from .test_teleop import IDENTITY, make_core


def test_stale_joint_states_lose_the_server_within_the_bound():
    watch = ServerWatch(stale_after_s=0.5)
    assert watch.state == ServerState.UNKNOWN and not watch.check(10.0)  # start-up: not lost
    for k in range(100):
        watch.on_joint_state(k * 0.01)
    assert not watch.check(0.99 + 0.5)
    assert watch.check(0.99 + 0.51) and watch.lost and "no joint_states" in watch.reason
    assert not watch.check(5.0)  # reported once
    assert watch.losses == 1


def test_a_failed_call_loses_it_at_once_and_probes_back_off():
    watch = ServerWatch(stale_after_s=0.5, backoff_initial_s=0.2, backoff_max_s=1.0)
    watch.on_joint_state(0.0)
    assert watch.on_call_failed(0.1, "connection refused") and watch.lost
    assert not watch.on_call_failed(0.11, "again")  # already lost
    assert not watch.probe_due(0.2) and watch.probe_due(0.31)
    times, now = [], 0.31
    for _ in range(6):  # the server stays away: probes space out, 0.4, 0.8, 1.0, 1.0 ...
        while not watch.probe_due(now):
            now += 0.01
        times.append(now)
        assert not watch.on_probe(now, ok=False)
    gaps = np.diff(times)
    assert gaps[0] == pytest.approx(0.4, abs=0.011) and gaps[-1] == pytest.approx(1.0, abs=0.011)


def test_the_server_is_back_only_with_a_good_probe_and_fresh_joint_states():
    watch = ServerWatch(stale_after_s=0.5)
    watch.on_joint_state(0.0)
    watch.check(1.0)
    assert watch.lost
    assert not watch.on_probe(1.3, ok=True)  # answers, but no joint_states since the loss
    watch.on_joint_state(1.4)
    assert watch.recovered(1.41) and watch.state == ServerState.ALIVE and watch.reason == ""


def test_bad_settings_are_refused():
    with pytest.raises(MotionCommanderError):
        ServerWatch(stale_after_s=0)
    with pytest.raises(MotionCommanderError):
        ServerWatch(backoff_initial_s=2.0, backoff_max_s=1.0)


def test_core_streams_nothing_while_the_server_is_lost_and_needs_a_fresh_engage_after():
    core = make_core(steady=2)
    core.on_joint_state(HOME)
    hand = np.array([0.0, 0.0, 0.2])
    core.on_hand_pose(0.01, hand, IDENTITY)
    assert core.on_hand_pose(0.02, hand, IDENTITY) is not None and core.mapper.engaged
    core.set_server_lost(True)
    assert core.status == TeleopStatus.SERVER_LOST and not core.mapper.engaged
    assert core.on_hand_pose(0.03, hand + 0.01, IDENTITY) is None
    assert core.measured_joints is None  # the state from before the loss is forgotten
    # Back: the arm is somewhere else now (a restarted controller); the stream never resumes
    # from before, the clutch needs its steady frames again, and engages on the measured joints.
    core.set_server_lost(False)
    assert core.status == TeleopStatus.WAITING_FOR_ROBOT
    assert core.on_hand_pose(0.035, hand + 0.02, IDENTITY) is None  # no robot state yet
    moved = HOME + 0.1
    core.on_joint_state(moved)
    assert core.status == TeleopStatus.DISENGAGED
    assert core.on_hand_pose(0.04, hand + 0.02, IDENTITY) is None  # steady frame 1 of 2
    first = core.on_hand_pose(0.05, hand + 0.02, IDENTITY)
    np.testing.assert_allclose(first.joints, moved, atol=1e-6)  # from the measured joints, no jump
