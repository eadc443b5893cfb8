"""Replays a recorded episode's actions on a robot behind the commander service and measures
how closely the tool retraces the recorded path (plain Python; the client and the clock are
injected, so it is tested without ROS).

The arm first moves (MOVE_J) to the episode's first recorded joints and gripper state; then
the joint targets are streamed with SET_JOINTS through the server's own checks (step, lag,
workspace, latched stop: the same as teleop's stream), and the gripper is set where the
action changes it. Frame ``i``'s targets go out at ``i / fps``; between two frames the
targets move linearly from one frame's to the next at ``stream_rate`` (the core commanded at
the hand's rate, ~110 Hz, and a servo following 10 Hz steps would trail by most of a step).
Just before frame ``i``'s targets are sent, the measured tool is compared with the tool
recorded at frame ``i``: both have followed the same targets up to then.
"""

import time
from dataclasses import dataclass, field

import numpy as np

__all__ = ["EpisodeReplay", "ReplayReport"]


@dataclass
class ReplayReport:
    frames: int = 0
    tool_error_mm: list = field(default_factory=list)
    refused: int = 0
    reason: str = ""

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
        }


class EpisodeReplay:
    """One replay; ``client`` has move_j, set_joints, set_gripper and get_pose."""

    def __init__(
        self,
        client,
        fps: float,
        stream_rate: float = 100.0,
        clock=time.monotonic,
        sleep=time.sleep,
        settle_s: float = 0.5,
    ):
        self.client = client
        self.period = 1.0 / fps
        self.substeps = max(1, int(round(stream_rate / fps)))
        self.clock = clock
        self.sleep = sleep
        self.settle_s = settle_s

    def run(self, states: np.ndarray, actions: np.ndarray, tool_poses: np.ndarray) -> ReplayReport:
        """``states`` and ``actions``: joints then gripper per frame; ``tool_poses``: x y z
        qx qy qz qw per frame, as recorded."""
        if not (len(states) == len(actions) == len(tool_poses)) or len(states) == 0:
            raise ValueError(
                f"episode arrays differ in length or are empty: {len(states)}, {len(actions)}, {len(tool_poses)}"
            )
        report = ReplayReport(frames=len(actions))
        dof = states.shape[1] - 1
        self.client.move_j([float(v) for v in states[0, :dof]])
        gripper = bool(states[0, dof] > 0.5)
        self.client.set_gripper(gripper)
        self.sleep(self.settle_s)
        start = self.clock()
        for i, action in enumerate(actions):
            self._wait_until(start + i * self.period)
            if i > 0:
                position, _ = self.client.get_pose()
                report.tool_error_mm.append(1000.0 * float(np.linalg.norm(np.asarray(position) - tool_poses[i, :3])))
            following = actions[i + 1, :dof] if i + 1 < len(actions) else action[:dof]
            for k in range(self.substeps if i + 1 < len(actions) else 1):
                if k:
                    self._wait_until(start + (i + k / self.substeps) * self.period)
                target = action[:dof] + (following - action[:dof]) * (k / self.substeps)
                try:
                    self.client.set_joints([float(v) for v in target])
                except Exception as exc:  # noqa: BLE001 - the server's refusal ends the replay, reported
                    report.refused += 1
                    report.reason = f"frame {i}: {exc}"
                    return report
                if k == 0:
                    closed = bool(action[dof] > 0.5)
                    if closed != gripper:
                        self.client.set_gripper(closed)
                        gripper = closed
        return report

    def _wait_until(self, moment: float) -> None:
        wait = moment - self.clock()
        if wait > 0:
            self.sleep(wait)
