"""Replays a recorded episode (its actions, or the recorded joint path itself: ``through_states``
below) on a robot behind the commander service and measures
how closely the tool retraces the recorded path (plain Python; the client and the clock are
injected, so it is tested without ROS).

The arm first moves (MOVE_J) to the episode's first recorded joints and gripper state; then
the joint targets are streamed with SET_JOINTS through the server's own checks (step, lag,
workspace, latched stop: the same as teleop's stream), and the gripper is set where the
action changes it. Frame ``i``'s targets go out at ``i / fps``; between two frames the
targets follow a Catmull-Rom curve through the frames' targets at ``stream_rate`` (the core
commanded at the hand's rate, ~110 Hz, along a curved path: a servo following 10 Hz steps
trails by most of a step, and straight lines between the frames cut the corners the arm
took by 1-2 mm at the teach demo's accelerations).

A recorded frame's state is the arm's at the frame's instant, when that frame's command
was the one in force (``stamped_history``). The replay compares like with like: the tool at
the moment frame ``i``'s targets are sent against the tool recorded at frame ``i``. With
``tool_at`` (the moment -> the measured tool position then, from the server's stamped tool
poses; None while not known yet) the tool is taken at exactly that moment; without it, the
server is asked (GET_ROBOT_CARTESIAN_POSITION) just before, which is up to a physics step
and a call off.

Between frames the curve is a cubic Hermite through the frames' targets, with Catmull-Rom's
tangents at the frames or, when given, recorded rates: the core commanded at the hand's ~110
Hz, and what it did between two frames sets the slope at which the arm reaches a frame,
which the frames alone cannot tell. The commands' recorded rate (``command_velocity``)
halves the typical error on the demo's episodes but, the rate between two consecutive
commands carrying the hand's jitter, makes the worst frames worse (docs/benchmarks.md).
An arm that trails its stream by more than the one the episode was recorded on (a UR's
servoJ smooths over its lookahead) is given the stream ``lead_s`` early: the tool is still
measured at each frame's moment.

``through_states``: the recorded joint path itself instead of the actions. The arm that
was recorded trailed its commands by a lag (~11 ms in the simulation), so its state at a
frame is where the commands were that much earlier, and the motion of the commands between
two frames (the hand's ~110 Hz, which 10 Hz actions do not hold) is in the states at the
frames already. The replay streams the cubic through the recorded joints, with the
measured joint velocities as its tangents, ahead by that lag (estimated from the episode:
the actions against the states, ``recorded_lag``) plus ``lead_s``: an arm that trails its
stream as the recorded one did is then at each frame's recorded joints at the frame's
moment, whatever the commands did in between.

``transport="path"``: the same curve, sampled at the stream's steps, goes to the server
ONCE as a timed joint path (FOLLOW_PATH) that the driver samples by its own clock, with
the path's velocity fed forward: client or server stalls can no longer bend it, and the
arm is on the path at the path's times (no servo lag: the recorded joints are sent at
their frames' moments, the actions that recorded lag late). The tool is measured
afterwards at the path's start (the server's stamp) plus the run-up (below) plus each
frame's time. The gripper changes go out meanwhile on ``gripper_client`` (a second
connection: the path blocks its own). A server whose driver cannot follow a path
(NOT_SUPPORTED) gets the stream instead, and ``log`` says so.

A timed path starts and ends at rest, but an episode may begin or end in motion (recording
started or stopped while the arm moved; through the actions with Catmull-Rom's tangents,
whenever the arm moves by the second frame): the path then gets a run-up, from rest at
constant acceleration onto the first frame's velocity, and a run-out, from the last frame's
velocity to rest, past the episode's ends; the arm is MOVE_J'd to the run-up's start, and
the frames are measured at the path's start plus the run-up plus their time. Without them
the driver would have to reach the first frame's speed within one 10 ms sample (0.65 rad/s
takes 260 rad/s^2, over a driver's 200), and it refuses such a path whole. The fastest
joint accelerates at ``ramp_acceleration``, or faster (up to ``RAMP_MOST_ACCELERATION``)
where that would take it more than ``RAMP_DISTANCE`` from the frame; an end that would
still need more than twice that (over 3.2 rad/s: past any driver's speed) is refused before
the arm moves.

The lag that matters is the REPLAYING arm's behind its stream, not the recorded one's: with
``stream_lag`` (a ``StreamLag`` fed by the caller with the arm's stamped joint samples) the
stream starts ahead by the recorded lag plus ``lead_s`` and moves, by at most
``LEAD_CHANGE_S`` a step, to the lag the arm is measured to trail it by. The recorded lags
of the demo's episodes differ by 2 ms (the recording machine's load), and the one 2 ms
below the replaying arm's put the tool 1-1.5 mm behind at every fast frame.
"""

import threading
import time
from dataclasses import dataclass, field

import numpy as np

from hw_interface.path_call import PathCall
from hw_interface.protocol import Result

__all__ = [
    "EpisodeReplay",
    "ReplayReport",
    "LEAD_CHANGE_S",
    "RAMP_ACCELERATION",
    "RAMP_DISTANCE",
    "RAMP_MOST_ACCELERATION",
    "RAMP_REST_SPEED",
]

#: The most the stream's lead moves toward a measured lag in one step (s): 0.1 ms a 10 ms
#: step, the targets' time running 1 % fast or slow while it moves (2 mm of lead in 0.2 s).
LEAD_CHANGE_S = 0.0001
#: rad/s^2: the acceleration of a timed path's run-up and run-out (the module's docstring):
#: 5 % of the drivers' 200, leaving the cubic between samples room; 0.65 rad/s is reached
#: in 65 ms over 0.021 rad.
RAMP_ACCELERATION = 10.0
#: rad: the farthest a run-up or run-out takes the fastest joint from its frame at
#: ``RAMP_ACCELERATION``; a faster end accelerates harder (2.24 rad/s and over)...
RAMP_DISTANCE = 0.05
#: rad/s^2: ... up to this (a quarter of the drivers' 200; the cubic between 10 ms samples
#: of a ramp peaks at under 2.8 times it).
RAMP_MOST_ACCELERATION = 50.0
#: rad/s: an end whose joints all move slower than this is at rest (no ramp: its speed
#: step costs the path's first 10 ms under 0.4 rad/s^2).
RAMP_REST_SPEED = 0.001


@dataclass
class ReplayReport:
    frames: int = 0
    tool_error_mm: list = field(default_factory=list)
    refused: int = 0
    reason: str = ""
    unmeasured: int = 0  # frames whose tool pose never came (tool_at)
    worst_frame: int = -1
    late_ms: dict = field(default_factory=dict)  # frame -> how late its targets went out (ms)
    errors_by_frame: dict = field(default_factory=dict)  # frame -> tool error (mm)
    lead_ms: float = 0.0  # how far ahead of the frames the stream ran at the end (ms)
    lead_ms_start: float = 0.0  # ... at the start (the recorded lag plus lead_s)
    lag_measured: bool = False  # the lead came from the replaying arm's measured lag
    transport: str = "stream"  # what ran: "stream" (SET_JOINTS) or "path" (FOLLOW_PATH)
    run_up_ms: float = 0.0  # a path's run-up from rest onto the first frame's velocity (ms)
    run_out_ms: float = 0.0  # ... and its run-out from the last frame's velocity to rest

    def add(self, frame: int, error_mm: float) -> None:
        if not self.tool_error_mm or error_mm > max(self.tool_error_mm):
            self.worst_frame = frame
        self.tool_error_mm.append(error_mm)
        self.errors_by_frame[frame] = error_mm

    def worst(self, count: int = 5) -> list:
        """[frame, tool error mm, how late its targets went out ms] of the worst frames."""
        ranked = sorted(self.errors_by_frame.items(), key=lambda item: -item[1])[:count]
        return [[frame, round(error, 3), round(self.late_ms.get(frame, 0.0), 1)] for frame, error in ranked]

    def summary(self) -> dict:
        errors = np.asarray(self.tool_error_mm, dtype=float)
        return {
            "frames": self.frames,
            "compared": int(errors.size),
            "tool_error_mm_p50": float(np.percentile(errors, 50)) if errors.size else None,
            "tool_error_mm_p95": float(np.percentile(errors, 95)) if errors.size else None,
            "tool_error_mm_max": float(errors.max()) if errors.size else None,
            "refused": self.refused,
            "reason": self.reason,
            "unmeasured": self.unmeasured,
            "worst_frame": self.worst_frame,
            "worst_frames": self.worst(),
            "late_ms_max": round(max(self.late_ms.values()), 1) if self.late_ms else 0.0,
            "stream_lead_ms": round(self.lead_ms, 2),
            "stream_lead_ms_start": round(self.lead_ms_start, 2),
            "lag_measured": self.lag_measured,
            "transport": self.transport,
            "run_up_ms": round(self.run_up_ms, 1),
            "run_out_ms": round(self.run_out_ms, 1),
        }


class EpisodeReplay:
    """One replay; ``client`` has move_j, set_joints, set_gripper and get_pose; ``lead_s``:
    how early the stream of targets runs (rounded to its steps)."""

    def __init__(
        self,
        client,
        fps: float,
        stream_rate: float = 100.0,
        clock=time.monotonic,
        sleep=time.sleep,
        settle_s: float = 0.5,
        lead_s: float = 0.0,
        log=print,
        ramp_acceleration: float = RAMP_ACCELERATION,
    ):
        self.client = client
        self.period = 1.0 / fps
        self.substeps = max(1, int(round(stream_rate / fps)))
        self.clock = clock
        self.sleep = sleep
        self.settle_s = settle_s
        self.lead_s = float(lead_s)
        self.log = log
        if not 0.0 < ramp_acceleration < np.inf:
            raise ValueError(f"ramp_acceleration {ramp_acceleration!r}: a positive, finite rad/s^2")
        self.ramp_acceleration = float(ramp_acceleration)

    @staticmethod
    def catmull_rom_tangents(targets: np.ndarray) -> np.ndarray:
        """Each frame's tangent (a change per frame) of the Catmull-Rom curve through the
        targets: half the change from the frame before to the frame after; the ends
        extended in a straight line (a straight path stays straight)."""
        tangents = np.empty_like(targets)
        if len(targets) < 2:
            return np.zeros_like(targets)
        tangents[1:-1] = 0.5 * (targets[2:] - targets[:-2])
        tangents[0] = targets[1] - targets[0]
        tangents[-1] = targets[-1] - targets[-2]
        return tangents

    @staticmethod
    def recorded_lag(states: np.ndarray, actions: np.ndarray, velocities: np.ndarray, most_s: float = 0.1) -> float:
        """How long (s) the recorded arm trailed its commands: the least-squares ``lag`` in
        action - state = measured velocity * lag over every joint and frame (0 for an
        episode that never moves; at most ``most_s``)."""
        dof = states.shape[1] - 1
        behind = (np.asarray(actions, dtype=np.float64) - np.asarray(states, dtype=np.float64))[:, :dof].ravel()
        speed = np.asarray(velocities, dtype=np.float64)[:, :dof].ravel()
        power = float(np.dot(speed, speed))
        return min(max(float(np.dot(behind, speed)) / power, 0.0), most_s) if power > 0 else 0.0

    @staticmethod
    def _curve(targets: np.ndarray, tangents: np.ndarray, i: int, u: float) -> np.ndarray:
        """The cubic Hermite curve between frame ``i``'s and ``i + 1``'s targets at ``u`` in
        [0, 1], with the frames' ``tangents`` (a change per frame)."""
        j = min(i + 1, len(targets) - 1)
        u2, u3 = u * u, u * u * u
        return (
            (2 * u3 - 3 * u2 + 1) * targets[i]
            + (u3 - 2 * u2 + u) * tangents[i]
            + (3 * u2 - 2 * u3) * targets[j]
            + (u3 - u2) * tangents[j]
        )

    def run(
        self,
        states: np.ndarray,
        actions: np.ndarray,
        tool_poses: np.ndarray,
        tool_at=None,
        velocities=None,
        through_states: bool = False,
        stream_lag=None,
        transport: str = "stream",
        measured_velocities=None,
        gripper_client=None,
    ) -> ReplayReport:
        """``states`` and ``actions``: joints then gripper per frame; ``tool_poses``: x y z
        qx qy qz qw per frame, as recorded; ``tool_at``: see the module's docstring;
        ``velocities``: joint velocities per frame (rad/s), the curve's tangents at the
        frames (None: Catmull-Rom's); ``through_states``: the curve goes through the
        recorded joints, ahead by the recorded lag (see the module's docstring), and
        ``velocities`` are the measured ones; ``stream_lag``: a ``StreamLag`` the caller
        feeds with the arm's joint samples; the replay tells it each target it sends, and
        (through the states) runs the stream ahead by the lag it measures; ``transport``:
        "stream" or "path" (see the module's docstring; needs ``tool_at``);
        ``measured_velocities``: the recorded joint velocities (the path through the actions
        runs their recorded lag late; default ``velocities`` through the states);
        ``gripper_client``: where the path's gripper changes go (default ``client``)."""
        if transport not in ("stream", "path"):
            raise ValueError(f"transport {transport!r}: stream or path")
        if transport == "path" and tool_at is None:
            raise ValueError("a replay over a timed path measures the tool afterwards: it needs tool_at")
        if not (len(states) == len(actions) == len(tool_poses)) or len(states) == 0:
            raise ValueError(
                f"episode arrays differ in length or are empty: {len(states)}, {len(actions)}, {len(tool_poses)}"
            )
        if through_states and velocities is None:
            raise ValueError("a replay through the recorded joints needs their measured velocities")
        report = ReplayReport(frames=len(actions))
        dof = states.shape[1] - 1
        joints = np.asarray((states if through_states else actions)[:, :dof], dtype=np.float64)
        if velocities is None:
            tangents = self.catmull_rom_tangents(joints)
        else:
            tangents = np.asarray(velocities, dtype=np.float64)[:, :dof] * self.period
            if tangents.shape != joints.shape:
                raise ValueError(f"velocities of shape {np.shape(velocities)} for {joints.shape} joint targets")
        bad = np.flatnonzero(~np.all(np.isfinite(joints), axis=1) | ~np.all(np.isfinite(tangents), axis=1))
        if bad.size:
            raise ValueError(f"frame {bad[0]}'s joints or velocities are not finite")
        steps = (len(actions) - 1) * self.substeps  # the stream's last step: the last frame's targets
        step_s = self.period / self.substeps
        start = np.asarray(states[0, :dof], dtype=np.float64)
        if transport == "path":
            measured = measured_velocities if measured_velocities is not None else velocities
            # The driver feeds the path's velocity forward: the arm is on it at its times,
            # so the recorded joints go at their frames' moments and the actions run the
            # recorded arm's lag behind them late.
            lag = 0.0 if through_states or measured is None else self.recorded_lag(states, actions, measured)
            lead_s = self.lead_s - lag
            report.lead_ms = report.lead_ms_start = 1000.0 * lead_s
            lead = round(lead_s / step_s, 9)
            ramps = []
            for end, tangent in (("first", tangents[0]), ("last", tangents[-1])):
                duration, distance = self._ramp(tangent)
                if distance > 2.0 * RAMP_DISTANCE:
                    report.refused += 1
                    report.reason = (
                        f"the {end} frame's joints move at up to {np.max(np.abs(tangent)) / self.period:.2f} rad/s: "
                        f"a timed path starts and ends at rest, and a ramp to that speed takes {distance:.3f} rad, "
                        f"over {2.0 * RAMP_DISTANCE:g} (--transport stream replays it)"
                    )
                    return report
                ramps.append(duration / step_s)
            report.run_up_ms, report.run_out_ms = (1000.0 * step_s * r for r in ramps)
            # Path sample k is the curve ``first`` steps before frame 0's step: from rest at
            # the run-up's start (or before it) to rest at the run-out's end (or after it).
            first = int(np.ceil(ramps[0] + max(lead, 0.0) - 1e-9))
            last = int(np.ceil(steps + ramps[1] - lead + first - 1e-9))
            targets = [self._target(joints, tangents, k - first, lead, steps, ramps) for k in range(last + 1)]
            start = targets[0]
        where = f"the run-up's start, {report.run_up_ms:.0f} ms before the first frame"
        if not self._move_to(start, where if report.run_up_ms else "the first frame", report):
            return report
        gripper = bool(states[0, dof] > 0.5)
        self.client.set_gripper(gripper)
        self.sleep(self.settle_s)
        if transport == "path":
            try:
                return self._follow(
                    report,
                    targets,
                    step_s,
                    first * step_s,
                    lead_s,
                    actions,
                    tool_poses,
                    tool_at,
                    gripper,
                    gripper_client,
                )
            except Exception as exc:  # noqa: BLE001 - NOT_SUPPORTED falls back, any other refusal is reported
                if getattr(exc, "result", None) != Result.NOT_SUPPORTED:
                    report.refused += 1
                    report.reason = f"path: {exc}"
                    return report
                self.log(f"replay_episode: the server cannot follow a timed path ({exc}): streaming SET_JOINTS instead")
                report.run_up_ms = report.run_out_ms = 0.0
                if not np.array_equal(start, states[0, :dof]):  # the stream begins at the first frame's joints
                    if not self._move_to(states[0, :dof], "the first frame", report):
                        return report
                    self.sleep(self.settle_s)
        lead_s = self.lead_s + (self.recorded_lag(states, actions, velocities) if through_states else 0.0)
        report.lead_ms = report.lead_ms_start = 1000.0 * lead_s
        follow_lag = stream_lag is not None and through_states
        if follow_lag:
            stream_lag.start_s = lead_s
        pending = []  # (frame, moment its targets were sent) not measured yet (tool_at)
        lead = round(lead_s / step_s, 9)  # the stream runs this many steps (or parts of one) ahead of the frames
        reached = 0  # the next frame whose gripper is still to be set
        start = self.clock()
        for step in range(steps + 1):
            if follow_lag:  # toward the replaying arm's measured lag, a little a step
                measured = stream_lag.lag_s()
                if np.isfinite(measured):  # never a lead that is no number: the last one stands
                    lead_s += min(max(measured - lead_s, -LEAD_CHANGE_S), LEAD_CHANGE_S)
                    lead = round(lead_s / step_s, 9)
            i, k = divmod(step, self.substeps)
            if k == 0:  # frame i's moment: its tool is measured
                self._wait_until(start + i * self.period)
                report.late_ms[i] = 1000.0 * (self.clock() - start - i * self.period)
                if i > 0 and tool_at is None:
                    position, _ = self.client.get_pose()
                    report.add(i, 1000.0 * float(np.linalg.norm(np.asarray(position) - tool_poses[i, :3])))
                elif i > 0:
                    pending.append((i, self.clock()))
                    pending = self._measure(pending, tool_at, tool_poses, report)
            else:
                self._wait_until(start + step * step_s)
            target = self._target(joints, tangents, step, lead, steps)
            frame = int(min(step + lead, steps) // self.substeps)
            sent_at = self.clock()
            try:
                self.client.set_joints([float(v) for v in target])
            except Exception as exc:  # noqa: BLE001 - the server's refusal ends the replay, reported
                report.refused += 1
                report.reason = f"frame {i}: {exc}"
                return report
            if stream_lag is not None:
                stream_lag.sent(sent_at, target)
            while reached <= frame:  # each frame the stream has reached: its gripper too
                closed = bool(actions[reached, dof] > 0.5)
                reached += 1
                if closed != gripper:
                    self.client.set_gripper(closed)
                    gripper = closed
        report.lead_ms = 1000.0 * lead_s
        report.lag_measured = bool(follow_lag and stream_lag.measuring)
        deadline = self.clock() + 1.0  # the last moments' tool poses are still on their way
        while pending and self.clock() < deadline:
            self.sleep(0.02)
            pending = self._measure(pending, tool_at, tool_poses, report)
        report.unmeasured = len(pending)
        return report

    def _move_to(self, joints, where: str, report: ReplayReport) -> bool:
        """MOVE_J to ``joints``; a refusal by the server (a run-up's start past a joint
        limit) is the report's reason, and False. Anything else (a lost connection) raises."""
        try:
            self.client.move_j([float(v) for v in joints])
        except Exception as exc:
            if getattr(exc, "result", None) is None:
                raise
            report.refused += 1
            report.reason = f"MOVE_J to {where}: {exc}"
            return False
        return True

    def _ramp(self, tangent: np.ndarray) -> tuple[float, float]:
        """(duration s, distance rad) of the ramp between rest and the velocity ``tangent``
        (a change per frame), for its fastest joint: at ``ramp_acceleration``, or faster
        (to ``RAMP_MOST_ACCELERATION``) to stay within ``RAMP_DISTANCE``; none at rest."""
        speed = float(np.max(np.abs(tangent))) / self.period
        if speed < RAMP_REST_SPEED:
            return 0.0, 0.0
        most = max(self.ramp_acceleration, RAMP_MOST_ACCELERATION)
        acceleration = min(max(self.ramp_acceleration, speed * speed / (2.0 * RAMP_DISTANCE)), most)
        return speed / acceleration, speed * speed / (2.0 * acceleration)

    def _target(self, joints, tangents, step, lead, steps, ramps=None) -> np.ndarray:
        """The curve's target at ``step`` run ``lead`` steps ahead (the first frame's before
        the start; past the last frame, on along its tangent). With ``ramps`` (run-up and
        run-out steps): before the first frame, the run-up at constant acceleration from rest
        onto the first frame's velocity; past the last frame, the run-out to rest."""
        ahead = step + lead
        if ramps is not None and (ahead < 0.0 or ahead > steps):
            before = ahead < 0.0
            ramp = ramps[0] if before else ramps[1]
            velocity = (tangents[0] if before else tangents[-1]) / self.substeps  # a change per step
            if ramp <= 0.0:
                return (joints[0] if before else joints[-1]).copy()
            tau = max(ahead, -ramp) if before else min(ahead - steps, ramp)  # steps from the frame
            sign = 1.0 if before else -1.0
            return (joints[0] if before else joints[-1]) + velocity * (tau + sign * tau * tau / (2.0 * ramp))
        ahead = min(max(ahead, 0.0), steps)
        frame = int(ahead // self.substeps)
        part = (ahead - frame * self.substeps) / self.substeps
        target = self._curve(joints, tangents, frame, part) if part else joints[frame]
        if step + lead > steps:
            target = joints[-1] + tangents[-1] * ((step + lead - steps) / self.substeps)
        return target

    def _follow(self, report, targets, step_s, offset_s, lead_s, actions, tool_poses, tool_at, gripper, gripper_client):
        """The curve as one timed path whose frame 0 is ``offset_s`` after its start (its
        run-up); the gripper set meanwhile where the actions change it (at their frame's
        moment counted from when the path was sent, on the replay's clock: the path's start
        comes later by the service call's latency); then each frame's tool at the path's
        start plus ``offset_s`` plus the frame's time. Leaving early (an error, Ctrl-C)
        STOPs the path."""
        dof = len(targets[0])
        times = [step * step_s for step in range(len(targets))]
        call = PathCall(self.client.follow_path, times, [[float(v) for v in t] for t in targets])
        changes = []
        for frame in range(1, len(actions)):
            closed = bool(actions[frame, dof] > 0.5)
            if closed != gripper:
                changes.append((max(offset_s + frame * self.period - lead_s, 0.0), closed))
                gripper = closed
        side = gripper_client or self.client
        try:
            sent_at = self.clock()
            call.start()
            for moment, closed in changes:
                self._wait_until(sent_at + moment, call.finished)
                if call.failed:  # refused or cut short: the gripper stays as it is
                    break
                side.set_gripper(closed)
            call.finished.wait()
        except BaseException:
            # Leaving while the arm follows the path (a gripper error, Ctrl-C): the server
            # would follow it to its end for nobody. STOP it, on the side connection.
            call.stop_until_answered(side.stop, lambda message: self.log(f"replay_episode: {message}"))
            if not call.finished.is_set():
                self.log(f"replay_episode: {call.describe()}")
            raise
        started = call.result()
        report.transport = "path"
        pending = [(i, started + offset_s + i * self.period) for i in range(1, len(actions))]
        deadline = self.clock() + 1.0  # the last moments' tool poses are still on their way
        pending = self._measure(pending, tool_at, tool_poses, report)
        while pending and self.clock() < deadline:
            self.sleep(0.02)
            pending = self._measure(pending, tool_at, tool_poses, report)
        report.unmeasured = len(pending)
        return report

    @staticmethod
    def _measure(pending: list, tool_at, tool_poses: np.ndarray, report: ReplayReport) -> list:
        """Errors of the pending frames whose moment's tool is known; the rest, still pending."""
        waiting = []
        for i, moment in pending:
            position = tool_at(moment)
            if position is None:
                waiting.append((i, moment))
            else:
                report.add(i, 1000.0 * float(np.linalg.norm(np.asarray(position) - tool_poses[i, :3])))
        return waiting

    def _wait_until(self, moment: float, finished: threading.Event | None = None) -> None:
        """Sleep until ``moment`` (the replay's clock); with ``finished``, in slices of at
        most 10 ms, returning once it is set."""
        wait = moment - self.clock()
        if finished is None:
            if wait > 0:
                self.sleep(wait)
            return
        while wait > 0 and not finished.is_set():
            self.sleep(min(wait, 0.01))
            wait = moment - self.clock()
