"""The per-frame work of the core keeps flat memory: a teleop session runs all day at 110 Hz.

pinocchio.Quaternion(3x3 matrix) leaked 80 bytes per call (pinocchio 4.1.0, eigenpy 3.13.0),
about 55 MB per hour in the core. The process's resident memory is read before and after a
day's worth of frames compressed into a few seconds of the same calls (the leak is in C++,
out of tracemalloc's sight): 150,000 frames would have grown it by 12 MB."""

import numpy as np

from motion_commander.teleop import AutoClutch, TeleopMapper
from motion_commander.teleop_core import SafetyConfig, TeleopCore
from motion_common.kinematics import RobotKinematics, matrix_to_quat

from ..conftest import HOME, UR5E

IDENTITY = [0.0, 0.0, 0.0, 1.0]


def rss_kb() -> int:
    with open("/proc/self/status", encoding="ascii") as status:
        for line in status:
            if line.startswith("VmRSS:"):
                return int(line.split()[1])
    raise RuntimeError("no VmRSS in /proc/self/status")


def test_matrix_to_quaternion_does_not_leak():
    rotation = np.eye(3)
    for _ in range(20_000):  # warm-up: allocator pools and caches settle
        matrix_to_quat(rotation)
    before = rss_kb()
    for _ in range(150_000):
        matrix_to_quat(rotation)
    assert rss_kb() - before < 2_000  # kB; the leak would add ~12,000


def test_a_streaming_core_keeps_flat_memory():
    """The whole per-frame path (mapping, IK, safety, the partial step) over 30,000 frames:
    one leaking call of 80 bytes a frame would add 2,400 kB."""
    core = TeleopCore(RobotKinematics(UR5E), TeleopMapper(1.0), AutoClutch(2, 0.2), SafetyConfig(engage_ramp_s=0.0))
    core.on_joint_state(HOME)

    def frames(start, count):
        for i in range(start, start + count):
            t = 0.009 * i
            hand = [0.05 * np.sin(t), 0.05 * np.cos(0.7 * t), 0.2 + 0.02 * np.sin(1.3 * t)]
            core.on_hand_pose(t, hand, IDENTITY)
            core.prepare_next()

    frames(0, 3_000)
    before = rss_kb()
    frames(3_000, 30_000)
    assert core.mapper.engaged
    growth = rss_kb() - before
    assert growth < 1_200, f"{growth} kB"
