"""pybullet simulation driver: the robot's URDF in a physics world, stepped in real time
in its own thread, under position control (DIRECT mode by default, GUI on request)."""

import os
import threading
import time

import numpy as np

from motion_common.kinematics import RobotKinematics
from motion_common.params import Param, ParamSchema
from motion_common.quiet_pybullet import bullet_client, pybullet

from .errors import HwInterfaceError
from .protocol import Result
from .robot_hw import DriverStatus, RobotDriver, SimulatedScene, UrdfModelMixin
from .stream_follower import STREAM_ACCELERATION_PARAM, StreamFollower
from .timed_path import TimedPath
from .timed_targets import TimedTargets
from .trajectory import JointPath, joint_move_duration, trapezoid_duration

# Fraction of the URDF velocity limits the simulated motors are capped at (see login()): the
# simulated arm's top joint speed. MoveJ/MoveL plan at speed_scale (0.5) of the limits, below it.
MOTOR_SPEED_FRACTION = 0.94

# How far (s) the physics thread may fall behind its schedule and still run every step it
# owes (each with the streamed target in force at its scheduled time, TimedTargets); further
# behind it drops the time (counted in ``overruns``) instead of racing. At 0.2 s a burst is
# ~100 steps of ~0.15 ms; the 20 ms this was before dropped time 0-2 times in a 25 s replay
# with one core of two kept busy, and the replay's arm then skipped 25 ms of its path (4.75 mm).
CATCH_UP_S = 0.2


def load_scene(client, spec) -> dict:
    """Create the scene's extra bodies; return {name: body id}.

    Each entry is a dict with ``name`` and either ``urdf`` (a path, absolute or inside
    pybullet_data) or ``box`` (half extents in m), plus ``position`` (m), ``rpy`` (rad),
    ``mass`` (kg, 0 = fixed) and ``color`` (rgba) for boxes.
    """
    import pybullet_data

    bodies = {}
    for index, entry in enumerate(spec):
        name = entry.get("name", f"body{index}")
        position = entry.get("position", [0.0, 0.0, 0.0])
        orientation = pybullet.getQuaternionFromEuler(entry.get("rpy", [0.0, 0.0, 0.0]))
        if "urdf" in entry:
            path = entry["urdf"]
            if not os.path.isabs(path):
                path = os.path.join(pybullet_data.getDataPath(), path)
            if not os.path.isfile(path):
                raise HwInterfaceError(f"scene body {name!r}: URDF {entry['urdf']!r} not found")
            bodies[name] = client.loadURDF(path, position, orientation, useFixedBase=bool(entry.get("fixed", False)))
        elif "box" in entry:
            half = [float(v) for v in entry["box"]]
            shape = client.createCollisionShape(pybullet.GEOM_BOX, halfExtents=half)
            visual = client.createVisualShape(
                pybullet.GEOM_BOX, halfExtents=half, rgbaColor=entry.get("color", [0.8, 0.6, 0.2, 1.0])
            )
            bodies[name] = client.createMultiBody(float(entry.get("mass", 0.1)), shape, visual, position, orientation)
        else:
            raise HwInterfaceError(f"scene body {name!r} needs 'urdf' or 'box'")
    return bodies


def entry_is_fixed(spec, name) -> bool:
    """True when scene body ``name`` is static (fixed URDF or zero mass): never gripped."""
    for index, entry in enumerate(spec):
        if entry.get("name", f"body{index}") == name:
            return bool(entry.get("fixed", False)) or ("box" in entry and float(entry.get("mass", 0.1)) == 0.0)
    return False


class PybulletSimDriver(UrdfModelMixin, SimulatedScene, RobotDriver):
    """Simulated arm. ``login("sim://")`` starts the physics; ``disconnect()`` ends it.

    Parameters: ``urdf_path`` of the robot, ``tool_frame`` (a link name), ``gui``,
    ``time_step`` (s), ``initial_joints`` (rad), ``speed_scale`` (fraction of the URDF
    velocity limits MoveJ/MoveL use), ``max_acceleration`` (rad/s^2),
    ``cartesian_speed`` (m/s, MoveL), ``real_time`` (False steps as fast as possible),
    ``scene`` (list of extra bodies, see load_scene), ``gripper_output`` (the digital
    output that switches the suction gripper), ``gripper_reach`` (m from the tool frame
    within which a body is picked), ``goal_tolerance`` (rad: a MoveJ/MoveL succeeds only
    once every MEASURED joint is this close to the goal), ``settle_timeout`` (s after the
    path's end to get there; otherwise the move fails, never a silent SUCCESS).

    stop() from another thread cuts a blocking move short: it answers INTERRUPTED.

    Streamed targets (SetJoints) are followed within the URDF joint velocity limits
    (StreamFollower, in simulated time), however fast they arrive; joint_sample() is stamped
    with the scheduled wall-clock time of the physics step that produced it.
    """

    name = "pybullet"

    PARAMETERS = ParamSchema(
        [
            Param("gui", False, doc="open the pybullet window (needs a display)"),
            Param("time_step", 0.002, "s", "physics step", low=0.0001, high=0.05),
            Param(
                "initial_joints",
                None,
                "rad",
                "start pose (from motion_common/config/robots/<robot>.yaml)",
                kind=list,
                nullable=True,
            ),
            Param(
                "speed_scale",
                0.5,
                "1",
                "fraction of the URDF joint velocity limits MoveJ/MoveL use",
                low=0.0,
                high=1.0,
                low_open=True,
            ),
            Param(
                "max_acceleration", 3.0, "rad/s^2", "MoveJ/MoveL joint acceleration", low=0.0, high=100.0, low_open=True
            ),
            Param("cartesian_speed", 0.25, "m/s", "MoveL tool speed", low=0.0, high=3.0, low_open=True),
            STREAM_ACCELERATION_PARAM,
            Param(
                "stream_timeout",
                0.1,
                "s",
                "without a new SET_JOINTS for this long a stream stops (the arm brakes to rest), as the UR's "
                "external control does",
                low=0.0,
                high=10.0,
                low_open=True,
            ),
            Param("real_time", True, doc="step in real time (false: as fast as possible)"),
            Param("scene", [], doc="extra bodies, see hw_interface.sim_driver.load_scene", item_kind=dict),
            Param("gripper_output", 0, "", "digital output that switches the suction gripper", low=0, high=63),
            Param(
                "gripper_reach", 0.02, "m", "how close a part must be to the flange to be gripped", low=0.0, high=0.5
            ),
            Param(
                "goal_tolerance",
                0.001,
                "rad",
                "largest measured joint error for a MoveJ/MoveL SUCCESS",
                low=0.0,
                high=0.1,
                low_open=True,
            ),
            Param(
                "settle_timeout",
                2.0,
                "s",
                "time after the path's end allowed to come within goal_tolerance",
                low=0.0,
                high=30.0,
                low_open=True,
            ),
        ]
    )

    def __init__(
        self,
        urdf_path: str,
        tool_frame: str = "tool0",
        gui: bool = False,
        time_step: float = 0.002,
        initial_joints=None,
        speed_scale: float = 0.5,
        max_acceleration: float = 3.0,
        cartesian_speed: float = 0.25,
        stream_acceleration: float = 200.0,
        stream_timeout: float = 0.1,
        real_time: bool = True,
        robot_name: str | None = None,
        scene=None,
        gripper_output: int = 0,
        gripper_reach: float = 0.02,
        goal_tolerance: float = 0.001,
        settle_timeout: float = 2.0,
    ):
        self.kinematics = RobotKinematics(urdf_path, tool_frame)
        self.urdf_path = urdf_path
        self.tool_frame = tool_frame
        self.gui = gui
        self.time_step = float(time_step)
        self.speed_scale = float(speed_scale)
        self.max_acceleration = float(max_acceleration)
        self.cartesian_speed = float(cartesian_speed)
        self.real_time = real_time
        self.goal_tolerance = float(goal_tolerance)
        self.settle_timeout = float(settle_timeout)
        self.robot_name = robot_name or self.kinematics.model.name
        dof = self.kinematics.dof
        self._initial = np.zeros(dof) if initial_joints is None else np.asarray(initial_joints, dtype=float)
        if self._initial.shape != (dof,):
            raise HwInterfaceError(f"initial_joints needs {dof} values, got {self._initial.shape}", Result.WRONG_LENGTH)
        # One lock guards the bullet client and the targets: pybullet is not thread-safe.
        self._lock = threading.Lock()
        self._client = None
        self._body = None
        self._joint_indices = []
        self._tool_link = -1
        self._target = self._initial.copy()
        self.stream_acceleration = float(stream_acceleration)
        self.stream_timeout = float(stream_timeout)
        # The streamed setpoint moves no faster than the motors can follow: a setpoint that
        # outran a capped motor (a wrist at its limit) left it behind, and the tool, off the
        # commanded path by up to 7 mm, went 2-3 mm past the hand's turning points as the
        # motors caught up.
        self._follower = StreamFollower(
            self.kinematics.velocity_limits * MOTOR_SPEED_FRACTION, self._initial, self.stream_acceleration
        )
        # Simulated time of the last SET_JOINTS applied (None: no stream): the stream watchdog.
        self._last_stream: float | None = None
        # SET_JOINTS targets by arrival (perf_counter), applied by the step scheduled after it.
        self._timed_targets = TimedTargets()
        self.stream_timeouts = 0
        # Wall-clock time (s) of the state after the last physics step, see joint_sample().
        self._step_stamp = time.time()
        # name -> (steps, value): readings of the state after the step numbered steps, see
        # _once_per_step; replaced by an empty dict when a reset moves the arm.
        self._step_cache = {}
        self._path: JointPath | None = None
        self._path_start = 0.0
        self._path_started: float | None = None  # wall-clock stamp of the running path's start
        self._path_done = threading.Event()
        self._path_outcome = None  # None: arrived; else (Result, reason) of a cut-short move
        self._sim_time = 0.0
        self._thread: threading.Thread | None = None
        self._running = threading.Event()
        self.steps = 0
        self.overruns = 0
        self.scene_spec = list(scene or [])
        self.bodies = {}
        self.gripper_output = int(gripper_output)
        self.gripper_reach = float(gripper_reach)
        self.outputs = {}
        self._grip_constraint = None
        self.gripped_body: str | None = None

    # -- template: connection ------------------------------------------------------------
    def login(self, url: str = "sim://", user: str = "", password: str = "") -> None:
        if self._client is not None:
            return
        if url and not url.startswith("sim"):
            raise HwInterfaceError(f"the pybullet driver connects to 'sim://', not {url!r}", Result.LOGIN_FAILED)
        self._client = bullet_client(pybullet.GUI if self.gui else pybullet.DIRECT)
        self._client.setGravity(0, 0, -9.81)
        self._client.setTimeStep(self.time_step)
        self._body = self._client.loadURDF(self.urdf_path, useFixedBase=True, flags=pybullet.URDF_USE_INERTIA_FROM_FILE)
        by_name = {}
        for index in range(self._client.getNumJoints(self._body)):
            info = self._client.getJointInfo(self._body, index)
            by_name[info[1].decode()] = index
            if info[12].decode() == self.tool_frame:
                self._tool_link = index
        missing = [n for n in self.joint_names if n not in by_name]
        if missing or self._tool_link < 0:
            self._client.disconnect()
            self._client = None
            raise HwInterfaceError(
                f"pybullet model lacks joints {missing} or tool link {self.tool_frame!r}", Result.LOGIN_FAILED
            )
        self._joint_indices = [by_name[n] for n in self.joint_names]
        self._efforts = np.array([self._client.getJointInfo(self._body, i)[10] for i in self._joint_indices])
        self._no_feedforward = [0.0] * len(self._joint_indices)  # the motors' target velocity
        # pybullet's motor constraint is soft: coupled to gravity and to the other joints'
        # reactions it ran up to ~6 % past its maxVelocity over a few steps under a fuzzed
        # stream (1 run in 4 of tests/unit/hw_interface/test_stream_speed.py). The motors are capped that
        # much below the URDF limit, so the measured speed stays within it.
        self._max_speeds = (self.kinematics.velocity_limits * MOTOR_SPEED_FRACTION).tolist()
        for index, value in zip(self._joint_indices, self._initial):
            self._client.resetJointState(self._body, index, float(value))
        self._step_cache = {}
        self._target = self._initial.copy()
        self._follower.reset(self._initial)
        # Nothing streamed to, or moving, an earlier session may move this one.
        if self._path is not None:
            self._end_path((Result.INTERRUPTED, "a new LOGIN reset the simulation; the move did not arrive"))
        self._timed_targets.clear()
        self._last_stream = None
        self.bodies = load_scene(self._client, self.scene_spec)
        self._running.set()
        self._thread = threading.Thread(target=self._step_loop, name="pybullet-step", daemon=True)
        self._thread.start()

    def disconnect(self) -> None:
        self._running.clear()
        if self._thread is not None:
            self._thread.join(timeout=2.0)
            self._thread = None
        with self._lock:
            if self._path is not None:  # a move of this simulation never goes on in the next
                self._end_path((Result.INTERRUPTED, "the simulation was disconnected; the move did not arrive"))
            if self._client is not None:
                self._client.disconnect()
                self._client = None
            # The step loop left its last readings here: without a simulation they must not
            # be served as the robot's state (reads then say NOT_CONNECTED).
            self._step_cache = {}
            self._timed_targets.clear()
            self._last_stream = None

    # -- template: state -------------------------------------------------------------------
    def _require_connection(self):
        if self._client is None:
            raise HwInterfaceError(
                "the simulation is not running: call LOGIN with url 'sim://' first", Result.NOT_CONNECTED
            )

    def get_robot_joints(self) -> np.ndarray:
        return self.joint_sample()[1]

    def _once_per_step(self, name, read):
        """``read()`` (under the lock) for the latest finished physics step, cached.

        The state only changes with a physics step (or a reset, which clears the cache), so
        it is read from pybullet once per step. A reading of the latest finished step is
        returned WITHOUT the lock: a streamed command then never waits for the step in
        progress (~0.1-0.2 ms of the 500 Hz loop) just to check or answer.
        """
        cached = self._step_cache.get(name)  # (steps, value) tuples are never mutated
        if cached is None or cached[0] != self.steps:
            with self._lock:
                self._require_connection()
                cached = (self.steps, read())
                self._step_cache[name] = cached
        return cached[1]

    def _read_joint_sample(self):
        """(stamp of the latest physics step, measured joints) from pybullet; under the lock."""
        states = self._client.getJointStates(self._body, self._joint_indices)
        return self._step_stamp, np.array([s[0] for s in states])

    def joint_sample(self):
        """(wall-clock time of the physics step the joints come from, measured joints)."""
        stamp, joints = self._once_per_step("joints", self._read_joint_sample)
        return stamp, joints.copy()

    def get_joint_velocities(self) -> np.ndarray:
        """Measured joint velocities (rad/s)."""
        with self._lock:
            self._require_connection()
            states = self._client.getJointStates(self._body, self._joint_indices)
        return np.array([s[1] for s in states])

    def get_robot_cartesian_position(self):
        def read():
            state = self._client.getLinkState(self._body, self._tool_link, computeForwardKinematics=True)
            return np.array(state[4]), np.array(state[5])

        position, orientation = self._once_per_step("tool_pose", read)
        return position.copy(), orientation.copy()

    def status(self) -> DriverStatus:
        moving = self._path is not None
        gripper = (self.gripped_body or "on (empty)") if self.outputs.get(self.gripper_output) else ""
        return DriverStatus(connected=self._client is not None, moving=moving, gripper=gripper)

    @property
    def sim_time(self) -> float:
        """Simulated seconds since login."""
        return self._sim_time

    # -- template: motion ------------------------------------------------------------------
    def set_joints(self, joints) -> None:
        target = np.asarray(joints, dtype=float)
        with self._lock:
            self._require_connection()
            if self._path is not None:
                raise HwInterfaceError("a MoveJ/MoveL is running; STOP it before streaming", Result.BUSY)
            if self.real_time:
                # The steps' own clock (monotonic): a wall-clock step (NTP, a resumed VM)
                # must not delay every target that follows.
                self._timed_targets.add(time.perf_counter(), target)
            else:
                self._follower.set_goal(target)
                self._last_stream = self._sim_time

    def move_j(self, joints, timeout: float = 30.0) -> None:
        goal = np.asarray(joints, dtype=float)
        start = self._current_command()
        duration = joint_move_duration(
            start, goal, self.kinematics.velocity_limits * self.speed_scale, self.max_acceleration
        )
        self._run_path(JointPath([start, goal], duration), timeout)

    def move_l(self, position, orientation, timeout: float = 30.0) -> None:
        line = self.kinematics.line_path(self._current_command(), position, orientation)
        if not line.reachable:
            raise HwInterfaceError(
                f"MoveL target unreachable at {line.failed_at:.0%} of the line "
                f"(IK error {line.ik_error * 1000:.1f} mm)",
                Result.UNREACHABLE,
            )
        waypoints, distance = line.joints, line.distance
        count = len(waypoints)
        steps = np.abs(np.diff(waypoints, axis=0)).max(axis=0) * (count - 1)
        duration = max(
            joint_move_duration(
                np.zeros_like(steps), steps, self.kinematics.velocity_limits * self.speed_scale, self.max_acceleration
            ),
            4.0 / 3.0 * trapezoid_duration(distance, self.cartesian_speed, self.max_acceleration),
        )
        self._run_path(JointPath(waypoints, duration), timeout)

    def path_limits(self):
        """The streamed motion's limits: the motors' speed cap and stream_acceleration."""
        velocity = self.kinematics.velocity_limits * MOTOR_SPEED_FRACTION
        return velocity, np.full(velocity.shape, self.stream_acceleration)

    def follow_path(self, path, timeout: float = 30.0) -> float:
        """Follow a timed path sampled at each physics step's simulated time (a late thread
        catches up on the path's own times), blocking; return its start's stamp."""
        self._current_command()
        self._run_path(path, timeout)
        with self._lock:
            return self._path_started

    def stop(self, reason: str = "STOP") -> None:
        with self._lock:
            if self._client is None:
                return
            states = self._client.getJointStates(self._body, self._joint_indices)
            self._target = np.array([s[0] for s in states])
            self._follower.reset(self._target)
            self._timed_targets.clear()  # no target sent before the STOP is applied after it
            if self._path is not None:
                self._end_path(
                    (Result.INTERRUPTED, f"motion interrupted by {reason}; the robot stopped short of the goal")
                )

    def _end_path(self, outcome) -> None:
        """Finish the running path with ``outcome`` (None: arrived); caller holds the lock."""
        self._path = None
        self._follower.reset(self._target)  # a stream after the move starts where it ended
        self._timed_targets.clear()
        self._path_outcome = outcome
        self._path_done.set()

    def set_gripper(self, closed: bool) -> None:
        self.set_digital_output(self.gripper_output, closed)

    def set_digital_output(self, output: int, value: bool) -> None:
        with self._lock:
            self._require_connection()
            self.outputs[int(output)] = bool(value)
            if int(output) == self.gripper_output:
                self._switch_suction(bool(value))

    def _switch_suction(self, on: bool) -> None:
        """Attach the nearest scene body within reach with a fixed constraint, or release.

        A constraint instead of contact physics makes the suction cup deterministic: a
        gripped part never slips, which is what a teleop user expects from a vacuum cup.
        """
        client = self._client
        if not on:
            if self._grip_constraint is not None:
                client.removeConstraint(self._grip_constraint)
            self._grip_constraint, self.gripped_body = None, None
            return
        if self._grip_constraint is not None:
            return
        tool = client.getLinkState(self._body, self._tool_link, computeForwardKinematics=True)
        # The tool frame is usually a massless frame without geometry: measure from the
        # nearest ancestor link that has a collision shape (the flange link of an arm).
        cup_link = self._tool_link
        while cup_link >= 0 and not client.getCollisionShapeData(self._body, cup_link):
            cup_link = client.getJointInfo(self._body, cup_link)[16]
        best = None
        for name, body in self.bodies.items():
            if entry_is_fixed(self.scene_spec, name):
                continue
            points = client.getClosestPoints(self._body, body, self.gripper_reach, linkIndexA=cup_link)
            if points:
                distance = min(p[8] for p in points)
                if best is None or distance < best[0]:
                    best = (distance, name, body)
        if best is None:
            return  # nothing under the cup: the vacuum is on but grips nothing
        _, name, body = best
        body_pos, body_orn = client.getBasePositionAndOrientation(body)
        inv_pos, inv_orn = client.invertTransform(tool[4], tool[5])
        rel_pos, rel_orn = client.multiplyTransforms(inv_pos, inv_orn, body_pos, body_orn)
        self._grip_constraint = client.createConstraint(
            self._body, self._tool_link, body, -1, pybullet.JOINT_FIXED, [0, 0, 0], rel_pos, [0, 0, 0], rel_orn
        )
        client.changeConstraint(self._grip_constraint, maxForce=500)
        self.gripped_body = name

    def body_pose(self, name: str):
        """(position, quaternion) of scene body ``name``."""
        with self._lock:
            self._require_connection()
            position, orientation = self._client.getBasePositionAndOrientation(self.bodies[name])
        return np.array(position), np.array(orientation)

    def scene_poses(self) -> dict:
        """{body name: (position, quaternion)} of every scene body."""
        with self._lock:
            self._require_connection()
            return {
                name: tuple(np.array(v) for v in self._client.getBasePositionAndOrientation(body))
                for name, body in self.bodies.items()
            }

    def reset_scene(self) -> None:
        """Gripper released, bodies at their scene-file poses, arm at its start joints."""
        with self._lock:
            self._require_connection()
            if self._path is not None:
                self._end_path((Result.INTERRUPTED, "motion interrupted by a scene reset"))
            self._switch_suction(False)
            self.outputs.clear()
            for index, entry in enumerate(self.scene_spec):
                body = self.bodies.get(entry.get("name", f"body{index}"))
                if body is None:
                    continue
                orientation = pybullet.getQuaternionFromEuler(entry.get("rpy", [0.0, 0.0, 0.0]))
                self._client.resetBasePositionAndOrientation(body, entry.get("position", [0.0, 0.0, 0.0]), orientation)
                self._client.resetBaseVelocity(body, [0.0, 0.0, 0.0], [0.0, 0.0, 0.0])
            for joint, value in zip(self._joint_indices, self._initial):
                self._client.resetJointState(self._body, joint, float(value))
            self._step_cache = {}
            self._target = self._initial.copy()
            self._follower.reset(self._target)
            self._timed_targets.clear()

    # -- internals -------------------------------------------------------------------------
    def _current_command(self) -> np.ndarray:
        with self._lock:
            self._require_connection()
            if self._path is not None:
                raise HwInterfaceError("another MoveJ/MoveL is running; wait or STOP it", Result.BUSY)
            # A move starts where the servo is, and the stream it cuts off ends there.
            self._follower.reset(self._target)
            self._timed_targets.clear()
            return self._target.copy()

    def _goal_error(self) -> float:
        """Largest MEASURED joint error (rad) from the path's end (caller holds the lock)."""
        states = self._client.getJointStates(self._body, self._joint_indices)
        return float(np.max(np.abs(np.array([s[0] for s in states]) - self._path.end)))

    def _run_path(self, path: JointPath, timeout: float) -> None:
        with self._lock:
            self._require_connection()
            self._path = path
            self._path_start = self._sim_time
            self._path_started = None
            self._path_outcome = None
            self._path_done.clear()
        try:
            arrived = self._path_done.wait(timeout=max(timeout, 0.0))
        except BaseException:  # the path must not go on moving the arm for nobody
            self.stop(reason="an error while the move ran")
            raise
        if not arrived:
            self.stop(reason="timeout")
            raise HwInterfaceError(f"motion did not finish within {timeout:.1f} s; stopped", Result.TIMEOUT)
        with self._lock:
            outcome = self._path_outcome
        if outcome is not None:
            raise HwInterfaceError(outcome[1], outcome[0])

    def _step_loop(self) -> None:
        next_tick = time.perf_counter()
        # perf_counter (monotonic) to wall clock: stamps are wall-clock like ROS's.
        to_wall = time.time() - next_tick
        while self._running.is_set():
            with self._lock:
                if self._client is None:
                    break
                feedforward = self._no_feedforward
                if self._path is None:
                    # The step scheduled at next_tick (perf_counter) applies the newest target
                    # that had arrived by then, however late the thread runs it.
                    goal = self._timed_targets.due(next_tick)
                    if goal is not None:
                        self._follower.set_goal(goal)
                        self._last_stream = self._sim_time
                    if self._last_stream is not None and self._sim_time - self._last_stream > self.stream_timeout:
                        # The stream stopped (a client died, the network was cut): brake to rest.
                        self._follower.brake()
                        self._last_stream = None
                        self.stream_timeouts += 1
                    self._target = self._follower.step(self.time_step)
                else:
                    elapsed = self._sim_time - self._path_start
                    if self._path_started is None:  # this step applies the path's time 0
                        self._path_started = (next_tick + to_wall) if self.real_time else time.time()
                    self._target = self._path.sample(elapsed)
                    if isinstance(self._path, TimedPath):
                        # Position and velocity setpoints, as a trajectory controller's: with
                        # the path's speed fed forward the arm is on the path at its times
                        # (within 0.06 mrad on a 0.5 Hz, 0.5 rad swing) instead of trailing
                        # it by the position servo's lag (3.3 ms, 5 mrad on that swing).
                        feedforward = self._path.velocity(elapsed).tolist()
                    if elapsed >= self._path.duration:
                        error = self._goal_error()
                        if error <= self.goal_tolerance:
                            self._end_path(None)
                        elif elapsed - self._path.duration > self.settle_timeout:
                            self._target = np.array(
                                [s[0] for s in self._client.getJointStates(self._body, self._joint_indices)]
                            )
                            self._end_path(
                                (
                                    Result.DRIVER_FAULT,
                                    (
                                        f"the arm did not settle within {self.settle_timeout:g} s of the path's end: "
                                        f"{error:.4f} rad from the goal (tolerance {self.goal_tolerance:g} rad); "
                                        "stopped there (blocked, or a joint limit/effort too low?)"
                                    ),
                                )
                            )
                # One call per joint: only setJointMotorControl2 takes maxVelocity, which
                # keeps the motor itself within the URDF limit (a servo lagging under
                # gravity would otherwise catch up faster than the limit).
                gain = 0.6  # pybullet positionGain, the same for every joint
                forces = (self._efforts * 4.0).tolist()
                for joint, target, force, speed, velocity in zip(
                    self._joint_indices, self._target.tolist(), forces, self._max_speeds, feedforward
                ):
                    self._client.setJointMotorControl2(
                        self._body,
                        joint,
                        pybullet.POSITION_CONTROL,
                        targetPosition=target,
                        targetVelocity=velocity,
                        force=force,
                        positionGain=gain,
                        maxVelocity=speed,
                    )
                self._client.stepSimulation()
                self._sim_time += self.time_step
                self.steps += 1
                # The state now is the one scheduled for the end of this step: stamping it
                # with that time (not with when someone reads it) keeps stamp differences
                # equal to simulated time, also while the loop catches up after a delay.
                self._step_stamp = (next_tick + self.time_step + to_wall) if self.real_time else time.time()
                # The joints of every step are read here, as a controller's state stream
                # would deliver them: a streamed command's checks (the server, ~110 Hz) and
                # /joint_states (100 Hz) then read them without the lock or pybullet, instead
                # of waiting behind the step in progress.
                self._step_cache["joints"] = (self.steps, self._read_joint_sample())
            if not self.real_time:
                # Yield the GIL and the lock so callers are not starved by a flat-out loop.
                time.sleep(0)
                continue
            next_tick += self.time_step
            delay = next_tick - time.perf_counter()
            if delay > 0:
                time.sleep(delay)
            elif delay < -CATCH_UP_S:
                # Far behind (machine busy): count it and resynchronise instead of racing.
                self.overruns += 1
                next_tick = time.perf_counter()
                to_wall = time.time() - next_tick
