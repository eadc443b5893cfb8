"""Rendering in its own process: TinyRenderer holds the interpreter for ~100 ms per
640x480 image, so a node steps physics in one process and renders in another.

``RenderWorker`` starts a process (this module, run by the same interpreter) that owns a pybullet DIRECT
client with the cell built in it (``SimScene``). Each request sends the part poses
(``SimScene.part_poses()``) and an optional camera pose; the worker mirrors them, renders
and sends back the RGB image with the stamp it was asked for (the image shows the scene
at that stamp)."""

import os
import subprocess
import sys
import tempfile
import threading
from multiprocessing.connection import Client, Listener

import numpy as np


def _serve(connection, cell_path, width, height, supersample):
    from motion_common.camera_model import PinholeCamera
    from motion_common.quiet_pybullet import connect
    from motion_common.quiet_pybullet import pybullet as p

    from .camera import render
    from .cell import load_cell
    from .sim_scene import SimScene

    client = connect(p.DIRECT)
    cell = load_cell(cell_path) if cell_path else load_cell()
    scene = SimScene(client, cell)
    camera = PinholeCamera.from_spec(cell.camera)
    if width and height:
        camera = camera.scaled(width, height)
    connection.send(("ready", None, None))
    while True:
        try:
            message = connection.recv()
        except EOFError:
            break  # the parent is gone
        if message is None:
            break
        stamp, poses, camera_pose, lighting = message
        scene.set_part_poses(poses)
        view = camera if camera_pose is None else camera.with_pose(camera_pose)
        connection.send(("image", stamp, render(client, view, lighting, supersample=supersample)))
    p.disconnect(client)


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

    def request(self, stamp: float, poses, camera_pose=None, lighting=None):
        """Ask for an image (non-blocking) of the parts at ``poses`` seen from
        ``camera_pose`` (4x4; None: the cell YAML's) under ``lighting`` (a
        kitting.camera.Lighting; None: the default); collect it with ``result``."""
        self._connection.send((stamp, list(poses), None if camera_pose is None else np.asarray(camera_pose), lighting))

    def result(self, timeout: float = 10.0):
        """(image, stamp) of the oldest request."""
        if not self._connection.poll(timeout):
            raise TimeoutError("render worker gave no image")
        _, stamp, image = self._connection.recv()
        return image, stamp

    def render(self, stamp: float, poses, camera_pose=None, timeout: float = 10.0, lighting=None):
        """Request and wait: (image, stamp)."""
        self.request(stamp, poses, camera_pose, lighting)
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
