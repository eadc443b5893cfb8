"""A camera looking at a simulated cell, rendered in a process of its own (the
``scene_camera`` node): pybullet's TinyRenderer holds its interpreter for tens of ms per
image, so it never runs in the simulation's (the server's) process, as the kitting cell's
render worker does.

The process keeps a mirror of the cell in a DIRECT client: the robot's URDF with the
measured joints (``set_joints``) and the scene's bodies (``load_scene``, the driver's own)
at the poses the server publishes (``set_body_pose``; the server's tf frames
``scene/<name>``, so a gripped part moves with the tool). ``render`` returns an RGB image.
Plain Python (pybullet), no ROS.
"""

import numpy as np

from motion_common.quiet_pybullet import bullet_client
from motion_common.quiet_pybullet import pybullet as p

from .sim_driver import load_scene

__all__ = ["SceneCamera"]


class SceneCamera:
    """Mirror of a simulated cell, rendered from one fixed viewpoint."""

    def __init__(self, urdf: str, scene_spec, width: int, height: int, eye, target, fov_deg: float = 60.0):
        self.client = bullet_client(p.DIRECT)
        self.width, self.height = int(width), int(height)
        self.robot = self.client.loadURDF(urdf, useFixedBase=True)
        self.joints = {}
        for index in range(self.client.getNumJoints(self.robot)):
            info = self.client.getJointInfo(self.robot, index)
            if info[2] in (p.JOINT_REVOLUTE, p.JOINT_PRISMATIC):
                self.joints[info[1].decode()] = index
        self.bodies = load_scene(self.client, scene_spec or [])
        self.view = p.computeViewMatrix(list(eye), list(target), [0, 0, 1])
        self.projection = p.computeProjectionMatrixFOV(fov_deg, self.width / self.height, 0.05, 10.0)

    def set_joints(self, names, positions) -> None:
        for name, value in zip(names, positions):
            index = self.joints.get(name)
            if index is not None:
                self.client.resetJointState(self.robot, index, float(value))

    def set_body_pose(self, name: str, position, orientation) -> None:
        body = self.bodies.get(name)
        if body is not None:
            self.client.resetBasePositionAndOrientation(body, list(position), list(orientation))

    def render(self) -> np.ndarray:
        """HxWx3 uint8 RGB."""
        _, _, rgba, _, _ = self.client.getCameraImage(
            self.width, self.height, self.view, self.projection, renderer=p.ER_TINY_RENDERER
        )
        return np.asarray(rgba, dtype=np.uint8).reshape(self.height, self.width, 4)[:, :, :3].copy()

    def close(self) -> None:
        self.client.disconnect()
