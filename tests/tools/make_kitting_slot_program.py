"""Writes tests/data/kitting_taught_slots.yaml: the tray slots of the simulated kitting cell
as the teach mode saves them when an operator teaches them by gesture, for the kitting
rostest (kitting_node ~slot_program).

It drives motion_apps.teach.TeachSession itself, the class behind the teach_mode node,
with the arm's state solved by pinocchio IK (the UR10e of the cell): for each slot, in a
shuffled order, a waypoint above the tray, then a 'release' with the magnet over the slot
off its YAML centre by a known offset (OFFSETS, up to 8 mm, as a hand-guided arm would be),
each after a 'grip' over the belt (the teach mode releases only what it gripped), then
'save'. The rostest checks that every part is released at the taught point, not the
YAML one. No operator's recording is involved; the gestures' own tests cover those.

Run: .venv/bin/python tests/tools/make_kitting_slot_program.py
"""

import os
import sys

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
for package in ("motion_common", "motion_commander", "motion_apps", "kitting"):
    sys.path.insert(0, os.path.join(ROOT, "src", package))

from kitting.cell import load_cell  # noqa: E402
from motion_apps.teach import TeachSession  # noqa: E402
from motion_common.kinematics import RobotKinematics, pose_to_se3, se3_to_pose  # noqa: E402

OUTPUT = os.path.join(ROOT, "tests", "data", "kitting_taught_slots.yaml")
# m, taught magnet point minus the YAML slot centre, per class.
OFFSETS = {
    "bolt_yellow": (0.006, -0.004),
    "nut_yellow": (-0.005, 0.007),
    "washer_yellow": (0.008, 0.003),
    "bolt_silver": (-0.007, -0.006),
    "nut_silver": (0.004, 0.008),
    "washer_silver": (-0.003, -0.008),
}
ORDER = ("nut_silver", "bolt_yellow", "washer_silver", "nut_yellow", "bolt_silver", "washer_yellow")
TOOL_DOWN = [1.0, 0.0, 0.0, 0.0]  # tool0 z axis pointing down
RELEASE_ABOVE_TRAY = 0.10  # m, magnet face above the tray floor at the release
BELT_PICK = (-0.25,)  # m, x on the belt where the operator grips
START = [0.0, -1.5707963, 1.5707963, -1.5707963, -1.5707963, 0.0]


def main() -> int:
    cell = load_cell()
    kinematics = RobotKinematics(os.path.join(ROOT, "src", "motion_common", "urdf", f"{cell.robot}.urdf"))
    state = {"joints": np.array(START)}

    def move_magnet_to(point):
        target = np.asarray(point, float) + [0.0, 0.0, cell.gripper.tcp_length]  # tool0, z down
        for seed in (state["joints"], START):  # the arm's pose first; the start pose if that is stuck
            result = kinematics.solve_ik(pose_to_se3(target, TOOL_DOWN), seed, max_iterations=500)
            if result.success:
                break
        else:
            raise SystemExit(f"IK failed for the magnet at {point}")
        state["joints"] = np.asarray(result.joints)

    def robot_state():
        position, orientation = se3_to_pose(kinematics.forward(state["joints"]))
        return list(position), list(orientation), list(state["joints"])

    folder, name = os.path.split(OUTPUT)
    session = TeachSession(
        cell.robot, robot_state, programs_dir=folder, program_name=name[: -len(".yaml")], clock=lambda: 0.0
    )
    floor = cell.tray.position[2]
    for class_name in ORDER:
        center = cell.tray.slot_for(class_name).center
        dx, dy = OFFSETS[class_name]
        move_magnet_to([BELT_PICK[0], cell.belt.y, cell.belt.height + 0.02])
        print(session.handle_command("grip"))
        move_magnet_to([center[0], center[1], floor + RELEASE_ABOVE_TRAY + 0.05])
        print(session.handle_command("mark_waypoint"))
        move_magnet_to([center[0] + dx, center[1] + dy, floor + RELEASE_ABOVE_TRAY])
        print(session.handle_command("release"))
    print(session.handle_command("save"))
    return 0


if __name__ == "__main__":
    sys.exit(main())
