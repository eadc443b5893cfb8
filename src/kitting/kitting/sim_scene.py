"""Builds the kitting cell in a pybullet client and moves parts along the belt.

Bodies: the belt (a dark box whose top is the belt plane), the kitting tray (a base plate
and six shallow slot pads), the marker plate (a quad textured with the ArUco marker that
``cv2.aruco.generateImageMarker`` draws, with a white quiet zone) and the parts (flat-shaded
meshes of ``kitting.meshes`` in their class colour). Parts are kinematic: mass 0, moved by
``step(dt)`` (reset per step at the belt speed), so a render process can mirror the same
poses with ``set_part_poses``. The robot is not built here (the driver loads it).
"""

import os
import tempfile
from collections.abc import Sequence
from dataclasses import dataclass

import cv2
import numpy as np

from motion_common.quiet_pybullet import pybullet as p
from motion_common.rotations import matrix_to_quaternion

from .cell import Cell
from .meshes import part_mesh
from .parts import part_class

BELT_RGBA = (0.16, 0.16, 0.18, 1.0)
TRAY_RGBA = (0.25, 0.35, 0.55, 1.0)
FLOOR_RGBA = (0.45, 0.45, 0.42, 1.0)
QUIET_ZONE_CELLS = 1  # white border around the marker, in marker cells
# An object of no known class (the detector must reject it, the arm must never pick it):
# a red plastic block, 40 x 30 x 20 mm.
FOREIGN_CLASS = "foreign"
FOREIGN_HALF_EXTENTS = (0.02, 0.015, 0.01)
FOREIGN_RGBA = (0.8, 0.1, 0.1, 1.0)


def marker_image(dictionary: str, marker_id: int, pixels_per_cell: int = 20) -> tuple[np.ndarray, float]:
    """(grey image of the marker with a white quiet zone, ratio of the whole image's side to
    the black square's side)."""
    aruco_dict = cv2.aruco.getPredefinedDictionary(getattr(cv2.aruco, dictionary))
    cells = aruco_dict.markerSize + 2  # data bits + the black border
    side = cells * pixels_per_cell
    image = cv2.aruco.generateImageMarker(aruco_dict, marker_id, side, borderBits=1)
    pad = QUIET_ZONE_CELLS * pixels_per_cell
    image = cv2.copyMakeBorder(image, pad, pad, pad, pad, cv2.BORDER_CONSTANT, value=255)
    return image, (cells + 2 * QUIET_ZONE_CELLS) / cells


def load_texture(client: int, image: np.ndarray) -> int:
    """A pybullet texture id for an image (grey or BGR), via a temporary PNG."""
    handle, path = tempfile.mkstemp(suffix=".png", prefix="kitting_tex_")
    os.close(handle)
    try:
        cv2.imwrite(path, image)
        return p.loadTexture(path, physicsClientId=client)
    finally:
        os.remove(path)


def textured_quad(client: int, image: np.ndarray, size: tuple[float, float], pose: np.ndarray, cells: int = 24) -> int:
    """A static body: a quad of ``size`` (x, y in its frame, m) at the 4x4 ``pose``, showing
    ``image`` upright (image top towards the quad's +y, image right towards +x), facing +z.

    The quad is split into ``cells`` x ``cells`` squares: TinyRenderer interpolates texture
    coordinates affinely in screen space (no perspective correction), which on one big
    quad moves the printed corners by about a pixel; on small cells the error vanishes."""
    sx, sy = size
    steps = np.linspace(0.0, 1.0, cells + 1)
    vertices, uvs, indices = [], [], []
    for v in steps:
        for u in steps:
            vertices.append(((u - 0.5) * sx, (v - 0.5) * sy, 0.0))
            uvs.append((u, v))
    row = cells + 1
    for j in range(cells):
        for i in range(cells):
            a = j * row + i
            indices += [a, a + 1, a + row + 1, a, a + row + 1, a + row]
    visual = p.createVisualShape(
        p.GEOM_MESH,
        vertices=vertices,
        indices=indices,
        uvs=uvs,
        normals=[(0, 0, 1)] * len(vertices),
        rgbaColor=[1, 1, 1, 1],
        physicsClientId=client,
    )
    body = p.createMultiBody(
        0.0,
        -1,
        visual,
        basePosition=pose[:3, 3].tolist(),
        baseOrientation=matrix_to_quaternion(pose[:3, :3]).tolist(),
        physicsClientId=client,
    )
    p.changeVisualShape(
        body, -1, textureUniqueId=load_texture(client, image), rgbaColor=[1, 1, 1, 1], physicsClientId=client
    )
    return body


def _box(client, half_extents, position, rgba, yaw=0.0, collide=True) -> int:
    visual = p.createVisualShape(p.GEOM_BOX, halfExtents=half_extents, rgbaColor=rgba, physicsClientId=client)
    collision = p.createCollisionShape(p.GEOM_BOX, halfExtents=half_extents, physicsClientId=client) if collide else -1
    return p.createMultiBody(
        0.0,
        collision,
        visual,
        basePosition=list(position),
        baseOrientation=p.getQuaternionFromEuler([0, 0, yaw]),
        physicsClientId=client,
    )


@dataclass
class PartState:
    """A part in the scene: its id, class and pose on the belt (x, y: m; yaw: rad; z = belt),
    or, off the belt (held, falling, in the tray), ``z`` (m) and ``orientation`` (x, y, z, w)."""

    part_id: int
    class_name: str
    x: float
    y: float
    yaw: float
    on_belt: bool = True
    z: float | None = None
    orientation: tuple[float, float, float, float] | None = None


class SimScene:
    """The cell's static bodies in ``client`` plus the parts, moved by the belt."""

    def __init__(self, client: int, cell: Cell, floor: bool = True):
        self.client, self.cell = client, cell
        self.parts: dict[int, PartState] = {}
        self._bodies: dict[int, int] = {}
        self._shapes: dict[str, int] = {}
        self._next_id = 1
        self.static_bodies: dict[str, int] = {}
        self._build(floor)

    # -- static cell --------------------------------------------------------------------
    def _build(self, floor: bool):
        cell, c = self.cell, self.client
        belt = cell.belt
        if floor:
            self.static_bodies["floor"] = _box(c, [2.0, 2.0, 0.005], [0, 0, belt.height - 0.35], FLOOR_RGBA)
        length = belt.x_end - belt.x_start
        self.static_bodies["belt"] = _box(
            c,
            [length / 2, belt.width / 2, belt.thickness / 2],
            [(belt.x_start + belt.x_end) / 2, belt.y, belt.height - belt.thickness / 2],
            BELT_RGBA,
        )
        tray = cell.tray
        tx, ty = tray.size
        self.static_bodies["tray"] = _box(
            c, [tx / 2 + 0.01, ty / 2 + 0.01, 0.005], tray.position - [0, 0, 0.005], TRAY_RGBA, tray.yaw
        )
        for slot in tray.slots:
            rgba = list(part_class(slot.part_class).rgba[:3]) + [1.0]
            rgba = [0.5 * v + 0.1 for v in rgba[:3]] + [1.0]
            self.static_bodies[f"slot_{slot.part_class}"] = _box(
                c,
                [slot.size[0] / 2 - 0.004, slot.size[1] / 2 - 0.004, 0.001],
                slot.center + [0, 0, 0.001],
                rgba,
                slot.yaw,
                collide=False,
            )
        for marker in cell.markers:
            image, ratio = marker_image(marker.dictionary, marker.id)
            side = marker.size * ratio
            self.static_bodies[f"marker_plate_{marker.id}"] = _box(
                c,
                [side / 2 + 0.01, side / 2 + 0.01, 0.02],
                marker.pose[:3, 3] - [0, 0, 0.0205],
                (0.3, 0.3, 0.3, 1),
                collide=True,
            )
            self.static_bodies[f"marker_{marker.id}"] = textured_quad(c, image, (side, side), marker.pose)

    # -- parts --------------------------------------------------------------------------
    def _shape(self, class_name: str) -> int:
        if class_name not in self._shapes and class_name == FOREIGN_CLASS:
            self._shapes[class_name] = p.createVisualShape(
                p.GEOM_BOX,
                halfExtents=list(FOREIGN_HALF_EXTENTS),
                visualFramePosition=[0, 0, FOREIGN_HALF_EXTENTS[2]],
                rgbaColor=list(FOREIGN_RGBA),
                physicsClientId=self.client,
            )
        if class_name not in self._shapes:
            part = part_class(class_name)
            vertices, indices, normals = part_mesh(part).arrays()
            self._shapes[class_name] = p.createVisualShape(
                p.GEOM_MESH,
                vertices=vertices,
                indices=indices,
                normals=normals,
                rgbaColor=list(part.rgba),
                physicsClientId=self.client,
            )
        return self._shapes[class_name]

    def add_part(
        self,
        class_name: str,
        x: float,
        y: float,
        yaw: float = 0.0,
        part_id: int | None = None,
        z: float | None = None,
        orientation=None,
    ) -> int:
        """A part of ``class_name`` (or FOREIGN_CLASS: an object of no known class) lying on
        the belt plane at (x, y, yaw), or at height ``z`` with ``orientation``; returns its id.
        The body is kinematic (mass 0, no collision): it is where it is put."""
        if part_id is None:
            part_id = self._next_id
        self._next_id = max(self._next_id, part_id + 1)
        body = p.createMultiBody(0.0, -1, self._shape(class_name), physicsClientId=self.client)
        self._bodies[part_id] = body
        self.parts[part_id] = PartState(
            part_id, class_name, x, y, yaw, z is None, z, None if orientation is None else tuple(orientation)
        )
        self._place(part_id)
        return part_id

    def add_foreign_object(
        self, half_extents=(0.02, 0.015, 0.01), x=0.0, y=None, yaw=0.0, rgba=(0.8, 0.1, 0.1, 1.0)
    ) -> int:
        """An object of no known class (a box) on the belt: returns its body id."""
        y = self.cell.belt.y if y is None else y
        return _box(
            self.client, list(half_extents), [x, y, self.cell.belt.height + half_extents[2]], rgba, yaw, collide=False
        )

    def remove_part(self, part_id: int):
        body = self._bodies.pop(part_id, None)
        self.parts.pop(part_id, None)
        if body is not None:
            p.removeBody(body, physicsClientId=self.client)

    def _place(self, part_id: int):
        state = self.parts[part_id]
        z = self.cell.belt.height if state.z is None else state.z
        orientation = p.getQuaternionFromEuler([0, 0, state.yaw]) if state.orientation is None else state.orientation
        p.resetBasePositionAndOrientation(
            self._bodies[part_id], [state.x, state.y, z], orientation, physicsClientId=self.client
        )

    def body_of(self, part_id: int) -> int:
        return self._bodies[part_id]

    def step(self, dt: float, speed: float | None = None):
        """Move every part still on the belt by speed * dt along +x (``speed`` m/s, default
        the cell's belt speed); a part past the belt's end leaves the belt (stays where it
        fell off: it is no longer moved)."""
        belt = self.cell.belt
        speed = belt.speed if speed is None else speed
        for part_id, state in self.parts.items():
            if not state.on_belt:
                continue
            state.x += speed * dt
            if state.x > belt.x_end:
                state.on_belt = False
            self._place(part_id)

    def part_poses(self) -> list[tuple]:
        """(id, class, x, y, yaw) of every part on the belt, (id, class, x, y, yaw, z,
        orientation) of the others: what a render process mirrors."""
        return [
            (s.part_id, s.class_name, s.x, s.y, s.yaw) + (() if s.z is None else (s.z, s.orientation))
            for s in self.parts.values()
        ]

    def set_part_poses(self, poses: Sequence[tuple]):
        """Mirror another scene's parts: add, move and remove so that exactly ``poses`` (as
        ``part_poses`` gives them) exist."""
        wanted = {int(pose[0]): pose[1:] for pose in poses}
        for part_id in [pid for pid in self.parts if pid not in wanted or self.parts[pid].class_name != wanted[pid][0]]:
            self.remove_part(part_id)
        for part_id, (name, x, y, yaw, *above) in wanted.items():
            z, orientation = above if above else (None, None)
            if part_id in self.parts:
                state = self.parts[part_id]
                state.x, state.y, state.yaw, state.z = x, y, yaw, z
                state.orientation = None if orientation is None else tuple(orientation)
                state.on_belt = z is None
                self._place(part_id)
            else:
                self.add_part(name, x, y, yaw, part_id=part_id, z=z, orientation=orientation)


def render_board_views(client, spec, camera, count: int, seed: int = 7) -> list[np.ndarray]:
    """``count`` simulated ChArUco calibration shots: the board of ``spec`` (a
    kitting.calibration.BoardSpec) as a textured quad, seen by ``camera`` from seeded random
    poses (tilted up to 30° about x/y, 20° about z, 0.45-0.6 m away, facing the camera).
    Resets the client's simulation first."""
    from scipy.spatial.transform import Rotation

    from .camera import render

    p.resetSimulation(physicsClientId=client)
    image, size = spec.image()
    body = textured_quad(client, image, size, np.eye(4))
    rng = np.random.default_rng(seed)
    images = []
    for _ in range(count):
        rotation = Rotation.from_euler("xyz", rng.uniform([-30, -30, -20], [30, 30, 20]), degrees=True)
        rotation = rotation * Rotation.from_euler("x", 180, degrees=True)  # face the camera
        position = rng.uniform([-0.05, -0.04, 0.45], [0.05, 0.04, 0.6])
        p.resetBasePositionAndOrientation(body, position.tolist(), rotation.as_quat().tolist(), physicsClientId=client)
        images.append(render(client, camera))
    return images
