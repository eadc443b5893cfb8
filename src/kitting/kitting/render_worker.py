"""Rendering in its own process: TinyRenderer holds the interpreter for ~100 ms per
640x480 image, so a node steps physics in one process and renders in another.

``RenderWorker`` starts a process (this module, run by the same interpreter) that owns a pybullet DIRECT
client with the cell built in it (``SimScene``). Each request sends the part poses
(``SimScene.part_poses()``) and an optional camera pose; the worker mirrors them, renders
and sends back the RGB image with the stamp it was asked for (the image shows the scene
at that stamp).

A real camera's image (``kitting.camera_effects``), each part of it optional per request:
the robot arm (the cell's robot URDF, loaded at the first request that gives joints,
posed from them) and the magnet on its tool (``robot_silhouette.magnet_shape``), so they
hide parts and markers as they do for a real camera; the belt's parts smeared by the
motion during the exposure; the exposure's gain, offset and gamma."""

import os
import subprocess
import sys
import tempfile
import threading
from multiprocessing.connection import Client, Listener

import numpy as np

__all__ = ["RenderWorker", "RobotBody", "realistic_image"]


def _serve(connection, cell_path, width, height, supersample):
    from motion_common.camera_model import PinholeCamera
    from motion_common.quiet_pybullet import connect
    from motion_common.quiet_pybullet import pybullet as p

    from .cell import load_cell
    from .sim_scene import SimScene

    client = connect(p.DIRECT)
    cell = load_cell(cell_path) if cell_path else load_cell()
    scene = SimScene(client, cell)
    camera = PinholeCamera.from_spec(cell.camera)
    if width and height:
        camera = camera.scaled(width, height)
    robot = None
    connection.send(("ready", None, None))
    while True:
        try:
            message = connection.recv()
        except EOFError:
            break  # the parent is gone
        if message is None:
            break
        stamp, poses, camera_pose, lighting, joints, blur, exposure = message
        scene.set_part_poses(poses)
        if joints is not None and robot is None:
            robot = RobotBody(client, cell)
        if robot is not None:
            robot.pose(joints)
        view = camera if camera_pose is None else camera.with_pose(camera_pose)
        image = realistic_image(client, scene, cell, view, lighting, supersample, blur, exposure)
        connection.send(("image", stamp, image))
    p.disconnect(client)


class RobotBody:
    """The cell's robot (its URDF's visuals) and the magnet under tool0, in the render client."""

    def __init__(self, client, cell):
        from motion_common.quiet_pybullet import pybullet as p

        from .robot_silhouette import MAGNET_RGBA, magnet_shape, robot_urdf

        self.client, self.p = client, p
        self.body = p.loadURDF(robot_urdf(cell.robot), useFixedBase=True, physicsClientId=client)
        self.joints, self.tool = {}, None
        for index in range(p.getNumJoints(self.body, physicsClientId=client)):
            info = p.getJointInfo(self.body, index, physicsClientId=client)
            if info[2] in (p.JOINT_REVOLUTE, p.JOINT_PRISMATIC):
                self.joints[info[1].decode()] = index
            if info[12].decode() == "tool0":
                self.tool = index
        self.magnet = magnet_shape(cell.gripper.tcp_length)
        radius, length = self.magnet.dims
        visual = p.createVisualShape(
            p.GEOM_CYLINDER, radius=radius, length=length, rgbaColor=list(MAGNET_RGBA), physicsClientId=client
        )
        self.magnet_body = p.createMultiBody(0.0, -1, visual, physicsClientId=client)
        self.hidden = False

    def pose(self, joints):
        """Put the arm at ``joints`` ((names, positions)); None: out of the camera's view."""
        p, c = self.p, self.client
        if joints is None:
            if not self.hidden:  # below the floor, beyond the camera's far plane
                p.resetBasePositionAndOrientation(self.body, [0, 0, -100], [0, 0, 0, 1], physicsClientId=c)
                p.resetBasePositionAndOrientation(self.magnet_body, [0, 0, -100], [0, 0, 0, 1], physicsClientId=c)
                self.hidden = True
            return
        if self.hidden:
            p.resetBasePositionAndOrientation(self.body, [0, 0, 0], [0, 0, 0, 1], physicsClientId=c)
            self.hidden = False
        for name, value in zip(*joints):
            index = self.joints.get(name)
            if index is not None:
                p.resetJointState(self.body, index, float(value), physicsClientId=c)
        if self.tool is not None:
            position, orientation = p.getLinkState(
                self.body, self.tool, computeForwardKinematics=True, physicsClientId=c
            )[4:6]
            offset = self.magnet.origin[:3, 3].tolist()
            centre, _ = p.multiplyTransforms(position, orientation, offset, [0, 0, 0, 1])
            p.resetBasePositionAndOrientation(self.magnet_body, centre, orientation, physicsClientId=c)


def realistic_image(client, scene, cell, view, lighting, supersample, blur, exposure):
    """Render ``view``; with ``blur`` = (exposure time s, belt speed m/s) smear the belt's
    parts, with ``exposure`` (camera_effects.Exposure) apply it."""
    from .camera import render
    from .camera_effects import apply_exposure, belt_direction_px, motion_blur

    if blur is None:
        image = render(client, view, lighting, supersample=supersample)
    else:
        image, ids = render(client, view, lighting, supersample=supersample, segmentation=True)
        exposure_time, speed = blur
        moving = [scene.body_of(pid) for pid, state in scene.parts.items() if state.on_belt]
        if moving and exposure_time * speed > 0:
            direction, px_per_m = belt_direction_px(view, cell.belt)
            image = motion_blur(image, np.isin(ids, moving), exposure_time * speed * px_per_m, direction)
    if exposure is not None:
        image = apply_exposure(image, exposure)
    return image


def main(argv=None):
    """Entry of the render process: ``python -m kitting.render_worker ADDRESS CELL W H S``
    (the authentication key comes on stdin)."""
    import signal

    # Ctrl-C reaches the whole process group; the parent ends this process itself.
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    address, cell_path, width, height, supersample = (argv or sys.argv)[1:6]
    key = sys.stdin.buffer.readline().strip()
    with Client(address, authkey=key) as connection:
        _serve(connection, cell_path or None, int(width), int(height), int(supersample))


class RenderWorker:
    """``with RenderWorker() as worker: image, stamp = worker.render(stamp, poses)``."""

    def __init__(
        self,
        cell_path: str | None = None,
        width: int | None = None,
        height: int | None = None,
        supersample: int = 1,
        timeout: float = 30.0,
    ):
        # A fresh interpreter running this module (not multiprocessing's spawn, which
        # re-imports the caller's main script: a ROS node's relay script breaks that),
        # connected over a private Unix socket.
        self._folder = tempfile.mkdtemp(prefix="kitting-render-")
        address = os.path.join(self._folder, "socket")
        key = os.urandom(16).hex().encode()
        self._listener = Listener(address, family="AF_UNIX", authkey=key)
        self._process = subprocess.Popen(
            [
                sys.executable,
                "-m",
                "kitting.render_worker",
                address,
                cell_path or "",
                str(width or 0),
                str(height or 0),
                str(int(supersample)),
            ],
            stdin=subprocess.PIPE,
            stdout=subprocess.DEVNULL,
        )
        self._process.stdin.write(key + b"\n")
        self._process.stdin.close()
        self._connection = None
        accepted = []
        waiter = threading.Thread(target=lambda: accepted.append(self._listener.accept()), daemon=True)
        waiter.start()
        waiter.join(timeout)
        if not accepted:
            self.close()  # closing the listener ends the waiting accept()
            raise RuntimeError(
                f"render worker did not connect within {timeout:.0f} s (exit code "
                f"{self._process.poll()}); run 'python -m kitting.render_worker' by hand to see why"
            )
        self._connection = accepted[0]
        if not self._connection.poll(timeout):
            self.close()
            raise RuntimeError("render worker did not start: it never said ready")
        self._connection.recv()

    def request(self, stamp: float, poses, camera_pose=None, lighting=None, joints=None, blur=None, exposure=None):
        """Ask for an image (non-blocking) of the parts at ``poses`` seen from
        ``camera_pose`` (4x4; None: the cell YAML's) under ``lighting`` (a
        kitting.camera.Lighting; None: the default); collect it with ``result``.
        ``joints``: (names, positions) of the robot arm to draw (None: no arm); ``blur``:
        (exposure time s, belt speed m/s) of the belt parts' motion blur (None: sharp);
        ``exposure``: a kitting.camera_effects.Exposure (None: the identity)."""
        if joints is not None:
            joints = (list(joints[0]), [float(v) for v in joints[1]])
        self._connection.send(
            (
                stamp,
                list(poses),
                None if camera_pose is None else np.asarray(camera_pose),
                lighting,
                joints,
                None if blur is None else (float(blur[0]), float(blur[1])),
                exposure,
            )
        )

    def result(self, timeout: float = 10.0):
        """(image, stamp) of the oldest request."""
        if not self._connection.poll(timeout):
            raise TimeoutError("render worker gave no image")
        _, stamp, image = self._connection.recv()
        return image, stamp

    def render(self, stamp: float, poses, camera_pose=None, timeout: float = 10.0, lighting=None, **realism):
        """Request and wait: (image, stamp); ``realism``: ``request``'s joints, blur, exposure."""
        self.request(stamp, poses, camera_pose, lighting, **realism)
        return self.result(timeout)

    def close(self):
        """Ask the render process to end; kill it if it does not within 5 s."""
        if self._process.poll() is None:
            try:
                if self._connection is not None:
                    self._connection.send(None)
            except (BrokenPipeError, OSError):
                pass
            try:
                self._process.wait(5.0)
            except subprocess.TimeoutExpired:
                self._process.kill()
                self._process.wait()
        self._listener.close()
        if os.path.isdir(self._folder):
            for name in os.listdir(self._folder):
                os.unlink(os.path.join(self._folder, name))
            os.rmdir(self._folder)

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()


if __name__ == "__main__":
    main()
