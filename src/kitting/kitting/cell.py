"""The simulated kitting cell as data: robot, conveyor belt, kitting tray with six slots,
ArUco marker on the belt plane, camera above the belt. Loaded from a YAML file
(``config/cell.yaml``) through ``motion_common.params.ParamSchema``: every value is typed,
ranged and carries its unit; an unknown key is an error naming the file and the valid keys.
All positions in the robot base frame (UR10e base at the origin), metres."""

import math
import os
from dataclasses import dataclass

import numpy as np

from motion_common.params import Param, ParamSchema, read_yaml_file

from .parts import CLASS_NAMES, part_class

DEFAULT_CELL = os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "config", "cell.yaml")

BELT_SCHEMA = ParamSchema(
    [
        Param("height", 0.05, "m", "z of the belt plane", low=-0.5, high=1.5),
        Param("y", 0.70, "m", "belt centre line", low=-2.0, high=2.0),
        Param("x_start", -0.80, "m", "upstream end", low=-3.0, high=3.0),
        Param("x_end", 0.80, "m", "downstream end", low=-3.0, high=3.0),
        Param("width", 0.25, "m", "belt width", low=0.05, high=1.0),
        Param("speed", 0.05, "m/s", "belt speed along +x", low=0.0, high=0.5),
        Param("thickness", 0.04, "m", "belt body below the plane", low=0.001, high=0.5),
    ]
)
TRAY_SCHEMA = ParamSchema(
    [
        Param("position", [0.35, 0.25, 0.05], "m", "centre of the tray floor", length=3, low=-3.0, high=3.0),
        Param("yaw", 0.0, "deg", "tray yaw", low=-180.0, high=180.0),
        Param("slot_size", [0.08, 0.08], "m", "slot footprint", length=2, low=0.02, high=0.5),
        Param("columns", 3, "", "slots along x", low=1, high=6),
        Param("slot_classes", list(CLASS_NAMES), "", "class of each slot, row by row", length=6, item_kind=str),
    ]
)
MARKER_ITEM_SCHEMA = ParamSchema(
    [
        Param("id", 7, "", "marker id", low=0, high=1023),
        Param("position", [-0.30, 0.525, 0.05], "m", "marker centre", length=3, low=-3.0, high=3.0),
        Param("yaw", 0.0, "deg", "marker yaw about z", low=-180.0, high=180.0),
    ]
)
MARKER_SCHEMA = ParamSchema(
    [
        Param(
            "dictionary",
            "DICT_4X4_50",
            "",
            "cv2.aruco dictionary",
            choices=("DICT_4X4_50", "DICT_5X5_50", "DICT_6X6_50", "DICT_ARUCO_ORIGINAL"),
        ),
        Param("size", 0.06, "m", "black square side", low=0.01, high=0.5),
        Param("markers", [MARKER_ITEM_SCHEMA.defaults()], "", "id and pose of each marker", item_kind=dict),
    ]
)
CAMERA_SCHEMA = ParamSchema(
    [
        Param("width", 640, "px", "image width", low=16, high=8192),
        Param("height", 480, "px", "image height", low=16, high=8192),
        Param("fx", 600.0, "px", "focal length x", low=1.0, high=1e5, low_open=True),
        Param("fy", 600.0, "px", "focal length y", low=1.0, high=1e5, low_open=True),
        Param("cx", 319.5, "px", "principal point x", low=0.0, high=8192.0),
        Param("cy", 239.5, "px", "principal point y", low=0.0, high=8192.0),
        Param("distortion", [0.0] * 5, "", "k1 k2 p1 p2 k3", length=5, low=-10.0, high=10.0),
        Param("position", [-0.30, 0.54, 0.60], "m", "optical centre", length=3, low=-5.0, high=5.0),
        Param("look_at", [-0.30, 0.64, 0.05], "m", "point on the optical axis", length=3, low=-5.0, high=5.0),
        Param("image_right", [1.0, 0.0, 0.0], "", "direction shown to the right", length=3, low=-1.0, high=1.0),
        Param("near", 0.05, "m", "near clip plane", low=0.001, high=10.0, low_open=True),
        Param("far", 2.0, "m", "far clip plane", low=0.01, high=100.0),
    ]
)
GRIPPER_SCHEMA = ParamSchema(
    [
        Param(
            "tcp_length", 0.05, "m", "magnet face below the flange (tool0), along the tool z axis", low=0.0, high=0.5
        ),
        Param(
            "grip_radius",
            0.012,
            "m",
            "largest horizontal offset of a part's centre from the magnet axis that still grips",
            low=0.001,
            high=0.1,
        ),
        Param(
            "grip_gap",
            0.006,
            "m",
            "largest gap between the magnet face and a part's top that still grips",
            low=0.0,
            high=0.05,
        ),
        Param("output", 0, "", "controller digital output that switches the magnet", low=0, high=63),
    ]
)
CELL_SCHEMA = ParamSchema(
    [
        Param("robot", "ur10e", "", "robot model", choices=("ur10e", "ur5e")),
        Param("belt", BELT_SCHEMA.defaults(), "", "conveyor belt", schema=BELT_SCHEMA),
        Param("tray", TRAY_SCHEMA.defaults(), "", "kitting tray", schema=TRAY_SCHEMA),
        Param("marker", MARKER_SCHEMA.defaults(), "", "ArUco marker", schema=MARKER_SCHEMA),
        Param("camera", CAMERA_SCHEMA.defaults(), "", "camera above the belt", schema=CAMERA_SCHEMA),
        Param("gripper", GRIPPER_SCHEMA.defaults(), "", "electromagnetic gripper", schema=GRIPPER_SCHEMA),
    ]
)


def rot_z(yaw: float) -> np.ndarray:
    c, s = math.cos(yaw), math.sin(yaw)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def transform(rotation, translation) -> np.ndarray:
    matrix = np.eye(4)
    matrix[:3, :3] = rotation
    matrix[:3, 3] = translation
    return matrix


def look_at_pose(position, target, image_right) -> np.ndarray:
    """4x4 pose in the base frame of an OpenCV optical frame (z forward, x right, y down)
    at ``position`` looking at ``target`` with ``image_right`` shown to the right."""
    position, target = np.asarray(position, float), np.asarray(target, float)
    z = target - position
    z /= np.linalg.norm(z)
    x = np.asarray(image_right, float) - np.dot(image_right, z) * z
    if np.linalg.norm(x) < 1e-6:
        raise ValueError("camera image_right is parallel to the optical axis")
    x /= np.linalg.norm(x)
    y = np.cross(z, x)
    return transform(np.c_[x, y, z], position)


@dataclass
class Belt:
    height: float
    y: float
    x_start: float
    x_end: float
    width: float
    speed: float
    thickness: float

    @property
    def plane_point(self) -> np.ndarray:
        return np.array([0.0, self.y, self.height])

    plane_normal = np.array([0.0, 0.0, 1.0])

    def on_belt(self, x: float, y: float, margin: float = 0.0) -> bool:
        """Is (x, y) on the belt, at least ``margin`` from its side edges and ends?"""
        return self.x_start + margin <= x <= self.x_end - margin and abs(y - self.y) <= self.width / 2 - margin


@dataclass
class Slot:
    part_class: str
    center: np.ndarray  # m, base frame, on the tray floor
    size: tuple[float, float]
    yaw: float  # rad

    def contains(self, xy, margin: float = 0.0) -> bool:
        """Is the point (x, y) inside this slot's footprint (less ``margin``)?"""
        local = rot_z(-self.yaw)[:2, :2] @ (np.asarray(xy, float)[:2] - self.center[:2])
        return bool(abs(local[0]) <= self.size[0] / 2 - margin and abs(local[1]) <= self.size[1] / 2 - margin)


@dataclass
class Tray:
    position: np.ndarray
    yaw: float  # rad
    slot_size: tuple[float, float]
    columns: int
    slots: list[Slot]

    def slot_for(self, class_name: str) -> Slot:
        for slot in self.slots:
            if slot.part_class == class_name:
                return slot
        raise ValueError(f"no tray slot for class {class_name!r}")

    @property
    def rows(self) -> int:
        return int(math.ceil(len(self.slots) / self.columns))

    @property
    def size(self) -> tuple[float, float]:
        return self.columns * self.slot_size[0], self.rows * self.slot_size[1]


@dataclass
class Marker:
    dictionary: str
    id: int
    size: float
    pose: np.ndarray  # 4x4, marker frame (x right, y up on the printed marker, z out of the plane) in base

    def corners(self) -> np.ndarray:
        """4 x 3 corners in the base frame, in ArUco's order (top-left, top-right,
        bottom-right, bottom-left of the printed marker)."""
        half = self.size / 2
        local = np.array([[-half, half, 0, 1], [half, half, 0, 1], [half, -half, 0, 1], [-half, -half, 0, 1]])
        return (self.pose @ local.T).T[:, :3]


@dataclass
class CameraSpec:
    width: int
    height: int
    K: np.ndarray
    distortion: np.ndarray
    pose: np.ndarray  # 4x4 optical frame in base
    near: float
    far: float


@dataclass
class Gripper:
    """The electromagnet on the flange (the paper's gripper): face ``tcp_length`` below
    tool0 along the tool z axis; grips a part whose top is within ``grip_gap`` of the face
    and whose centre is within ``grip_radius`` of the magnet axis."""

    tcp_length: float
    grip_radius: float
    grip_gap: float
    output: int


@dataclass
class Cell:
    robot: str
    belt: Belt
    tray: Tray
    markers: list[Marker]
    camera: CameraSpec
    gripper: Gripper
    source: str = "<defaults>"

    @property
    def marker(self) -> Marker:
        """The first marker."""
        return self.markers[0]


def _tray(values) -> Tray:
    yaw = math.radians(values["yaw"])
    position = np.asarray(values["position"], float)
    columns, (sx, sy) = values["columns"], values["slot_size"]
    rows = int(math.ceil(6 / columns))
    slots = []
    for index, name in enumerate(values["slot_classes"]):
        part_class(name)  # ValueError on an unknown class
        row, column = divmod(index, columns)
        local = np.array([(column - (columns - 1) / 2) * sx, ((rows - 1) / 2 - row) * sy, 0.0])
        slots.append(Slot(name, position + rot_z(yaw) @ local, (sx, sy), yaw))
    if sorted(values["slot_classes"]) != sorted(CLASS_NAMES):
        raise ValueError(f"tray slot_classes must name each of {list(CLASS_NAMES)} once")
    return Tray(position, yaw, (sx, sy), columns, slots)


def cell_from_dict(values: dict | None, source: str = "<dict>") -> Cell:
    """A Cell from a mapping with CELL_SCHEMA's keys (missing ones take their defaults)."""
    values = CELL_SCHEMA.validate(values, source)
    belt = Belt(**values["belt"])
    if belt.x_end <= belt.x_start:
        raise ValueError(f"{source}: belt x_end must be greater than x_start")
    m = values["marker"]
    markers = []
    for index, item in enumerate(m["markers"]):
        item = MARKER_ITEM_SCHEMA.validate(item, f"{source}: marker.markers[{index}]")
        markers.append(
            Marker(
                m["dictionary"], item["id"], m["size"], transform(rot_z(math.radians(item["yaw"])), item["position"])
            )
        )
    if not markers or len({mk.id for mk in markers}) != len(markers):
        raise ValueError(f"{source}: marker.markers needs at least one marker and distinct ids")
    c = values["camera"]
    K = np.array([[c["fx"], 0.0, c["cx"]], [0.0, c["fy"], c["cy"]], [0.0, 0.0, 1.0]])
    camera = CameraSpec(
        c["width"],
        c["height"],
        K,
        np.asarray(c["distortion"], float),
        look_at_pose(c["position"], c["look_at"], c["image_right"]),
        c["near"],
        c["far"],
    )
    return Cell(values["robot"], belt, _tray(values["tray"]), markers, camera, Gripper(**values["gripper"]), source)


def load_cell(path: str = DEFAULT_CELL) -> Cell:
    """The cell described by a YAML file (default: this package's config/cell.yaml)."""
    return cell_from_dict(read_yaml_file(path), path)


def class_names() -> dict[str, int]:
    """Class name -> index (a stable order for confusion matrices)."""
    return {name: i for i, name in enumerate(CLASS_NAMES)}
