"""Where the robot arm and its gripper appear in the cell camera's image, from the joints.

The camera looks at the belt from above, and the arm works between it and the belt: while
it waits, descends on a part or carries one away, its links and the magnet hide parts and
markers. The vision pipeline must neither detect the arm (a light grey link looks like a
silver part) nor measure a part the arm half hides (its blob's centroid would move). The
arm's shapes are known: the URDF's visual geometry (cylinders, boxes, spheres) at the link
poses the joints give (pinocchio forward kinematics), plus the magnet (``magnet_shape``)
under tool0. ``RobotSilhouette.mask`` projects their convex hulls into a posed camera: the
image of a convex solid is the convex hull of its projected points, so a cylinder's is the
hull of its two end circles (sampled), a box's of its corners. The simulated camera's
renderer draws the same shapes (``kitting.render_worker`` loads the same URDF and
``magnet_shape``), so the mask and the rendered arm agree to the pixel up to the joint
sample's age; a margin covers that.

Plain numpy / OpenCV / pinocchio: no simulator, no ROS (a real cell runs it on its own
robot's measured joints).
"""

import math
import os
import xml.etree.ElementTree as ET
from dataclasses import dataclass

import cv2
import numpy as np
import pinocchio as pin

__all__ = ["RobotShape", "RobotSilhouette", "magnet_shape", "robot_urdf", "MAGNET_RADIUS", "MAGNET_RGBA"]

# The electromagnet on tool0: a dark cylinder from the flange down to the magnet face
# (cell.yaml gripper.tcp_length), 60 mm across (a 30 kg-class holding magnet).
MAGNET_RADIUS = 0.03  # m
MAGNET_RGBA = (0.12, 0.12, 0.13, 1.0)
_CIRCLE_POINTS = 16  # samples of a cylinder's end circle (hull error < 2 % of the radius)
_RINGS = 5  # circles sampled along a cylinder (a link that crosses the camera plane is cut there)


def robot_urdf(robot: str) -> str:
    """Path of motion_common's URDF of ``robot`` (the cell YAML's robot model)."""
    kitting_package = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    path = os.path.join(os.path.dirname(kitting_package), "motion_common", "urdf", f"{robot}.urdf")
    if not os.path.isfile(path):
        raise ValueError(f"no URDF for robot {robot!r} at {path}")
    return path


@dataclass(frozen=True)
class RobotShape:
    """One solid of the robot: ``kind`` cylinder (dims: radius, length along z), box (dims:
    half extents) or sphere (dims: radius), at ``origin`` (4x4) in ``link``'s frame."""

    link: str
    kind: str
    dims: tuple
    origin: np.ndarray


def magnet_shape(tcp_length: float, tool_frame: str = "tool0") -> RobotShape:
    """The magnet: a cylinder from the flange to the face, ``tcp_length`` along tool0's z."""
    origin = np.eye(4)
    origin[2, 3] = tcp_length / 2
    return RobotShape(tool_frame, "cylinder", (MAGNET_RADIUS, float(tcp_length)), origin)


def _origin(element) -> np.ndarray:
    T = np.eye(4)
    if element is None:
        return T
    xyz = [float(v) for v in element.get("xyz", "0 0 0").split()]
    rpy = [float(v) for v in element.get("rpy", "0 0 0").split()]
    T[:3, :3] = pin.rpy.rpyToMatrix(*rpy)
    T[:3, 3] = xyz
    return T


def urdf_visual_shapes(urdf_path: str) -> list[RobotShape]:
    """Every primitive visual of the URDF (meshes are skipped: the project's URDFs have none)."""
    shapes = []
    for link in ET.parse(urdf_path).getroot().iter("link"):
        for visual in link.iter("visual"):
            geometry = visual.find("geometry")
            if geometry is None or len(geometry) == 0:
                continue
            g = geometry[0]
            origin = _origin(visual.find("origin"))
            if g.tag == "cylinder":
                dims = (float(g.get("radius")), float(g.get("length")))
            elif g.tag == "box":
                dims = tuple(0.5 * float(v) for v in g.get("size").split())
            elif g.tag == "sphere":
                dims = (float(g.get("radius")),)
            else:
                continue
            shapes.append(RobotShape(link.get("name"), g.tag, dims, origin))
    return shapes


def _hull_points(shape: RobotShape) -> np.ndarray:
    """Points (N x 3, in the shape's frame) whose convex hull is the solid (to sampling)."""
    if shape.kind == "box":
        hx, hy, hz = shape.dims
        return np.array([[x, y, z] for x in (-hx, hx) for y in (-hy, hy) for z in (-hz, hz)])
    angles = np.linspace(0.0, 2.0 * math.pi, _CIRCLE_POINTS, endpoint=False)
    # Circumscribed polygon: its hull contains the circle.
    scale = 1.0 / math.cos(math.pi / _CIRCLE_POINTS)
    if shape.kind == "sphere":
        r = shape.dims[0] * scale
        ring = np.c_[np.cos(angles), np.sin(angles)] * r
        return np.vstack(
            [np.c_[ring, np.zeros(len(ring))], np.c_[ring[:, 0], np.zeros(len(ring)), ring[:, 1]]]
            + [np.c_[np.zeros(len(ring)), ring]]
        )
    radius, length = shape.dims
    ring = np.c_[np.cos(angles), np.sin(angles)] * radius * scale
    return np.vstack([np.c_[ring, np.full(len(ring), z)] for z in np.linspace(-length / 2, length / 2, _RINGS)])


class RobotSilhouette:
    """The robot's shapes (URDF visuals + the magnet) and their image in a camera."""

    def __init__(self, urdf_path: str, tcp_length: float, tool_frame: str = "tool0"):
        self.model = pin.buildModelFromUrdf(urdf_path)
        self.data = self.model.createData()
        self.shapes = urdf_visual_shapes(urdf_path) + [magnet_shape(tcp_length, tool_frame)]
        self._frames = {}
        for shape in self.shapes:
            if not self.model.existFrame(shape.link):
                raise ValueError(f"URDF {urdf_path}: no frame for link {shape.link!r}")
            self._frames[shape.link] = self.model.getFrameId(shape.link)
        self._points = [_hull_points(shape) for shape in self.shapes]
        # q index of each 1-DOF joint, by name
        self.joint_index = {
            self.model.names[j]: self.model.joints[j].idx_q
            for j in range(1, self.model.njoints)
            if self.model.joints[j].nq == 1
        }

    def configuration(self, names, positions) -> np.ndarray:
        """q from (joint names, positions) as a JointState gives them; joints not named stay 0.
        ValueError when none of the names is one of the robot's."""
        q = pin.neutral(self.model)
        known = 0
        for name, value in zip(names, positions):
            index = self.joint_index.get(name)
            if index is not None:
                q[index] = float(value)
                known += 1
        if not known:
            raise ValueError(f"none of the joints {list(names)} is one of the robot's {sorted(self.joint_index)}")
        return q

    def world_points(self, q) -> list[np.ndarray]:
        """Each shape's hull points in the base frame at configuration ``q``."""
        pin.framesForwardKinematics(self.model, self.data, np.asarray(q, float))
        out = []
        for shape, points in zip(self.shapes, self._points):
            T = self.data.oMf[self._frames[shape.link]].homogeneous @ shape.origin
            out.append(points @ T[:3, :3].T + T[:3, 3])
        return out

    def mask(self, camera, q, margin_px: float = 0.0) -> np.ndarray:
        """uint8 mask (255 = robot) of the robot at ``q`` in the posed ``camera``
        (a motion_common PinholeCamera), grown by ``margin_px``."""
        mask = np.zeros((camera.height, camera.width), np.uint8)
        T = camera.world_to_camera()
        rvec, _ = cv2.Rodrigues(T[:3, :3])
        for points in self.world_points(q):
            in_camera = points @ T[:3, :3].T + T[:3, 3]
            front = in_camera[:, 2] > camera.near
            if not np.any(front):
                continue
            visible = points[front]
            if not np.all(front):
                # A link reaching behind the camera: the solid cut at the near plane. The cut
                # face's corners lie on segments between a point in front and one behind
                # (every such point is inside the convex solid): add them all.
                za, zb = in_camera[front, 2][:, None], in_camera[~front, 2][None, :]
                s = (za - camera.near * 1.01) / (za - zb)  # fraction from the front point
                a, b = points[front][:, None, :], points[~front][None, :, :]
                visible = np.vstack([visible, (a + s[..., None] * (b - a)).reshape(-1, 3)])
            pixels, _ = cv2.projectPoints(visible, rvec, T[:3, 3], camera.K, camera.distortion)
            pixels = pixels.reshape(-1, 2)
            # Far outside the image only the hull's direction matters: clamp to keep int32 sane.
            pixels = np.clip(pixels, -4 * camera.width, 5 * camera.width)
            hull = cv2.convexHull(np.round(pixels * 16).astype(np.int32))
            cv2.fillConvexPoly(mask, hull, 255, lineType=cv2.LINE_8, shift=4)
        if margin_px > 0 and mask.any():
            size = 2 * int(math.ceil(margin_px)) + 1
            mask = cv2.dilate(mask, cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (size, size)))
        return mask
