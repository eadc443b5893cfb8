"""Checks a program before the arm moves: every waypoint and every segment, with reasons.

``ProgramChecker(urdf_path, robot_name, scene=..., params=...).check(program, start_joints)``
returns a ``CheckReport`` (``ok``, ``issues`` naming the waypoint index and name, and the
joints each waypoint will be reached with). It refuses:

* a program taught on another robot (its ``robot`` differs from ``robot_name``), or with a
  joint count or tool frame this URDF does not have;
* a waypoint whose recorded joints lie outside the URDF limits, or whose pose pinocchio's
  IK (motion_common.kinematics, seeded with the waypoint's recorded joints) cannot reach;
* a tool position outside the workspace fence (a box, ``fence_min`` / ``fence_max``);
* a segment that collides with a STATIC body of the scene (fixed URDF or zero-mass box, as
  hw_interface.sim_driver.entry_is_fixed decides; movable parts are what the gripper
  picks and are not obstacles): the MoveJ from ``start_joints`` to the first waypoint is
  sampled in joint space, the MoveL segments between the others along the straight line
  (IK at each sample, seeded from the previous, as the simulation driver does), and at
  each sample the robot is posed in a pybullet DIRECT client of its own and
  getClosestPoints against each static body within ``collision_margin``. Link/body pairs
  already touching at the URDF's zero pose (the base on the floor) are not collisions.

Not checked: self-collision, a part carried by the gripper, and the controller's own
MoveL path on a real UR (it interpolates itself, close to the line checked here).
"""

import math
from dataclasses import dataclass, field

import numpy as np

from hw_interface.sim_driver import entry_is_fixed, load_scene
from motion_common.errors import ParameterError, RobotModelError
from motion_common.kinematics import RobotKinematics, pose_to_se3, slerp
from motion_common.params import Param, ParamSchema, read_yaml_file
from motion_common.quiet_pybullet import bullet_client, pybullet

CHECK_SCHEMA = ParamSchema(
    [
        Param("fence_min", [-1.0, -1.0, 0.01], "m", "workspace fence, lower corner of the tool position", length=3),
        Param("fence_max", [1.0, 1.0, 1.2], "m", "workspace fence, upper corner", length=3),
        Param(
            "collision_margin", 0.005, "m", "a link closer than this to a static scene body collides", low=0.0, high=0.2
        ),
        Param("sample_step", 0.01, "m", "MoveL segments are checked every this much tool travel", low=0.001, high=0.2),
        Param("sample_angle", 0.05, "rad", "... and every this much tool rotation", low=0.001, high=1.0),
        Param(
            "joint_step",
            0.05,
            "rad",
            "the MoveJ to the first waypoint is checked every this much joint travel",
            low=0.001,
            high=1.0,
        ),
        Param(
            "ik_position_tolerance", 0.001, "m", "IK residual accepted as reachable", low=0.0, high=0.05, low_open=True
        ),
        Param(
            "ik_rotation_tolerance", 0.01, "rad", "IK residual accepted as reachable", low=0.0, high=0.5, low_open=True
        ),
    ],
    ignore=("config_file",),
)

#: Largest joint change (rad) between two samples 1 cm apart on a MoveL: more means the
#: line passes a singularity or flips the arm's configuration.
MAX_SAMPLE_JUMP = 0.5


def check_params(values: dict | None, source: str) -> dict:
    """Checked checker parameters; ParameterError names ``source`` and the key."""
    params = CHECK_SCHEMA.validate(values, source)
    if any(lo >= hi for lo, hi in zip(params["fence_min"], params["fence_max"])):
        raise ParameterError(
            f"{source}: fence_min {params['fence_min']} must be below fence_max {params['fence_max']} on every axis"
        )
    return params


def load_check_params(path: str) -> dict:
    """Read and check a program_check.yaml."""
    return check_params(read_yaml_file(path), path)


def load_scene_file(path: str) -> list:
    """The body list of a scene YAML (hw_interface/config/scenes/*.yaml: a ``scene:`` key)."""
    data = read_yaml_file(path)
    spec = data.get("scene") if isinstance(data, dict) else data
    if not isinstance(spec, list) or not all(isinstance(entry, dict) for entry in spec):
        raise ParameterError(
            f"{path}: a scene file holds 'scene:' with a list of bodies (see "
            "hw_interface/config/scenes/table_parts.yaml)"
        )
    return spec


@dataclass
class Issue:
    """One reason to refuse: the waypoint (index, name; None for the program) and why."""

    index: int | None
    name: str
    reason: str

    def __str__(self) -> str:
        return (f"waypoint {self.index} {self.name!r}: " if self.index is not None else "program: ") + self.reason


@dataclass
class CheckReport:
    """The outcome of a check: refused when ``issues`` is not empty."""

    robot: str
    issues: list[Issue] = field(default_factory=list)
    joints: list[list] = field(default_factory=list)  # per waypoint, the IK solution (rad)
    samples: int = 0
    start_checked: bool = False

    @property
    def ok(self) -> bool:
        return not self.issues

    def text(self) -> str:
        if self.ok:
            start = "" if self.start_checked else " (the MoveJ from the robot's current pose was not checked: unknown)"
            return f"check passed: {len(self.joints)} waypoints, {self.samples} poses sampled{start}"
        return "check REFUSED the program:\n" + "\n".join(f"  - {issue}" for issue in self.issues)


class ProgramChecker:
    """Checks programs for one robot (URDF) in one scene; see the module doc."""

    def __init__(self, urdf_path: str, robot_name: str, scene: list | None = None, params: dict | None = None):
        self.urdf_path = urdf_path
        self.robot_name = robot_name
        self.params = check_params(params, "program check parameters")
        self.scene_spec = list(scene or [])
        self._client = None

    # -- pybullet world -------------------------------------------------------------------
    def _world(self, kinematics: RobotKinematics):
        if self._client is not None:
            return
        client = bullet_client(pybullet.DIRECT)
        self._client = client
        self._robot = client.loadURDF(self.urdf_path, useFixedBase=True)
        by_name, self._link_names = {}, {-1: "base"}
        # Links that cannot move (the base, and links fixed to it before the first joint):
        # their contacts (the base standing on the floor or a table) never count. Every
        # moving link is checked, whatever it touches at any particular pose.
        self._static_links = {-1}
        for index in range(client.getNumJoints(self._robot)):
            info = client.getJointInfo(self._robot, index)
            by_name[info[1].decode()] = index
            self._link_names[index] = info[12].decode()
            if info[2] == pybullet.JOINT_FIXED and info[16] in self._static_links:
                self._static_links.add(index)
        self._joint_indices = [by_name[name] for name in kinematics.joint_names]
        static = [
            entry
            for entry in self.scene_spec
            if entry_is_fixed(self.scene_spec, entry.get("name", f"body{self.scene_spec.index(entry)}"))
        ]
        self._bodies = load_scene(client, static)

    def _contacts(self, joints):
        client = self._client
        for index, value in zip(self._joint_indices, joints):
            client.resetJointState(self._robot, index, float(value))
        client.performCollisionDetection()
        found = []
        margin = self.params["collision_margin"]
        for name, body in self._bodies.items():
            for point in client.getClosestPoints(self._robot, body, margin):
                if point[8] < margin and (point[3], name) not in found:
                    found.append((point[3], name))
        return found

    def _collisions(self, joints):
        return [
            (self._link_names.get(link, str(link)), body)
            for link, body in self._contacts(joints)
            if link not in self._static_links
        ]

    def close(self):
        """Disconnect the pybullet client."""
        if self._client is not None:
            self._client.disconnect()
            self._client = None

    # -- the check ------------------------------------------------------------------------
    def check(self, program, start_joints=None) -> CheckReport:
        """Check ``program``; ``start_joints`` (rad) is where the robot is now (the MoveJ to
        the first waypoint is checked from there; None skips that segment)."""
        report = CheckReport(robot=self.robot_name)
        if program.robot != self.robot_name:
            report.issues.append(
                Issue(
                    None,
                    "",
                    f"taught on robot {program.robot!r}, this robot is "
                    f"{self.robot_name!r}: refusing to replay it on another robot",
                )
            )
            return report
        try:
            kin = RobotKinematics(self.urdf_path, program.tool_frame)
        except RobotModelError as exc:
            report.issues.append(Issue(None, "", f"tool frame {program.tool_frame!r}: {exc}"))
            return report
        wrong = [i for i, w in enumerate(program.waypoints) if len(w.joints) != kin.dof]
        if wrong:
            report.issues.append(
                Issue(
                    None, "", f"waypoints {wrong} have the wrong joint count for {self.robot_name} ({kin.dof} joints)"
                )
            )
            return report
        self._world(kin)
        p = self.params
        lower, upper = np.array(p["fence_min"]), np.array(p["fence_max"])

        def outside(position):
            return not (np.all(position >= lower) and np.all(position <= upper))

        # Each waypoint on its own: limits, IK, fence, collisions.
        for index, wp in enumerate(program.waypoints):
            seed = np.asarray(wp.joints, dtype=float)
            if not kin.within_limits(seed):
                bad = [kin.joint_names[i] for i in np.flatnonzero((seed < kin.lower) | (seed > kin.upper))]
                report.issues.append(Issue(index, wp.name, f"recorded joints {bad} outside their limits"))
            solution = kin.solve_ik(
                pose_to_se3(wp.position, wp.orientation),
                seed,
                max_iterations=200,
                position_tolerance=p["ik_position_tolerance"],
                rotation_tolerance=p["ik_rotation_tolerance"],
            )
            report.joints.append(solution.joints.tolist())
            if not solution.success:
                report.issues.append(
                    Issue(
                        index,
                        wp.name,
                        (
                            f"unreachable: IK from the recorded joints ends {solution.position_error * 1000:.1f} mm / "
                            f"{solution.rotation_error:.3f} rad from the pose"
                        ),
                    )
                )
                continue
            if outside(np.asarray(wp.position)):
                report.issues.append(
                    Issue(
                        index,
                        wp.name,
                        (
                            f"tool position {np.round(wp.position, 3).tolist()} m is outside the workspace fence "
                            f"{p['fence_min']}..{p['fence_max']}"
                        ),
                    )
                )
            hits = self._collisions(solution.joints)
            report.samples += 1
            if hits:
                report.issues.append(Issue(index, wp.name, "in collision: " + _hits_text(hits)))
        if not report.ok:
            return report
        # Segments: MoveJ from the start pose to waypoint 0, then MoveL between waypoints.
        if start_joints is not None:
            report.start_checked = True
            start = np.asarray(start_joints, dtype=float)
            goal = np.asarray(report.joints[0])
            count = max(1, int(math.ceil(np.max(np.abs(goal - start)) / p["joint_step"])))
            for k in range(1, count + 1):
                q = start + (goal - start) * k / count
                report.samples += 1
                issue = self._sample_issue(kin, q, outside)
                if issue:
                    report.issues.append(
                        Issue(0, program.waypoints[0].name, f"MoveJ from the current pose, at {k / count:.0%}: {issue}")
                    )
                    break
        for index in range(1, len(program.waypoints)):
            issue = self._movel_issue(
                kin, program.waypoints[index - 1], program.waypoints[index], report.joints[index - 1], report, outside
            )
            if issue:
                report.issues.append(
                    Issue(
                        index,
                        program.waypoints[index].name,
                        f"MoveL from {program.waypoints[index - 1].name!r}: {issue}",
                    )
                )
        return report

    def _sample_issue(self, kin, joints, outside) -> str:
        position, _ = kin.forward_pose(joints)
        if outside(position):
            return f"tool at {np.round(position, 3).tolist()} m leaves the workspace fence"
        hits = self._collisions(joints)
        return "collision: " + _hits_text(hits) if hits else ""

    def _movel_issue(self, kin, a, b, seed, report, outside) -> str:
        p = self.params
        pa, pb = np.asarray(a.position, dtype=float), np.asarray(b.position, dtype=float)
        dot = min(1.0, abs(float(np.dot(a.orientation, b.orientation))))
        angle = 2.0 * math.acos(dot)
        count = max(1, int(math.ceil(max(np.linalg.norm(pb - pa) / p["sample_step"], angle / p["sample_angle"]))))
        q = np.asarray(seed, dtype=float)
        for k in range(1, count + 1):
            fraction = k / count
            target = pose_to_se3(pa + (pb - pa) * fraction, slerp(a.orientation, b.orientation, fraction))
            solution = kin.solve_ik(
                target,
                q,
                max_iterations=200,
                position_tolerance=p["ik_position_tolerance"],
                rotation_tolerance=p["ik_rotation_tolerance"],
            )
            if not solution.success:
                return f"the line is unreachable at {fraction:.0%} (IK error {solution.position_error * 1000:.1f} mm)"
            jump = float(np.max(np.abs(solution.joints - q)))
            if jump > MAX_SAMPLE_JUMP:
                return (
                    f"the line passes a singularity or flips the arm at {fraction:.0%} "
                    f"(joints jump {jump:.2f} rad between samples)"
                )
            q = solution.joints
            report.samples += 1
            issue = self._sample_issue(kin, q, outside)
            if issue:
                return f"at {fraction:.0%}: {issue}"
        return ""


def _hits_text(hits) -> str:
    return ", ".join(f"link {link} touches {body}" for link, body in hits)
