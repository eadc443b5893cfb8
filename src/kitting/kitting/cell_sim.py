"""The simulated kitting cell's physics: the belt carries parts, the electromagnet on the
robot's flange grips them (a fixed constraint), a released part falls under gravity into
the tray or wherever it is dropped.

The robot itself is simulated by hw_interface's pybullet driver (motion_controller_server);
this world mirrors its tool pose (``set_tool_pose``, from /motion_controller/tool_pose) and
the magnet's state (``set_magnet``, from the gripper output), so the same kitting program
drives the simulated cell and the real one.

Time is the caller's clock (seconds, e.g. ROS time): ``advance(t)`` moves belt parts by
speed x elapsed time exactly (kinematic, so their positions never depend on how busy the
machine is) and steps the physics of held and falling parts in fixed ``time_step``
increments up to ``t``. When the caller falls far behind, the physics skips ahead and the
update counts as an overrun; ``real_time_factor`` says how much physics time was stepped
per second of the clock.
"""

import math
from collections import deque
from dataclasses import dataclass

import numpy as np

from motion_common.quiet_pybullet import connect
from motion_common.quiet_pybullet import pybullet as p

from .cell import Cell
from .parts import PART_CLASSES
from .sim_scene import FOREIGN_CLASS, FOREIGN_HALF_EXTENTS, SimScene

SPAWN_MARGIN = 0.03  # m, a new part's centre from the belt's upstream end
SETTLE_SPEED = 0.01  # m/s, below this a falling part counts as still
SETTLE_TIME = 0.2  # s, still for this long: resting
MAX_CATCH_UP = 0.25  # s of physics stepped at most per advance(); more is an overrun
TRAY_DEPTH = 0.05  # m above the tray floor that still counts as in the tray (stacked parts)
PART_DENSITY_MASS = {"bolt": 0.025, "nut": 0.017, "washer": 0.004, FOREIGN_CLASS: 0.01}  # kg


@dataclass
class CellPartState:
    """Ground truth of one part: pose (m, quaternion x, y, z, w), state, slot it rests in."""

    part_id: int
    class_name: str
    position: np.ndarray
    orientation: np.ndarray
    state: str  # belt | held | falling | resting | gone
    slot: str = ""


class _Part:
    def __init__(self, part_id, class_name):
        self.part_id, self.class_name = part_id, class_name
        self.state = "belt"
        self.final_pose = None  # (x, y, yaw) where it fell off the belt's end
        self.body: int | None = None  # dynamic body once off the belt
        self.constraint: int | None = None
        self.still_since: float | None = None
        self.slot = ""

    @property
    def kind(self) -> str:
        return FOREIGN_CLASS if self.class_name == FOREIGN_CLASS else PART_CLASSES[self.class_name].kind

    @property
    def half_extents(self):
        if self.class_name == FOREIGN_CLASS:
            return list(FOREIGN_HALF_EXTENTS)
        part = PART_CLASSES[self.class_name]
        return [part.length / 2, part.width / 2, part.height / 2]


class CellSimulation:
    """The cell (``kitting.cell.Cell``) in its own pybullet DIRECT client.

    Not thread-safe: one caller (or one lock) at a time.
    """

    def __init__(self, cell: Cell, time_step: float = 1.0 / 240.0, start_time: float = 0.0):
        self.cell = cell
        self.time_step = float(time_step)
        self.client = connect(p.DIRECT)
        p.setGravity(0, 0, -9.81, physicsClientId=self.client)
        p.setTimeStep(self.time_step, physicsClientId=self.client)
        self.scene = SimScene(self.client, cell)
        self.belt_speed = cell.belt.speed
        self.parts: dict[int, _Part] = {}
        self._next_id = 1
        self.time = float(start_time)
        self._physics_time = self.time  # clock time the physics has been stepped to
        self.tool_position = np.array([0.0, 0.0, 1.0])
        self.tool_orientation = np.array([1.0, 0.0, 0.0, 0.0])
        self.magnet_on = False
        self.held: int | None = None
        # The magnet: a kinematic body without collision that follows the tool; a gripped
        # part hangs from it by a fixed constraint.
        self._magnet = p.createMultiBody(0.0, -1, -1, [0, 0, 1], physicsClientId=self.client)
        self.steps = 0
        self.overruns = 0
        self._rtf_window = deque()  # (clock time, physics seconds stepped)

    def close(self):
        """Disconnect the physics client."""
        if self.client is not None:
            p.disconnect(self.client)
            self.client = None

    # -- inputs ------------------------------------------------------------------------------
    def spawn(self, class_name: str, y_offset: float = 0.0, yaw: float = 0.0) -> int:
        """A new part at the belt's upstream end; returns its id. ValueError for an unknown
        class or an offset that puts the part off the belt."""
        if class_name != FOREIGN_CLASS and class_name not in PART_CLASSES:
            raise ValueError(f"unknown part class {class_name!r}; valid: {sorted(PART_CLASSES)} or {FOREIGN_CLASS!r}")
        belt = self.cell.belt
        if not (math.isfinite(y_offset) and math.isfinite(yaw)) or abs(y_offset) > belt.width / 2 - 0.01:
            raise ValueError(f"y_offset {y_offset} m puts the part off the belt (half width {belt.width / 2} m)")
        part_id = self._next_id
        self._next_id += 1
        self.parts[part_id] = _Part(part_id, class_name)
        # The scene owns a belt part's pose and moves it (SimScene.step).
        self.scene.add_part(class_name, belt.x_start + SPAWN_MARGIN, belt.y + y_offset, yaw, part_id=part_id)
        return part_id

    def clear(self):
        """Remove every part (the gripper lets go)."""
        for part_id in list(self.parts):
            self._remove(part_id)
        self.held = None

    def clear_tray(self) -> int:
        """The tray swap: remove every part lying still or falling over the tray's footprint
        (2 cm around it), in a slot or not; belt and held parts stay. Returns how many."""
        tray = self.cell.tray
        half = np.asarray(tray.size, float) / 2 + 0.02
        c, s = math.cos(tray.yaw), math.sin(tray.yaw)
        removed = 0
        for state in self.states():
            if state.state not in ("resting", "falling"):
                continue
            dx, dy = state.position[0] - tray.position[0], state.position[1] - tray.position[1]
            local = (c * dx + s * dy, -s * dx + c * dy)
            if abs(local[0]) <= half[0] and abs(local[1]) <= half[1]:
                self._remove(state.part_id)
                removed += 1
        return removed

    def set_tool_pose(self, position, orientation):
        """The robot's tool0 pose (m; quaternion x, y, z, w), base frame."""
        position, orientation = np.asarray(position, float), np.asarray(orientation, float)
        if (
            position.shape == (3,)
            and orientation.shape == (4,)
            and np.all(np.isfinite(position))
            and np.all(np.isfinite(orientation))
            and np.linalg.norm(orientation) > 0.5
        ):
            self.tool_position, self.tool_orientation = position, orientation / np.linalg.norm(orientation)

    def set_magnet(self, on: bool):
        """Switch the electromagnet; off releases a held part (it falls)."""
        self.magnet_on = bool(on)
        if not on and self.held is not None:
            part = self.parts[self.held]
            p.removeConstraint(part.constraint, physicsClientId=self.client)
            part.constraint, part.state, part.still_since = None, "falling", None
            self.held = None

    # -- time --------------------------------------------------------------------------------
    def advance(self, t: float):
        """Bring the cell to clock time ``t`` (s)."""
        dt = float(t) - self.time
        if dt <= 0:
            return
        self.time = float(t)
        self.scene.step(dt, self.belt_speed)
        for part_id, state in list(self.scene.parts.items()):
            if not state.on_belt:  # fell off the belt's end: out of the cell
                part = self.parts[part_id]
                part.state, part.final_pose = "gone", (state.x, state.y, state.yaw)
                self.scene.remove_part(part_id)
        self._update_magnet()
        if dt > MAX_CATCH_UP:
            # Far behind (a busy machine): skip ahead rather than run physics in a burst.
            self.overruns += 1
            self._physics_time = self.time - MAX_CATCH_UP
        steps = int((self.time - self._physics_time) / self.time_step + 1e-9)
        self._physics_time += steps * self.time_step
        for _ in range(steps):
            p.stepSimulation(physicsClientId=self.client)
        self.steps += steps
        self._rtf_window.append((self.time, steps * self.time_step))
        while self._rtf_window and self._rtf_window[0][0] < self.time - 1.0:
            self._rtf_window.popleft()
        self._update_falling()

    @property
    def real_time_factor(self) -> float:
        """Physics seconds stepped per clock second over the last second (1.0: keeping up)."""
        if len(self._rtf_window) < 2:
            return 1.0
        span = self._rtf_window[-1][0] - self._rtf_window[0][0]
        stepped = sum(s for _, s in list(self._rtf_window)[1:])
        return stepped / span if span > 0 else 1.0

    # -- internals ---------------------------------------------------------------------------
    def _magnet_face(self):
        rotation = np.array(p.getMatrixFromQuaternion(self.tool_orientation.tolist())).reshape(3, 3)
        return self.tool_position + rotation[:, 2] * self.cell.gripper.tcp_length

    def _update_magnet(self):
        face = self._magnet_face()
        p.resetBasePositionAndOrientation(
            self._magnet, face.tolist(), self.tool_orientation.tolist(), physicsClientId=self.client
        )
        if not self.magnet_on or self.held is not None:
            return
        gripper = self.cell.gripper
        best = None
        for part in self.parts.values():
            if part.state not in ("belt", "resting"):
                continue
            centre, top = self._centre_and_top(part)
            offset = math.hypot(centre[0] - face[0], centre[1] - face[1])
            gap = face[2] - top
            if offset <= gripper.grip_radius and -0.002 <= gap <= gripper.grip_gap:
                if best is None or offset < best[0]:
                    best = (offset, part)
        if best is not None:
            self._attach(best[1], face)

    def _belt_pose(self, part: _Part):
        """(x, y, yaw) of a part on the belt, or where it fell off the belt's end."""
        if part.part_id in self.scene.parts:
            state = self.scene.parts[part.part_id]
            return state.x, state.y, state.yaw
        return part.final_pose

    def _centre_and_top(self, part: _Part):
        if part.state == "belt":
            x, y, _ = self._belt_pose(part)
            return np.array([x, y, self.cell.belt.height]), self.cell.belt.height + 2 * part.half_extents[2]
        position, _ = p.getBasePositionAndOrientation(part.body, physicsClientId=self.client)
        return np.array(position), position[2] + part.half_extents[2]

    def _attach(self, part: _Part, face):
        """Grip ``part``: it becomes a dynamic body hanging from the magnet (fixed constraint)."""
        if part.state == "belt":
            x, y, yaw = self._belt_pose(part)
            self.scene.remove_part(part.part_id)
            half = part.half_extents
            position = [x, y, self.cell.belt.height + half[2]]
            orientation = p.getQuaternionFromEuler([0, 0, yaw])
            shape = p.createCollisionShape(p.GEOM_BOX, halfExtents=half, physicsClientId=self.client)
            part.body = p.createMultiBody(
                PART_DENSITY_MASS[part.kind], shape, -1, position, orientation, physicsClientId=self.client
            )
            p.changeDynamics(part.body, -1, lateralFriction=0.8, restitution=0.0, physicsClientId=self.client)
        position, orientation = p.getBasePositionAndOrientation(part.body, physicsClientId=self.client)
        inv_pos, inv_orn = p.invertTransform(face.tolist(), self.tool_orientation.tolist())
        rel_pos, rel_orn = p.multiplyTransforms(inv_pos, inv_orn, position, orientation)
        part.constraint = p.createConstraint(
            self._magnet,
            -1,
            part.body,
            -1,
            p.JOINT_FIXED,
            [0, 0, 0],
            rel_pos,
            [0, 0, 0],
            rel_orn,
            physicsClientId=self.client,
        )
        p.changeConstraint(part.constraint, maxForce=50.0, physicsClientId=self.client)
        part.state, part.slot = "held", ""
        self.held = part.part_id

    def _update_falling(self):
        for part in self.parts.values():
            if part.state != "falling":
                continue
            linear, _ = p.getBaseVelocity(part.body, physicsClientId=self.client)
            if np.linalg.norm(linear) < SETTLE_SPEED:
                if part.still_since is None:
                    part.still_since = self.time
                elif self.time - part.still_since >= SETTLE_TIME:
                    part.state = "resting"
                    part.slot = self._slot_of(part)
            else:
                part.still_since = None
            position, _ = p.getBasePositionAndOrientation(part.body, physicsClientId=self.client)
            if position[2] < self.cell.belt.height - 1.0:
                part.state = "gone"  # fell through the world: never counts as placed

    def _slot_of(self, part: _Part) -> str:
        """Class of the tray slot whose footprint holds the part's centre, in the tray (on its
        floor, or on parts already in the slot)."""
        position, _ = p.getBasePositionAndOrientation(part.body, physicsClientId=self.client)
        bottom = position[2] - part.half_extents[2]
        tray_floor = self.cell.tray.position[2]
        if not tray_floor - 0.005 <= bottom <= tray_floor + TRAY_DEPTH:
            return ""
        for slot in self.cell.tray.slots:
            if slot.contains(position[:2]):
                return slot.part_class
        return ""

    def _remove(self, part_id: int):
        part = self.parts.pop(part_id)
        if part.constraint is not None:
            p.removeConstraint(part.constraint, physicsClientId=self.client)
        if part.body is not None:
            p.removeBody(part.body, physicsClientId=self.client)
        if part_id in self.scene.parts:
            self.scene.remove_part(part_id)

    # -- outputs -----------------------------------------------------------------------------
    def states(self) -> list[CellPartState]:
        """Ground truth of every part at the current time."""
        out = []
        for part in self.parts.values():
            if part.body is None:
                x, y, yaw = self._belt_pose(part)
                position = np.array([x, y, self.cell.belt.height])
                orientation = np.array(p.getQuaternionFromEuler([0, 0, yaw]))
            else:
                position, orientation = (
                    np.array(v) for v in p.getBasePositionAndOrientation(part.body, physicsClientId=self.client)
                )
                position = position - [0, 0, part.half_extents[2]]  # bottom centre, like belt parts
            out.append(CellPartState(part.part_id, part.class_name, position, orientation, part.state, part.slot))
        return out

    def render_poses(self) -> list[tuple]:
        """The parts as ``SimScene.set_part_poses`` takes them (what the camera sees)."""
        poses = []
        for state in self.states():
            if state.state == "gone":
                continue
            if state.state == "belt":
                poses.append((state.part_id, state.class_name) + self._belt_pose(self.parts[state.part_id]))
            else:
                poses.append(
                    (
                        state.part_id,
                        state.class_name,
                        float(state.position[0]),
                        float(state.position[1]),
                        0.0,
                        float(state.position[2]),
                        tuple(float(v) for v in state.orientation),
                    )
                )
        return poses
