"""TeleopCore: from a filtered hand pose to a safe joint command (no ROS here).

The node feeds it hand poses, the robot's measured joints, the clutch button and the
e-stop; it answers with the joint target to stream, or with the status that explains why
nothing is sent. ``tick`` tells the node when to halt the robot (stale input).
"""

import enum
import math
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from motion_common.errors import ParameterError
from motion_common.float_list import float_list
from motion_common.kinematics import RobotKinematics
from motion_common.params import Param, ParamSchema
from motion_common.rotations import is_unit_quaternion, matrix_to_quaternion

from .safety import (
    EngageRamp,
    JointLimitMargin,
    JointStepLimiter,
    SingularityGuard,
    StaleCommandWatchdog,
    WorkspaceFence,
    condition_certainly_below,
    condition_number,
    extreme_singular_values,
)
from .teleop import AutoClutch, TeleopMapper


class TeleopStatus(enum.IntEnum):
    """Status codes published on /motion_commander/status (std_msgs/UInt8 data)."""

    WAITING_FOR_ROBOT = 0  # no /joint_states yet: nothing can be commanded
    DISENGAGED = 1  # clutch open: the robot holds still
    ENGAGED = 2  # commands are streaming at full allowed speed
    JOINT_SPEED_LIMITED = 3  # engaged; this command was slowed to the joint velocity/acceleration limits
    IK_FAILED = 4  # the target is unreachable: the robot holds its last command
    BAD_INPUT = 5  # the hand pose was not finite / not a unit quaternion: ignored
    STALE_INPUT_HALT = 6  # no fresh command within the stale timeout: the robot was halted
    SINGULARITY_SLOWDOWN = 7  # near a singularity: motion toward it is slowed
    SINGULARITY_HALT = 8  # at the singularity threshold: motion toward it is stopped
    WORKSPACE_LIMIT = 9  # the target left the workspace fence (box/floor): clamped to it
    JOINT_LIMIT_MARGIN = 10  # a joint target was clipped to its limit minus the margin
    ESTOP = 11  # e-stop active: robot halted, teleop disengaged until released
    RAMPING = 12  # just engaged or resumed: speed ramping up from zero
    SERVER_LOST = 13  # the robot server stopped answering (or its joint_states went stale): nothing streams


# Engaged and commanding at the allowed speed: the statuses a fast hand moves among many
# times a second (nothing for the operator to act on).
STREAMING_STATUSES = frozenset({TeleopStatus.ENGAGED, TeleopStatus.JOINT_SPEED_LIMITED, TeleopStatus.RAMPING})


class Action(enum.Enum):
    """What tick() asks the node to do."""

    NONE = 0
    HALT = 1  # send STOP: stale input
    DISENGAGE = 2  # hand lost: disengage (and hold)


#: The safety rules' parameters (moveit_servo's set), declared once: the node's schema
#: (motion_commander.config) and ``SafetyConfig`` both take their defaults from here.
SAFETY_PARAMS = ParamSchema(
    [
        Param(
            "joint_speed_scale", 1.0, "fraction", "of the URDF joint velocity limits", low=0.0, high=1.0, low_open=True
        ),
        Param(
            "joint_acceleration",
            200.0,
            "rad/s^2",
            "change of commanded joint velocity; the limiter also brakes to stop at the target (empty: unlimited)",
            kind=float,
            low=0.0,
            high=1000.0,
            low_open=True,
            nullable=True,
        ),
        Param("joint_limit_margin", 0.05, "rad", "kept clear of every URDF joint limit", low=0.0, high=0.5),
        # UR5e: 8 at home, 40 with the wrist (q5) or elbow (q3) ~0.2 rad from straight.
        Param(
            "singularity_slowdown",
            40.0,
            "condition number",
            "motion toward a singularity slows here",
            low=1.0,
            high=1e6,
        ),
        Param(
            "singularity_halt", 80.0, "condition number", "motion toward a singularity stops here", low=1.0, high=1e6
        ),
        Param(
            "workspace_lower", [-1.2, -1.2, 0.0], "m", "tool target box, robot base frame", length=3, low=-10, high=10
        ),
        Param("workspace_upper", [1.2, 1.2, 1.3], "m", "tool target box, robot base frame", length=3, low=-10, high=10),
        Param("floor_z", 0.02, "m", "the tool target never goes below this height", low=-10.0, high=10.0),
        Param("engage_ramp_s", 0.3, "s", "speed ramps from 0 after engage or resume", low=0.0, high=10.0),
        Param(
            "stale_timeout_s",
            0.1,
            "s",
            "without a fresh command before the robot is halted",
            low=0.0,
            high=5.0,
            low_open=True,
        ),
    ]
)


@dataclass
class SafetyConfig:
    """Safety parameters; defaults, units and ranges are those of ``SAFETY_PARAMS``, and a
    value out of range raises ParameterError when the config is built."""

    joint_speed_scale: float = SAFETY_PARAMS.field("joint_speed_scale")
    joint_acceleration: float | None = SAFETY_PARAMS.field("joint_acceleration")
    joint_limit_margin: float = SAFETY_PARAMS.field("joint_limit_margin")
    singularity_slowdown: float = SAFETY_PARAMS.field("singularity_slowdown")
    singularity_halt: float = SAFETY_PARAMS.field("singularity_halt")
    workspace_lower: list = SAFETY_PARAMS.field("workspace_lower")
    workspace_upper: list = SAFETY_PARAMS.field("workspace_upper")
    floor_z: float = SAFETY_PARAMS.field("floor_z")
    engage_ramp_s: float = SAFETY_PARAMS.field("engage_ramp_s")
    stale_timeout_s: float = SAFETY_PARAMS.field("stale_timeout_s")

    def __post_init__(self):
        SAFETY_PARAMS.check_fields(self, "SafetyConfig")
        if self.singularity_slowdown >= self.singularity_halt:
            raise ParameterError(
                f"singularity_slowdown ({self.singularity_slowdown}) must be below "
                f"singularity_halt ({self.singularity_halt})"
            )
        if any(low >= high for low, high in zip(self.workspace_lower, self.workspace_upper)):
            raise ParameterError("workspace_lower must be below workspace_upper on every axis")


@dataclass
class TeleopCommand:
    """A joint target for the driver, with the sensor stamp it came from and the tool
    target it was solved for (position, 3x3 rotation)."""

    stamp: float
    joints: np.ndarray
    target_position: np.ndarray
    target_rotation: np.ndarray
    status: TeleopStatus = TeleopStatus.ENGAGED

    @property
    def target_orientation(self) -> np.ndarray:
        """The target rotation as a quaternion (x, y, z, w); computed when asked for, i.e.
        after the command has left, not on every frame's latency."""
        return matrix_to_quaternion(self.target_rotation)


class TeleopCore:
    """Clutch, mapping, IK and the safety rules for one robot."""

    def __init__(
        self,
        kinematics: RobotKinematics,
        mapper: TeleopMapper,
        clutch: AutoClutch,
        safety: SafetyConfig = None,
        limiter: JointStepLimiter = None,
    ):
        self.kinematics = kinematics
        self.mapper = mapper
        self.clutch = clutch
        self.safety = safety or SafetyConfig()
        s = self.safety
        self.limiter = limiter or JointStepLimiter(
            kinematics.velocity_limits, s.joint_speed_scale, s.joint_acceleration
        )
        self.margin = JointLimitMargin(kinematics.lower, kinematics.upper, s.joint_limit_margin)
        self.singularity = SingularityGuard(s.singularity_slowdown, s.singularity_halt)
        self.fence = WorkspaceFence(s.workspace_lower, s.workspace_upper, s.floor_z)
        self.ramp = EngageRamp(s.engage_ramp_s)
        self.watchdog = StaleCommandWatchdog(s.stale_timeout_s)
        self.status = TeleopStatus.WAITING_FOR_ROBOT
        self.measured_joints: np.ndarray | None = None
        self.estopped = False
        self.server_lost = False
        self._command: np.ndarray | None = None
        # Jacobian condition number and tool pose at _command (None: not known yet); the
        # first is carried from the frame that chose the command, both are filled between
        # frames by prepare_next(), so the next frame does not spend its latency on them.
        self._command_condition: float | None = None
        self._command_pose = None
        # The previous frame's IK solution (the unlimited goal): the next IK starts there.
        self._last_goal: np.ndarray | None = None
        # That IK's first step at its seed (pose, Jacobian), done by prepare_next() ahead of
        # the frame, and the largest and smallest singular values of that Jacobian; None:
        # not done yet, the frame does without.
        self._prepared_seed = None
        self._seed_extremes = None
        self._command_stamp: float | None = None
        self._halted = False

    # -- inputs ----------------------------------------------------------------------------
    def on_joint_state(self, joints) -> None:
        """Record the robot's measured joints (the reference at engage and resume)."""
        self.measured_joints = np.asarray(joints, dtype=float)
        if self.status == TeleopStatus.WAITING_FOR_ROBOT and not self.server_lost:
            self.status = TeleopStatus.DISENGAGED

    def set_estop(self, active: bool) -> bool:
        """Engage or release the e-stop; return True when the node must halt the robot."""
        was = self.estopped
        self.estopped = bool(active)
        if self.estopped:
            self.disengage()
            self.status = TeleopStatus.ESTOP
            return not was
        if was:
            self.clutch.reset()  # a release never re-engages by itself: a fresh engage is needed
            self.status = TeleopStatus.DISENGAGED if self.measured_joints is not None else self.status
        return False

    def set_server_lost(self, lost: bool) -> None:
        """The robot server is lost (True) or back (False). Lost: disengage and stream
        nothing. Back: a fresh engage is needed, from the measured joints at that time, through
        the engage ramp; a stream never resumes by itself."""
        was = self.server_lost
        self.server_lost = bool(lost)
        if self.server_lost:
            self.disengage()
            self.measured_joints = None  # the state from before the outage is not the robot's now
            self.status = TeleopStatus.SERVER_LOST
        elif was:
            self.clutch.reset()
            self.status = TeleopStatus.WAITING_FOR_ROBOT if self.measured_joints is None else TeleopStatus.DISENGAGED

    def disengage(self) -> None:
        """Open the clutch: no more commands until the next engage; the robot holds."""
        self.mapper.disengage()
        self._command = None
        self.watchdog.clear()
        if self.status not in (TeleopStatus.WAITING_FOR_ROBOT, TeleopStatus.ESTOP, TeleopStatus.SERVER_LOST):
            self.status = TeleopStatus.DISENGAGED

    def tick(self, now: float) -> Action:
        """Periodic check (>= 50 Hz): hand lost, or stale commands."""
        if not self.mapper.engaged:
            return Action.NONE
        # Stale input first: when a late tick finds both expired (a busy machine), the
        # robot is halted for staleness now and the clutch opens on the next tick, so the
        # halt never waits behind the hand-lost logic.
        if self.watchdog.expired(now):
            self.watchdog.clear()
            self._halted = True
            self.status = TeleopStatus.STALE_INPUT_HALT
            return Action.HALT
        if self.clutch.hand_lost(now):
            self.disengage()
            return Action.DISENGAGE
        return Action.NONE

    def on_hand_pose(
        self, stamp: float, position, orientation, hands_num: int = 1, now: float | None = None
    ) -> TeleopCommand | None:
        """Process one filtered hand pose; return the command to send, if any."""
        now = stamp if now is None else now
        # Plain floats for the checks: numpy's per-call overhead on 3- and 4-vectors costs
        # more than the checks, and this runs on every frame's latency.
        try:
            p, q = float_list(position), float_list(orientation)
        except (TypeError, ValueError):
            p, q = [], []
        if not (len(p) == 3 and len(q) == 4 and all(map(math.isfinite, p + q)) and is_unit_quaternion(q)):
            self.status = TeleopStatus.BAD_INPUT
            return None
        position, orientation = p, q  # the mapper takes float lists
        if self.measured_joints is None or self.estopped or self.server_lost:
            return None
        if not self.clutch.on_frame(stamp, hands_num):
            if self.mapper.engaged:
                self.disengage()
            return None
        if not self.mapper.engaged:
            # Engage on the measured robot pose so the first target is where the robot is.
            tool_position, tool_orientation = self.kinematics.forward_pose(self.measured_joints)
            self.mapper.engage(position, orientation, tool_position, tool_orientation)
            self._restart(stamp)
        elif self._halted:
            # Resume after a stale halt: the robot stopped where it was, start from there.
            self._restart(stamp)
        return self._command_for(stamp, now, position, orientation)

    # -- internals -------------------------------------------------------------------------
    def _restart(self, stamp: float) -> None:
        self._command = self.measured_joints.copy()
        self._command_condition = None
        self._command_pose = None
        self._last_goal = None
        self._prepared_seed = None
        self._seed_extremes = None
        self._command_stamp = stamp
        self._halted = False
        self.limiter.reset()
        self.ramp.start(stamp)

    def prepare_next(self) -> None:
        """Compute, between frames, what the next frame needs that does not depend on its
        hand pose: the current command's Jacobian condition number and tool pose, and the
        first step of the next IK at its seed. The next frame's command then leaves sooner,
        and is the same as without it. Optional: the next frame computes whatever is still
        missing itself."""
        if self._command is None or not self.mapper.engaged:
            return
        self._condition_at_command()
        self._pose_at_command()
        if self._prepared_seed is None:
            self._prepared_seed = self.kinematics.prepare_seed(self._ik_seed())
            self._seed_extremes = extreme_singular_values(self._prepared_seed.local_jacobian)

    def _ik_seed(self) -> np.ndarray:
        # The previous frame's IK solution: the hand moved little since, so one iteration
        # usually converges, while the command may lag far behind under the speed limits.
        # Both seeds lie on the same continuous branch (each solution started from the one
        # before, back to the measured joints at engage).
        return self._command if self._last_goal is None else self._last_goal

    def _condition_at_command(self) -> float:
        """Jacobian condition number at the current command, computed once per command."""
        if self._command_condition is None:
            self._command_condition = condition_number(self.kinematics.jacobian(self._command))
        return self._command_condition

    def _pose_at_command(self):
        """Tool (position, quaternion) at the current command, computed once per command."""
        if self._command_pose is None:
            self._command_pose = self.kinematics.forward_pose(self._command)
        return self._command_pose

    def _partial_step(self, target_position, target_rotation, position_fraction, rotation_fraction, seed):
        """Joints reaching ``position_fraction`` of the way from the commanded tool position to
        the target's and ``rotation_fraction`` of the way from the commanded orientation to the
        target's, solved from ``seed``; None when this IK fails."""
        start_position, start_orientation = self._pose_at_command()
        # Plain floats and pinocchio's own quaternion: fewer numpy calls on the frame's
        # latency. The target goes in as coefficients: pinocchio's matrix constructor of a
        # quaternion leaks memory on every call.
        if rotation_fraction <= 0.0:
            rotation = pin.Quaternion(start_orientation).matrix()
        else:
            target = pin.Quaternion(matrix_to_quaternion(target_rotation))
            rotation = pin.Quaternion(start_orientation).slerp(rotation_fraction, target).matrix()
        position = np.array(
            [s + position_fraction * (t - s) for s, t in zip(start_position.tolist(), target_position.tolist())]
        )
        result = self.kinematics.solve_ik(pin.SE3(rotation, position), seed)
        return self.margin.apply(result.joints)[0] if result.success else None

    def _limited_step(self, target_position, target_rotation, overshoot, goal, dt, speed):
        """(joints, stop, ratio) for a frame whose IK target ``goal`` is ``overshoot`` (> 1)
        times too far for one step: the tool position first, the orientation with what speed
        is left. ``stop`` and ``ratio`` are what JointStepLimiter.limit() takes as its goal
        and ratio (None: computed there).

        A real hand's orientation is noisy and its rotations are quick, so the wrist joints
        ask for several times their speed limit where the position needs a fraction of it.
        Scaling the whole step by one factor would then make the tool's position trail the
        hand by the wrist's backlog (tens of ms). Instead the step reaches the target
        position (or, where the joints could no longer stop there, the part of the way they
        can: _braked_position_step) with the commanded orientation, plus the largest part of
        the orientation change the limits still allow. When the position alone is too far for one step, the
        tool moves 1/overshoot of the way along the Cartesian path (position and orientation
        alike) rather than cutting straight through joint space, which can swing the tool
        far off the path when the IK solution moved a lot.
        """
        limiter = self.limiter
        held = self._partial_step(target_position, target_rotation, 1.0, 0.0, self._command)
        reach = 1.0  # the fraction of the way to the target position this step takes
        if held is not None:
            held, reach = self._braked_position_step(held, target_position, target_rotation, goal, dt, speed)
        fraction = None if held is None else limiter.fraction_within(self._command, held, goal, dt, speed)
        if fraction is not None:
            joints = held
            if fraction > 0.0:
                seed = np.array([h + fraction * (g - h) for h, g in zip(held.tolist(), goal.tolist())])
                solved = self._partial_step(target_position, target_rotation, reach, fraction, seed)
                joints = held if solved is None else solved
            # Checked for speed alone (and acceleration by limit()): the braking at the goal
            # is already in the position's reach and in the orientation's fraction.
            return joints, joints, limiter.speed_ratio(self._command, joints, dt, speed)
        if held is not None:
            # The position alone is beyond the speed limit: the position step, scaled down.
            return held, held, limiter.speed_ratio(self._command, held, dt, speed)
        fraction = 1.0 / overshoot
        # Seeded the same fraction of the way in joint space: for the small steps of a
        # stream that point already lies within the IK's tolerance of the Cartesian one
        # (the solve then ends at its first check), and otherwise it is the closer start.
        seed = np.array([c + fraction * (g - c) for c, g in zip(self._command.tolist(), goal.tolist())])
        joints = self._partial_step(target_position, target_rotation, fraction, fraction, seed)
        return (goal if joints is None else joints), goal, None

    def _braked_position_step(self, held, target_position, target_rotation, goal, dt, speed):
        """(joints, fraction): ``held`` (the whole position step, fraction 1), or the part of
        it along the same path from which every joint moving toward the goal can still stop
        there.

        A command catching up with a hand that then stops dead must not arrive at a speed the
        joints' acceleration limit cannot take off in time: it would run past the hand's
        turning point. Scaled along the Cartesian path (re-solved, twice at most: the joint
        steps are nearly linear in the fraction), the tool stays on the hand's path."""
        reach, fraction = 1.0, self.limiter.braking_fraction(self._command, held, goal, dt, speed)
        for _ in range(2):
            if fraction >= 1.0:
                break
            braked = self._partial_step(target_position, target_rotation, reach * fraction, 0.0, self._command)
            if braked is None:
                break
            held, reach = braked, reach * fraction
            fraction = self.limiter.braking_fraction(self._command, held, goal, dt, speed)
        return held, reach

    def _command_for(self, stamp, now, position, orientation) -> TeleopCommand | None:
        flags = []
        target_position, target_rotation = self.mapper.target_transform(position, orientation)
        target_position, fenced = self.fence.clamp(target_position)
        if fenced:
            flags.append(TeleopStatus.WORKSPACE_LIMIT)
        result = self.kinematics.solve_ik(
            pin.SE3(target_rotation, target_position), self._ik_seed(), prepared=self._prepared_seed
        )
        if not result.success:
            self.status = TeleopStatus.IK_FAILED
            return None
        joints, clipped = self.margin.apply(result.joints)
        self._last_goal = joints
        seed, seed_extremes = self._prepared_seed, self._seed_extremes
        self._prepared_seed = self._seed_extremes = None
        if clipped:
            flags.append(TeleopStatus.JOINT_LIMIT_MARGIN)
        fraction = self.ramp.fraction(stamp)
        if fraction < 1.0:
            flags.append(TeleopStatus.RAMPING)
        # The singularity guard slows motion only toward a condition number of at least its
        # slowdown threshold: when the IK solution's is certainly below it (bounded from the
        # seed's, a frame away), full speed is allowed without computing it exactly.
        if seed_extremes is not None and condition_certainly_below(
            self.kinematics.local_jacobian(joints), seed.local_jacobian, seed_extremes, self.singularity.slowdown
        ):
            target_condition, singular = None, 1.0
        else:
            target_condition = condition_number(self.kinematics.jacobian(joints))
            singular = self.singularity.speed_fraction(self._condition_at_command(), target_condition)
        if singular < 1.0:
            flags.append(TeleopStatus.SINGULARITY_HALT if singular == 0.0 else TeleopStatus.SINGULARITY_SLOWDOWN)
        speed = min(fraction, singular)
        dt = stamp - self._command_stamp
        goal = joints
        self.limiter.observe_target(goal, dt)
        overshoot = self.limiter.overshoot(self._command, joints, dt, speed)
        # Also when some joint may not move toward its goal at all (overshoot infinite: its
        # target is already coming back): the position step is still taken, and only what
        # cannot move waits, instead of the whole arm standing still and lurching after.
        partial = overshoot > 1.0
        previous = self._command

        def jacobian():  # computed only on the frames where the acceleration limit binds
            return self.kinematics.jacobian(previous)

        if partial:
            joints, stop, ratio = self._limited_step(target_position, target_rotation, overshoot, goal, dt, speed)
            joints, limited = self.limiter.limit(previous, joints, dt, speed, goal=stop, ratio=ratio, jacobian=jacobian)
            limited = True  # the step is short of the target either way
        else:  # the step to the IK target itself: its overshoot is known
            joints, limited = self.limiter.limit(
                previous, joints, dt, speed, goal=goal, ratio=overshoot, jacobian=jacobian
            )
        if limited and not flags:
            flags.append(TeleopStatus.JOINT_SPEED_LIMITED)
        # The condition number at the new command is known when it is the IK target itself;
        # otherwise the next frame computes it (one Jacobian SVD instead of two per frame).
        self._command_condition = None if (partial or limited) else target_condition
        self._command_pose = None
        self._command = joints
        self._command_stamp = stamp
        self.watchdog.commanded(now)
        # The most safety-relevant condition is the one reported.
        self.status = max(flags, key=_severity) if flags else TeleopStatus.ENGAGED
        return TeleopCommand(stamp, joints, target_position, target_rotation, self.status)


_SEVERITY = [
    TeleopStatus.SINGULARITY_HALT,
    TeleopStatus.WORKSPACE_LIMIT,
    TeleopStatus.JOINT_LIMIT_MARGIN,
    TeleopStatus.SINGULARITY_SLOWDOWN,
    TeleopStatus.RAMPING,
    TeleopStatus.JOINT_SPEED_LIMITED,
]


def _severity(status: TeleopStatus) -> int:
    return len(_SEVERITY) - _SEVERITY.index(status)
