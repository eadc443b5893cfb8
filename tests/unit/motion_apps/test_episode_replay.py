"""Replay of a recorded episode against a stand-in server (no ROS), and the dataset's
summary and picture."""

import json
import os
import signal
import threading
import time

import numpy as np
import pytest

from hw_interface.timed_path import TimedPath, check_timed_path
from motion_apps.episode_replay import EpisodeReplay
from motion_apps.episode_report import (
    dataset_size_bytes,
    format_summary,
    plot_episode,
    summarize_dataset,
    velocity_agreement,
)
from motion_apps.stream_lag import StreamLag


class _Arm:
    """A server whose tool sits at the first three joints (metres) one call behind."""

    def __init__(self, refuse_at=None):
        self.joints = np.zeros(3)
        self.calls = []
        self.refuse_at = refuse_at
        self.sent = 0

    def move_j(self, joints):
        self.calls.append(("move_j", list(joints)))
        self.joints = np.array(joints)

    def set_gripper(self, closed):
        self.calls.append(("gripper", closed))

    def get_pose(self):
        return list(self.joints), [0, 0, 0, 1]

    def set_joints(self, joints):
        if self.sent == self.refuse_at:
            raise RuntimeError("SET_JOINTS refused: STREAM_STEP_TOO_LARGE")
        self.sent += 1
        self.joints = np.array(joints)


def _episode(n=20):
    path = np.stack([np.linspace(0, 0.1, n), np.zeros(n), np.full(n, 0.5)], axis=1).astype(np.float32)
    gripper = (np.arange(n) >= n // 2).astype(np.float32)[:, None]
    states = np.hstack([path, gripper])
    actions = np.hstack([np.vstack([path[1:], path[-1:]]), gripper])
    tools = np.hstack([path, np.tile([0, 0, 0, 1], (n, 1))]).astype(np.float32)
    return states, actions, tools


def _replay(arm):
    now = [0.0]
    return EpisodeReplay(
        arm, 10.0, stream_rate=10.0, clock=lambda: now[0], sleep=lambda s: now.__setitem__(0, now[0] + s)
    )


def test_replay_retraces_the_recorded_tool_and_sets_the_gripper_where_it_changed():
    states, actions, tools = _episode()
    arm = _Arm()
    report = _replay(arm).run(states, actions, tools)
    assert arm.calls[0] == ("move_j", pytest.approx([0.0, 0.0, 0.5]))
    assert arm.calls[1:] == [("gripper", False), ("gripper", True)]
    summary = report.summary()
    assert summary["frames"] == 20 and summary["compared"] == 19 and summary["refused"] == 0
    assert summary["tool_error_mm_max"] == pytest.approx(0.0, abs=1e-3)


def test_replay_streams_targets_between_frames():
    states, actions, tools = _episode(4)
    arm = _Arm()
    sent = []
    arm.set_joints = lambda joints: sent.append(joints[0])
    now = [0.0]
    replay = EpisodeReplay(
        arm, 10.0, stream_rate=40.0, clock=lambda: now[0], sleep=lambda s: now.__setitem__(0, now[0] + s)
    )
    replay.run(states, actions, tools)
    # 4 targets per frame interval (40 Hz over 10 Hz frames), linear between the frames' targets
    step = float(actions[1, 0] - actions[0, 0])
    assert len(sent) == 3 * 4 + 1
    assert sent[:5] == pytest.approx([actions[0, 0] + step * k / 4 for k in range(5)], abs=1e-6)


def test_replay_reports_a_refusal_and_stops():
    states, actions, tools = _episode()
    report = _replay(_Arm(refuse_at=5)).run(states, actions, tools)
    assert report.refused == 1 and report.reason.startswith("frame 5: SET_JOINTS refused")


def test_replay_refuses_episodes_whose_arrays_disagree():
    states, actions, tools = _episode()
    with pytest.raises(ValueError, match="differ in length"):
        _replay(_Arm()).run(states, actions[:-1], tools)


def test_summary_and_picture_of_a_dataset(tmp_path):
    root = tmp_path / "versions" / "000000"
    (root / "data").mkdir(parents=True)
    (root / "data" / "a.parquet").write_bytes(b"x" * 1000)
    os.link(root / "data" / "a.parquet", root / "data" / "same.parquet")  # counted once
    os.symlink(root, tmp_path / "set")
    assert dataset_size_bytes(str(tmp_path / "set")) == 1000
    meta = {"episodes": 2, "frames": 40, "fps": 10, "video_keys": ["observation.images.scene"]}
    records = [{"success": True, "camera_loss_fraction": 0.1}, {"success": False, "camera_loss_fraction": 0.0}]
    summary = summarize_dataset(str(tmp_path / "set"), meta, records)
    assert (summary["episodes"], summary["successes"], summary["size_mb"]) == (2, 1, 0.0)
    text = format_summary(summary)
    assert "2 (1 successful)" in text and "40 at 10 fps" in text and "10.0 %" in text
    json.dumps(summary)
    states, actions, _ = _episode()
    frames = np.random.default_rng(1).uniform(size=(20, 3, 12, 16)).astype(np.float32)
    episode = {"observation.state": states, "action": actions, "observation.images.scene": frames}
    path = plot_episode(str(tmp_path / "episode.png"), episode, 10.0, "test")
    with open(path, "rb") as stream:
        assert stream.read(8) == b"\x89PNG\r\n\x1a\n"


def test_replay_measures_the_tool_when_each_frames_targets_are_sent():
    """With the server's stamped tool poses (tool_at), frame i's tool is the arm's at the
    moment frame i's targets went out, known only once a later pose has come."""
    states, actions, tools = _episode()
    arm = _Arm()
    now = [0.0]
    log = []  # (time, tool) as the server's stamped poses
    set_joints = arm.set_joints

    def sent(joints):
        log.append((now[0], arm.joints.copy()))  # the tool when this target goes out
        set_joints(joints)

    arm.set_joints = sent

    def tool_at(moment):
        after = [tool for t, tool in log if t > moment]
        if not after:
            return None
        return [tool for t, tool in log if t <= moment][-1] if any(t <= moment for t, _ in log) else after[0]

    replay = EpisodeReplay(
        arm, 10.0, stream_rate=10.0, clock=lambda: now[0], sleep=lambda s: now.__setitem__(0, now[0] + s)
    )
    report = replay.run(states, actions, tools, tool_at=tool_at)
    summary = report.summary()
    assert summary["compared"] + summary["unmeasured"] == 19
    assert summary["compared"] == 18  # the last frame's moment has no later pose
    assert summary["tool_error_mm_max"] == pytest.approx(0.0, abs=1e-3)


def test_replay_targets_between_frames_follow_the_recorded_curve():
    """Between two frames the targets follow a curve through the frames' targets, not the
    chord: on a circle sampled at 10 Hz, mid-way targets stay on it within 0.3 mm where the
    chord cuts 3 mm inside."""
    n = 12
    angle = np.linspace(0, 3.3, n)
    path = np.stack([0.3 * np.cos(angle), 0.3 * np.sin(angle), np.zeros(n)], axis=1).astype(np.float32)
    gripper = np.zeros((n, 1), np.float32)
    states = actions = np.hstack([path, gripper])
    tools = np.hstack([path, np.tile([0, 0, 0, 1], (n, 1))]).astype(np.float32)
    arm = _Arm()
    sent = []
    arm.set_joints = lambda joints: sent.append(np.array(joints))
    now = [0.0]
    replay = EpisodeReplay(
        arm, 10.0, stream_rate=20.0, clock=lambda: now[0], sleep=lambda s: now.__setitem__(0, now[0] + s)
    )
    replay.run(states, actions, tools)
    middles = np.array(sent[3:-3:2])  # half-way between frames 1-2 ... 9-10 (the ends go straight on)
    off_circle = 1000 * np.abs(np.linalg.norm(middles[:, :2], axis=1) - 0.3)
    assert off_circle.max() < 0.3
    chord = 1000 * (0.3 - np.linalg.norm((path[:-1, :2] + path[1:, :2]) / 2, axis=1))
    assert chord.min() > 3.0


def test_velocity_agreement_tells_recorded_velocities_from_missing_ones():
    t = np.arange(50) / 10.0
    state = np.column_stack([np.sin(t), np.cos(t), np.zeros_like(t)])  # two joints and the gripper
    velocity = np.column_stack([np.cos(t), -np.sin(t)])
    agreed = velocity_agreement({"observation.state": state, "observation.velocity": velocity}, fps=10.0)
    assert agreed["moving_frames"] == 48 and agreed["gain"] == pytest.approx(1.0, abs=0.01)
    missing = velocity_agreement({"observation.state": state, "observation.velocity": 0 * velocity}, fps=10.0)
    assert missing["gain"] == 0.0


def _lagging_replay(
    states, actions, tools, lag, velocities=None, lead_s=0.0, through_states=False, stall_s=0.0, hold=False
) -> dict:
    """The replay's summary against an arm whose tool follows the targets' path ``lag`` s
    late (linear between the targets sent; ``hold``: each target until the next), on a
    simulated clock (the client held up ``stall_s`` once, see _stalling)."""
    now, sent = [0.0], []
    arm = _Arm()
    arm.set_joints = lambda joints: sent.append((now[0], np.array(joints)))

    def tool_at(moment):
        if not sent or sent[-1][0] < moment:
            return None
        moment -= lag
        k = max([i for i, (stamp, _) in enumerate(sent) if stamp <= moment], default=0)
        (t0, p0), (t1, p1) = sent[k], sent[min(k + 1, len(sent) - 1)]
        return p0 if hold else p0 + (p1 - p0) * ((moment - t0) / (t1 - t0) if t1 > t0 else 0.0)

    clock, sleep = (lambda: now[0]), _stalling(now, stall_s=stall_s)
    run = EpisodeReplay(arm, 10.0, stream_rate=100.0, clock=clock, sleep=sleep, settle_s=0.0, lead_s=lead_s)
    return run.run(
        states, actions, tools, tool_at=tool_at, velocities=velocities, through_states=through_states
    ).summary()


def test_replay_follows_what_the_commands_did_between_frames_with_their_recorded_rate():
    """The core commands at the hand's ~110 Hz; 10 Hz frames of a command path that wiggles
    between them lie on a straight line, and a curve through the frames alone reaches each
    frame with the wrong slope: an arm following the targets 10 ms late is then off by
    10 ms of that slope at every frame. The commands' recorded rate at the frames
    (command_velocity) gives the curve its tangents there."""
    lag, n = 0.01, 14

    def command(t):  # 0.1 m/s with a 4 mm wiggle of 5 Hz: zero at every frame
        return 0.1 * t + 0.004 * np.sin(2 * np.pi * t / 0.2)

    def command_rate(t):
        return 0.1 + 0.004 * 2 * np.pi / 0.2 * np.cos(2 * np.pi * t / 0.2)

    t = np.arange(n) / 10.0

    def xyz(x):
        return np.stack([x, np.zeros_like(x), np.full_like(x, 0.5)], axis=1)

    states = np.hstack([xyz(command(t - lag)), np.zeros((n, 1))])  # the arm, 10 ms behind its commands
    actions = np.hstack([xyz(command(t)), np.zeros((n, 1))])
    rates = np.hstack([command_rate(t)[:, None], np.zeros((n, 2))])
    tools = np.hstack([states[:, :3], np.tile([0, 0, 0, 1], (n, 1))])
    through_frames = _lagging_replay(states, actions, tools, lag)
    with_rates = _lagging_replay(states, actions, tools, lag, velocities=rates)
    assert through_frames["compared"] == with_rates["compared"] >= n - 3
    assert through_frames["tool_error_mm_max"] > 1.0  # 10 ms of the wiggle's slope
    assert with_rates["tool_error_mm_max"] < 0.3


def test_a_lead_sends_the_targets_early_by_an_arms_extra_lag():
    # An arm that trails its stream by 30 ms more than the recorded one (a servoJ's
    # lookahead): given the stream 30 ms early it retraces the recording.
    n, extra = 12, 0.03
    x = 0.02 * np.arange(n, dtype=float) ** 1.5 / n
    path = np.stack([x, np.zeros(n), np.full(n, 0.5)], axis=1)
    states = actions = np.hstack([path, np.zeros((n, 1))])
    tools = np.hstack([path, np.tile([0, 0, 0, 1], (n, 1))])
    assert _lagging_replay(states, actions, tools, extra)["tool_error_mm_max"] > 1.0
    assert _lagging_replay(states, actions, tools, extra, lead_s=extra)["tool_error_mm_max"] < 0.05


def _wiggling_episode(lag, n=14, wiggle=0.004, speed=0.1, hz=7.0):
    """Commands at ``speed`` m/s with a ``wiggle`` of ``hz`` between the 10 Hz frames (the
    hand's motion that the frames' actions do not hold), the arm ``lag`` s behind them:
    states, actions, measured velocities, tools."""

    def command(t):
        return speed * t + wiggle * np.sin(2 * np.pi * hz * t)

    def rate(t):
        return speed + wiggle * 2 * np.pi * hz * np.cos(2 * np.pi * hz * t)

    t = np.arange(n) / 10.0

    def xyz(x):
        return np.stack([x, np.zeros_like(x), np.full_like(x, 0.5)], axis=1)

    states = np.hstack([xyz(command(t - lag)), np.zeros((n, 1))])
    actions = np.hstack([xyz(command(t)), np.zeros((n, 1))])
    velocities = np.hstack([rate(t - lag)[:, None], np.zeros((n, 2))])
    tools = np.hstack([states[:, :3], np.tile([0, 0, 0, 1], (n, 1))])
    return states, actions, velocities, tools


def test_the_recorded_lag_is_the_arms_delay_behind_its_commands():
    states, actions, velocities, _ = _wiggling_episode(0.012)
    assert EpisodeReplay.recorded_lag(states, actions, velocities) == pytest.approx(0.012, abs=0.0015)
    assert EpisodeReplay.recorded_lag(states, states, 0 * velocities) == 0.0  # never moves


def test_replay_through_the_recorded_joints_holds_the_motion_between_frames():
    """The worst frames of the demo's replays through the actions: the commands moved
    between two 10 Hz frames in a way the actions do not hold (a 7 Hz wiggle here), and an
    arm 12 ms behind its targets is off by 12 ms of that motion at a frame. The recorded
    joints at the frames hold it (the arm was there), and the replay that streams them
    ahead by the arm's lag, estimated from the episode, puts the arm there again."""
    lag = 0.012
    states, actions, velocities, tools = _wiggling_episode(lag)
    through_actions = _lagging_replay(states, actions, tools, lag)
    with_command_rate = _lagging_replay(states, actions, tools, lag, velocities=velocities)
    through_states = _lagging_replay(states, actions, tools, lag, velocities=velocities, through_states=True)
    assert through_actions["tool_error_mm_max"] > 1.0
    assert through_states["compared"] >= len(states) - 3
    assert through_states["stream_lead_ms"] == pytest.approx(12.0, abs=1.5)
    assert through_states["tool_error_mm_max"] < 0.2 < with_command_rate["tool_error_mm_max"]
    # An arm that trails its stream 30 ms more than the recorded one: the lead adds to the lag.
    slower = _lagging_replay(states, actions, tools, lag + 0.03, velocities, lead_s=0.03, through_states=True)
    assert slower["tool_error_mm_max"] < 0.2


def test_replay_through_the_recorded_joints_needs_their_velocities():
    states, actions, _, tools = _wiggling_episode(0.01)
    with pytest.raises(ValueError, match="measured velocities"):
        _replay(_Arm()).run(states, actions, tools, through_states=True)


def _live_lag_replay(arm_lag, recorded_lag, live) -> dict:
    """An episode recorded on an arm ``recorded_lag`` s behind its commands, replayed
    through its states on an arm ``arm_lag`` s behind its stream whose joints are sampled
    at 100 Hz (``live``: fed to a StreamLag, as the node does from joint_states)."""
    # 0.5 m/s with a 5 Hz wiggle: the demo's save circle's speeds
    states, actions, velocities, tools = _wiggling_episode(recorded_lag, n=30, wiggle=0.01, speed=0.5, hz=5.0)
    now, sent = [0.0], []
    arm = _Arm()
    arm.set_joints = lambda joints: sent.append((now[0], np.array(joints)))

    def arm_at(moment):  # the targets' path, arm_lag late (linear between the targets)
        moment -= arm_lag
        k = max([i for i, (stamp, _) in enumerate(sent) if stamp <= moment], default=0)
        (t0, p0), (t1, p1) = sent[k], sent[min(k + 1, len(sent) - 1)]
        return p0 + (p1 - p0) * ((moment - t0) / (t1 - t0) if t1 > t0 else 0.0)

    stream_lag = StreamLag(0.0) if live else None
    sampled = [0.0035]  # the next joint sample's moment, off the stream's phase

    def sleep(seconds):
        now[0] += seconds
        while stream_lag is not None and sent and sampled[0] <= now[0]:
            stream_lag.measured(sampled[0], arm_at(sampled[0]))
            sampled[0] += 0.01

    def tool_at(moment):
        return arm_at(moment) if sent and sent[-1][0] >= moment else None

    run = EpisodeReplay(arm, 10.0, stream_rate=100.0, clock=lambda: now[0], sleep=sleep, settle_s=0.0)
    report = run.run(
        states, actions, tools, tool_at=tool_at, velocities=velocities, through_states=True, stream_lag=stream_lag
    )
    after = [error for frame, error in report.errors_by_frame.items() if frame >= 10]
    return dict(report.summary(), max_after_1s=max(after))


def test_replay_runs_ahead_by_the_replaying_arms_measured_lag_not_the_recorded_one():
    """The demo's episode 0 was recorded with its arm 10.5 ms behind its commands, and the
    replaying arm trailed its stream by 12.5 ms: ahead by the recorded lag, the tool was
    2 ms of its motion behind at every fast frame (1-1.5 mm at 0.5-0.6 m/s). Measured from
    the arm's joint samples, the lead becomes the replaying arm's lag within the episode's
    first second."""
    recorded = _live_lag_replay(0.0125, 0.0105, live=False)
    live = _live_lag_replay(0.0125, 0.0105, live=True)
    assert recorded["stream_lead_ms"] == pytest.approx(10.5, abs=0.3) and not recorded["lag_measured"]
    assert live["stream_lead_ms_start"] == pytest.approx(10.5, abs=0.3)
    assert live["lag_measured"] and live["stream_lead_ms"] == pytest.approx(12.5, abs=0.4)
    assert recorded["tool_error_mm_p50"] > 0.4 and recorded["max_after_1s"] > 1.0
    assert live["tool_error_mm_p50"] < 0.2 and live["max_after_1s"] < 0.3


class _NoNumberLag:
    """A lag measurement that says no number (what a NaN joint sample once made of it)."""

    measuring = False

    def sent(self, moment, target):
        pass

    def lag_s(self):
        return float("nan")


def test_a_lag_that_is_no_number_leaves_the_lead_where_it_was():
    states, actions, velocities, tools = _wiggling_episode(0.0105, n=10, wiggle=0.01, speed=0.5, hz=5.0)
    arm, sent = _Arm(), []
    arm.set_joints = sent.append
    run = EpisodeReplay(arm, 10.0, stream_rate=100.0, clock=lambda: 0.0, sleep=lambda s: None, settle_s=0.0)
    report = run.run(states, actions, tools, velocities=velocities, through_states=True, stream_lag=_NoNumberLag())
    summary = report.summary()
    assert summary["compared"] == 9 and summary["stream_lead_ms"] == pytest.approx(10.5, abs=0.3)
    assert len(sent) == 91 and np.all(np.isfinite(sent))


class _PathArm(_Arm):
    """A server whose driver follows a timed path exactly by its own clock: the tool at a
    moment is the path's sample then (linear between the 100 Hz samples); the path starts
    ``delay`` s after the call (the server's stamp)."""

    def __init__(self, now, delay=0.013, supported=True):
        super().__init__()
        self.now, self.delay, self.supported = now, delay, supported
        self.paths = []

    def follow_path(self, times, joints):
        if not self.supported:
            error = RuntimeError("FOLLOW_PATH refused: NOT_SUPPORTED")
            error.result = 17
            raise error
        self.paths.append((np.asarray(times), np.asarray(joints)))
        self.started = self.now[0] + self.delay
        return self.started

    def tool_at(self, moment):
        times, joints = self.paths[-1]
        started = self.started
        return np.array([np.interp(moment - started, times, joints[:, j]) for j in range(joints.shape[1])])


def _stalling(now, stall_at=40, stall_s=0.06):
    """A client's sleep that is held up ``stall_s`` once, at its ``stall_at``-th call."""
    calls = [0]

    def sleep(seconds):
        calls[0] += 1
        now[0] += seconds + (stall_s if calls[0] == stall_at else 0.0)

    return sleep


def test_a_replay_over_a_timed_path_is_not_bent_by_a_stalled_client():
    """Streamed, a client held up 60 ms sends its targets late and the arm that follows them
    is that far behind; sent as one timed path, the driver samples it by its own clock."""
    states, actions, velocities, tools = _wiggling_episode(0.012, n=30, wiggle=0.01, speed=0.5, hz=5.0)
    now = [0.0]
    arm = _PathArm(now)
    gripper = _Arm()
    replay = EpisodeReplay(arm, 10.0, stream_rate=100.0, clock=lambda: now[0], sleep=_stalling(now), settle_s=0.0)

    report = replay.run(
        states,
        actions,
        tools,
        tool_at=arm.tool_at,
        velocities=velocities,
        through_states=True,
        transport="path",
        gripper_client=gripper,
    )
    summary = report.summary()
    assert summary["transport"] == "path" and len(arm.paths) == 1 and summary["compared"] == len(states) - 1
    times, joints = arm.paths[0]
    np.testing.assert_allclose(np.diff(times), 0.01)
    first = int(np.ceil(report.run_up_ms / 10.0 - 1e-9))  # the samples before frame 0: the run-up's
    assert first > 0  # the episode starts in motion
    # the recorded joints at their frames
    np.testing.assert_allclose(joints[first::10][: len(states)], states[:, :3], atol=1e-9)
    assert summary["tool_error_mm_max"] < 0.01
    streamed = _lagging_replay(states, actions, tools, 0.012, velocities, through_states=True, stall_s=0.06, hold=True)
    assert streamed["transport"] == "stream" and streamed["tool_error_mm_max"] > 5.0


def test_a_path_through_the_actions_runs_the_recorded_lag_late_and_sets_the_gripper_on_the_side():
    states, actions, tools = _episode()
    now = [0.0]
    arm, gripper = _PathArm(now), _Arm()
    replay = EpisodeReplay(arm, 10.0, stream_rate=100.0, clock=lambda: now[0], sleep=_stalling(now), settle_s=0.0)
    velocities = np.hstack([np.full((20, 1), 0.1 / 19 * 10), np.zeros((20, 2))])  # one frame a frame
    velocities[-1] = 0.0  # at rest at the last frame, its action
    report = replay.run(
        states,
        actions,
        tools,
        tool_at=arm.tool_at,
        transport="path",
        measured_velocities=velocities,
        gripper_client=gripper,
    )
    assert report.transport == "path" and report.lead_ms == pytest.approx(-100.0, abs=1.0)  # one frame behind
    assert report.summary()["tool_error_mm_max"] < 0.01
    assert gripper.calls == [("gripper", True)] and ("gripper", True) not in arm.calls


def test_a_driver_without_timed_paths_gets_the_stream_and_a_refused_path_is_reported():
    states, actions, tools = _episode()
    now = [0.0]
    arm, lines = _PathArm(now, supported=False), []
    replay = EpisodeReplay(
        arm, 10.0, stream_rate=10.0, clock=lambda: now[0], sleep=_stalling(now, stall_s=0.0), log=lines.append
    )
    report = replay.run(states, actions, tools, tool_at=lambda moment: None, transport="path")
    assert report.transport == "stream" and arm.sent == 20 and "streaming SET_JOINTS instead" in lines[0]
    arm = _PathArm(now)
    arm.follow_path = lambda times, joints: (_ for _ in ()).throw(RuntimeError("FOLLOW_PATH refused: TOO_FAR"))
    report = EpisodeReplay(arm, 10.0, clock=lambda: now[0], sleep=_stalling(now, stall_s=0.0)).run(
        states, actions, tools, tool_at=lambda moment: None, transport="path"
    )
    assert report.refused == 1 and report.reason == "path: FOLLOW_PATH refused: TOO_FAR" and arm.sent == 0
    with pytest.raises(ValueError, match="needs tool_at"):
        replay.run(states, actions, tools, transport="path")


def test_a_refused_path_is_reported_at_once_not_at_the_first_gripper_change():
    states, actions, tools = _episode()  # the gripper closes at frame 10: 1.0 s in
    now, threads = [0.0], []
    arm = _PathArm(now)

    def refuse(times, joints):
        threads.append(threading.current_thread())
        raise RuntimeError("FOLLOW_PATH refused: TOO_FAR")

    def sleep(seconds):  # the path's thread has answered before the replay's time moves on
        threads[0].join(5.0) if threads else None
        now[0] += seconds

    arm.follow_path = refuse
    gripper = _Arm()
    report = EpisodeReplay(arm, 10.0, clock=lambda: now[0], sleep=sleep, settle_s=0.0).run(
        states, actions, tools, tool_at=lambda moment: None, transport="path", gripper_client=gripper
    )
    assert report.refused == 1 and "TOO_FAR" in report.reason
    assert now[0] < 0.05, f"the refusal was reported {now[0]:.2f} s late"
    assert gripper.calls == []


def _path_cut_by_stop(now):
    """(a server whose path runs until a STOP on the side connection cuts it, that side, the
    event set once the path runs)."""
    arm = _PathArm(now)
    running, stopped = threading.Event(), threading.Event()

    def follow(times, joints):
        running.set()
        assert stopped.wait(10.0), "nobody stopped the path"
        raise RuntimeError("FOLLOW_PATH: INTERRUPTED by STOP")

    class Side(_Arm):
        def stop(self):
            self.calls.append(("stop",))
            stopped.set()

    arm.follow_path = follow
    return arm, Side(), running


def test_a_replay_left_while_its_path_runs_stops_the_path():
    states, actions, tools = _episode()
    now = [0.0]
    arm, side, running = _path_cut_by_stop(now)

    def failing_gripper(closed):
        raise RuntimeError("SET_GRIPPER: DRIVER_FAULT")

    def sleep(seconds):
        running.wait(5.0)
        now[0] += seconds

    side.set_gripper = failing_gripper
    report = EpisodeReplay(arm, 10.0, clock=lambda: now[0], sleep=sleep).run(
        states, actions, tools, tool_at=lambda moment: None, transport="path", gripper_client=side
    )
    assert side.calls == [("stop",)]
    assert report.refused == 1 and "DRIVER_FAULT" in report.reason


def test_ctrl_c_while_the_path_runs_stops_it():
    """SIGINT while the replay waits for its path (no gripper change left): the path is
    STOPped. Python 3.11.2's Thread.join, interrupted, marks the thread stopped while it
    still waits for the server, so the replay waits on an Event."""
    states, actions, tools = _episode()
    actions[:, 3] = 0.0  # no gripper change: the replay goes straight to waiting for the path
    now = [0.0]
    arm, side, running = _path_cut_by_stop(now)

    def interrupt():
        running.wait(10.0)
        time.sleep(0.1)  # the replay is waiting for the path by then
        signal.pthread_kill(threading.main_thread().ident, signal.SIGINT)

    # Python's own SIGINT handler (an earlier test in the process may have installed
    # rospy's, which swallows the KeyboardInterrupt).
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    try:
        threading.Thread(target=interrupt, daemon=True).start()
        with pytest.raises(KeyboardInterrupt):
            EpisodeReplay(arm, 10.0, clock=lambda: now[0], sleep=lambda s: now.__setitem__(0, now[0] + s)).run(
                states, actions, tools, tool_at=lambda moment: None, transport="path", gripper_client=side
            )
    finally:
        signal.signal(signal.SIGINT, previous)
    assert side.calls == [("stop",)]


def test_a_stop_that_reaches_the_server_before_the_path_is_sent_again():
    """The replay leaves (its gripper fails at once) while its path is still on the wire: a
    STOP that finds nothing to stop is repeated until the path answers."""
    states, actions, tools = _episode()
    actions[1:, 3] = 1.0  # the gripper closes at frame 1: its moment is 0 with a one-frame lead
    now = [0.0]
    arm = _PathArm(now)
    first_stop, at_server, cut = threading.Event(), threading.Event(), threading.Event()
    stops = []

    def follow(times, joints):  # reaches the server only after the first STOP went out
        assert first_stop.wait(5.0), "no STOP at all"
        at_server.set()
        assert cut.wait(5.0), "no STOP came once the path was at the server"
        raise RuntimeError("FOLLOW_PATH: INTERRUPTED by STOP")

    class Side(_Arm):
        def set_gripper(self, closed):
            raise RuntimeError("SET_GRIPPER: NOT_CONNECTED")

        def stop(self):
            stops.append(at_server.is_set())
            first_stop.set()
            if stops[-1]:
                cut.set()

    arm.follow_path = follow
    side = Side()
    report = EpisodeReplay(
        arm, 10.0, lead_s=0.1, clock=lambda: now[0], sleep=lambda s: now.__setitem__(0, now[0] + s), settle_s=0.0
    ).run(states, actions, tools, tool_at=lambda moment: None, transport="path", gripper_client=side)
    assert stops[0] is False and stops[-1] is True and cut.is_set()
    assert report.refused == 1 and "NOT_CONNECTED" in report.reason


def _moving_episode(n=20, speed=0.65, fps=10.0):
    """An episode recorded while the arm moved: three joints at ``speed`` rad/s from its
    first frame to its last, the gripper open; (states, actions, velocities, tools)."""
    t = np.arange(n) / fps
    joints = np.stack([0.1 + speed * t, -0.5 - 0.5 * speed * t, np.full(n, 0.3)], axis=1)
    states = actions = np.hstack([joints, np.zeros((n, 1))])
    velocities = np.hstack([np.tile([speed, -0.5 * speed, 0.0], (n, 1)), np.zeros((n, 1))])
    tools = np.hstack([joints, np.tile([0, 0, 0, 1], (n, 1))])
    return states, actions, velocities, tools


class _CheckingPathArm(_PathArm):
    """A _PathArm whose driver checks the path as the server does (joint limits, speed 3
    rad/s, acceleration 200 rad/s^2), refusing it whole."""

    def follow_path(self, times, joints):
        names = ["a", "b", "c"]
        check_timed_path(times, joints, names, ([-6.0] * 3, [6.0] * 3), 3.0, 200.0)
        return super().follow_path(times, joints)


def test_an_episode_that_starts_and_ends_in_motion_gets_a_run_up_and_a_run_out():
    """Recording began and ended while the arm moved at 0.65 rad/s. A timed path starts and
    ends at rest: straight onto the first frame's speed it needs 260 rad/s^2 in its first
    10 ms, and the driver refuses it. The replay runs up from rest onto that speed, and out
    to rest, at 10 rad/s^2; the frames are still measured at their moments."""
    states, actions, velocities, tools = _moving_episode()
    now = [0.0]
    arm = _CheckingPathArm(now)
    replay = EpisodeReplay(arm, 10.0, stream_rate=100.0, clock=lambda: now[0], sleep=_stalling(now), settle_s=0.0)
    report = replay.run(
        states, actions, tools, tool_at=arm.tool_at, velocities=velocities, through_states=True, transport="path"
    )
    summary = report.summary()
    assert summary["refused"] == 0, summary["reason"]
    assert summary["compared"] == len(states) - 1 and summary["tool_error_mm_max"] < 0.01
    assert summary["run_up_ms"] == pytest.approx(65.0) and summary["run_out_ms"] == pytest.approx(65.0)
    times, joints = arm.paths[0]
    np.testing.assert_allclose(arm.calls[0][1], joints[0])  # MOVE_J to the run-up's start
    # 0.65 rad/s over 65 ms from rest: 21 mm (rad) before the first frame, and after the last.
    np.testing.assert_allclose(joints[0, 0], states[0, 0] - 0.65 * 0.065 / 2, atol=1e-9)
    np.testing.assert_allclose(joints[-1, 0], states[-1, 0] + 0.65 * 0.065 / 2, atol=1e-9)
    _, accelerations = TimedPath(times, joints).peaks()
    assert accelerations.max() < 40.0  # the cubic between 10 ms samples of a 10 rad/s^2 ramp

    # Without the run-up the same path is refused, with the reason the driver gives.
    strict = EpisodeReplay(arm, 10.0, stream_rate=100.0, clock=lambda: now[0], sleep=_stalling(now), settle_s=0.0)
    strict._ramp = lambda tangent: (0.0, 0.0)
    refused = strict.run(
        states, actions, tools, tool_at=arm.tool_at, velocities=velocities, through_states=True, transport="path"
    )
    assert refused.refused == 1 and "acceleration reaches 260 rad/s^2" in refused.reason


def _refusal(message, result=7):
    """An error as the commander client raises it for a server's refusal (with a result)."""
    error = RuntimeError(message)
    error.result = result
    return error


def test_a_run_up_is_undone_when_the_driver_cannot_follow_a_path():
    """The arm waits at the run-up's start; a server without timed paths gets the stream,
    from the first frame's joints, and a refusal of that move is reported."""
    states, actions, velocities, tools = _moving_episode(n=5)
    now = [0.0]
    arm, lines = _PathArm(now, supported=False), []
    replay = EpisodeReplay(
        arm, 10.0, stream_rate=10.0, clock=lambda: now[0], sleep=_stalling(now, stall_s=0.0), log=lines.append
    )
    run = dict(tool_at=lambda moment: None, velocities=velocities, through_states=True, transport="path")
    report = replay.run(states, actions, tools, **run)
    moves = [call[1] for call in arm.calls if call[0] == "move_j"]
    assert report.transport == "stream" and len(moves) == 2 and report.run_up_ms == report.run_out_ms == 0.0
    np.testing.assert_allclose(moves[0][0], states[0, 0] - 0.65 * 0.065 / 2)
    assert moves[1] == pytest.approx(list(states[0, :3])) and arm.sent == 5

    arm = _PathArm(now, supported=False)
    moved = []

    def second_refused(joints):
        moved.append(joints)
        if len(moved) == 2:
            raise _refusal("MOVE_J refused: WORKSPACE")

    arm.move_j = second_refused
    report = EpisodeReplay(arm, 10.0, clock=lambda: now[0], sleep=_stalling(now, stall_s=0.0), log=lines.append).run(
        states, actions, tools, **run
    )
    assert report.refused == 1 and report.reason == "MOVE_J to the first frame: MOVE_J refused: WORKSPACE"
    assert arm.sent == 0


def test_a_replay_refuses_a_ramp_acceleration_that_is_no_positive_number():
    for bad in (0.0, -1.0, float("nan"), float("inf")):
        with pytest.raises(ValueError, match="ramp_acceleration"):
            EpisodeReplay(_Arm(), 10.0, ramp_acceleration=bad)


def test_a_run_up_start_the_server_refuses_is_reported_and_a_lost_server_raises():
    states, actions, velocities, tools = _moving_episode()
    now = [0.0]
    arm = _PathArm(now)
    run = dict(tool_at=arm.tool_at, velocities=velocities, through_states=True, transport="path")

    def refuse(joints):
        raise _refusal("MOVE_J refused: JOINT_LIMIT")

    arm.move_j = refuse
    replay = EpisodeReplay(arm, 10.0, clock=lambda: now[0], sleep=_stalling(now, stall_s=0.0), settle_s=0.0)
    report = replay.run(states, actions, tools, **run)
    assert report.refused == 1 and arm.paths == []
    assert report.reason == "MOVE_J to the run-up's start, 65 ms before the first frame: MOVE_J refused: JOINT_LIMIT"

    def lost(joints):
        raise ConnectionError("service motion_controller unavailable")

    arm.move_j = lost
    with pytest.raises(ConnectionError):
        replay.run(states, actions, tools, **run)


def test_a_run_up_with_a_lead_and_through_the_actions_keeps_the_frames_at_their_moments():
    """The UR driver's 30 ms lead (the path starts earlier on the curve) and the actions'
    path (the recorded lag late) with a run-up: the driver accepts both, the MOVE_J goes to
    the path's first sample, and every frame's tool is where it was recorded."""
    states, actions, velocities, tools = _moving_episode()
    for lead_s, through_states in ((0.03, True), (0.0, False)):
        now = [0.0]
        arm = _CheckingPathArm(now)
        replay = EpisodeReplay(
            arm, 10.0, clock=lambda now=now: now[0], sleep=_stalling(now, stall_s=0.0), settle_s=0.0, lead_s=lead_s
        )
        report = replay.run(
            states,
            actions,
            tools,
            tool_at=arm.tool_at,
            velocities=velocities if through_states else None,
            through_states=through_states,
            measured_velocities=velocities,
            transport="path",
        )
        summary = report.summary()
        assert summary["refused"] == 0, summary["reason"]
        times, joints = arm.paths[0]
        np.testing.assert_allclose(arm.calls[0][1], joints[0])
        # at rest at the run-out's end: 0.65 rad/s to rest at 10 rad/s^2, 21 mrad past the last frame
        np.testing.assert_allclose(joints[-1, 0], states[-1, 0] + 0.65 * 0.065 / 2, atol=1e-9)
        # the tool at each frame's moment: the recorded one, the lead's distance ahead
        assert summary["compared"] == len(states) - 1
        assert summary["tool_error_mm_max"] == pytest.approx(1000 * 0.65 * lead_s * np.sqrt(1.25), abs=0.01)


def test_the_gripper_closes_when_the_path_reaches_its_frame_whatever_the_lead():
    """The gripper changes at a frame of a moving episode; the path (run-up, then the curve
    ``lead`` ahead) reaches that frame's joints at the run-up plus the frame's time minus the
    lead (for a lead over a frame, before the run-up ends), and the gripper goes out then on
    the side connection."""
    states, actions, velocities, tools = _moving_episode()
    for lead_s, frame in ((0.0, 10), (0.03, 10), (0.25, 1)):
        actions = actions.copy()
        actions[:, 3] = 0.0
        actions[frame:, 3] = 1.0
        now = [0.0]
        arm, side = _PathArm(now), _Arm()
        closed = threading.Event()
        sent = {}

        def follow(times, joints, arm=arm, closed=closed, now=now, sent=sent):
            sent["at"] = now[0]
            started = _PathArm.follow_path(arm, times, joints)
            assert closed.wait(5.0), "the gripper never closed"
            return started

        def close(state, side=side, closed=closed, now=now):
            side.calls.append(("gripper", state, now[0]))
            closed.set()

        arm.follow_path, side.set_gripper = follow, close
        replay = EpisodeReplay(
            arm, 10.0, clock=lambda now=now: now[0], sleep=_stalling(now, stall_s=0.0), settle_s=0.0, lead_s=lead_s
        )
        path = dict(velocities=velocities, through_states=True, transport="path", gripper_client=side)
        report = replay.run(states, actions, tools, tool_at=arm.tool_at, **path)
        assert report.refused == 0, report.reason
        times, joints = arm.paths[0]
        ((_, state, at),) = side.calls
        sample = int(round((at - sent["at"]) / 0.01))
        assert state is True
        np.testing.assert_allclose(joints[sample], states[frame, :3], atol=0.65 * 0.0101)  # within a 10 ms slice


def test_an_end_too_fast_for_a_ramp_is_refused_before_the_arm_moves_and_a_fast_one_ramps_harder():
    states, actions, velocities, tools = _moving_episode(speed=4.0)
    now = [0.0]
    arm = _CheckingPathArm(now)
    replay = EpisodeReplay(arm, 10.0, clock=lambda: now[0], sleep=_stalling(now, stall_s=0.0), settle_s=0.0)
    run = dict(tool_at=arm.tool_at, velocities=velocities, through_states=True, transport="path")
    report = replay.run(states, actions, tools, **run)
    assert report.refused == 1 and arm.calls == [] and arm.paths == []
    assert (
        report.reason.startswith("the first frame's joints move at up to 4.00 rad/s") and "0.160 rad" in report.reason
    )
    # 2.9 rad/s: at 10 rad/s^2 the run-up would reach 0.42 rad back; at 50, 0.084 rad
    states, actions, velocities, tools = _moving_episode(speed=2.9)
    report = replay.run(states, actions, tools, **dict(run, velocities=velocities))
    assert report.refused == 0, report.reason
    assert report.run_up_ms == pytest.approx(1000 * 2.9 / 50.0)
    np.testing.assert_allclose(arm.paths[0][1][0, 0], states[0, 0] - 2.9**2 / 100.0, atol=1e-9)


def test_an_end_at_rest_gets_no_ramp_and_a_value_that_is_no_number_is_refused():
    states, actions, velocities, tools = _moving_episode(speed=0.0005)  # under 1 mrad/s: at rest
    now = [0.0]
    arm = _CheckingPathArm(now)
    replay = EpisodeReplay(arm, 10.0, clock=lambda: now[0], sleep=_stalling(now, stall_s=0.0), settle_s=0.0)
    run = dict(tool_at=arm.tool_at, velocities=velocities, through_states=True, transport="path")
    report = replay.run(states, actions, tools, **run)
    assert report.run_up_ms == report.run_out_ms == 0.0 and len(arm.paths[0][0]) == 10 * (len(states) - 1) + 1
    np.testing.assert_allclose(arm.calls[0][1], states[0, :3])
    velocities = velocities.copy()
    velocities[0, 1] = np.nan
    with pytest.raises(ValueError, match="frame 0's joints or velocities are not finite"):
        replay.run(states, actions, tools, **dict(run, velocities=velocities))
