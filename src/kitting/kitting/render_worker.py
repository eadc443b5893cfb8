"""Rendering in its own process: TinyRenderer holds the interpreter for ~100 ms per
640x480 image, so a node steps physics in one process and renders in another.

``RenderWorker`` starts a ``multiprocessing`` (spawn) process that owns a pybullet DIRECT
client with the cell built in it (``SimScene``). Each request sends the part poses
(``SimScene.part_poses()``) and an optional camera pose; the worker mirrors them, renders
and sends back the RGB image with the stamp it was asked for (the image shows the scene
at that stamp)."""
import multiprocessing as mp
from typing import Optional

import numpy as np


def _serve(connection, cell_path, width, height, supersample):
    import pybullet as p
    from .camera import PinholeCamera, render
    from .cell import load_cell
    from .sim_scene import SimScene
    client = p.connect(p.DIRECT)
    cell = load_cell(cell_path) if cell_path else load_cell()
    scene = SimScene(client, cell)
    camera = PinholeCamera.from_spec(cell.camera)
    if width and height:
        camera = camera.scaled(width, height)
    connection.send(("ready", None, None))
    while True:
        message = connection.recv()
        if message is None:
            break
        stamp, poses, camera_pose, lighting = message
        scene.set_part_poses(poses)
        view = camera if camera_pose is None else camera.with_pose(camera_pose)
        connection.send(("image", stamp, render(client, view, lighting, supersample=supersample)))
    p.disconnect(client)


class RenderWorker:
    """``with RenderWorker() as worker: image, stamp = worker.render(stamp, poses)``."""

    def __init__(self, cell_path: Optional[str] = None, width: Optional[int] = None,
                 height: Optional[int] = None, supersample: int = 1, timeout: float = 30.0):
        context = mp.get_context("spawn")
        self._connection, child = context.Pipe()
        self._process = context.Process(target=_serve, args=(child, cell_path, width, height, supersample),
                                         daemon=True)
        self._process.start()
        if not self._connection.poll(timeout):
            self.close()
            raise RuntimeError("render worker did not start")
        self._connection.recv()

    def request(self, stamp: float, poses, camera_pose=None, lighting=None):
        """Ask for an image (non-blocking) of the parts at ``poses`` seen from
        ``camera_pose`` (4x4; None: the cell YAML's) under ``lighting`` (a
        kitting.camera.Lighting; None: the default); collect it with ``result``."""
        self._connection.send((stamp, list(poses), None if camera_pose is None else np.asarray(camera_pose),
                               lighting))

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
        if self._process.is_alive():
            try:
                self._connection.send(None)
            except (BrokenPipeError, OSError):
                pass
            self._process.join(5.0)
            if self._process.is_alive():
                self._process.terminate()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()
