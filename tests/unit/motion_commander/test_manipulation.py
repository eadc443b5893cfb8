"""The paper's API, the motion vocabulary and pick-and-place, on the real simulation driver."""

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from hw_interface.dispatcher import CommandDispatcher
from hw_interface.errors import HwInterfaceError
from hw_interface.protocol import CommandIndex, Result
from hw_interface.sim_driver import PybulletSimDriver
from motion_commander.errors import MotionCommanderError
from motion_commander.manipulation import ManipulationAPI

from ..conftest import HOME, UR5E


class DispatcherController:
    """The client interface over a CommandDispatcher: what the server does, without ROS."""

    def __init__(self, dispatcher):
        self.dispatcher = dispatcher

    def _call(self, command, **kw):
        answer = self.dispatcher.handle(command, **kw)
        if answer.result != Result.SUCCESS:
            raise HwInterfaceError(answer.reason, answer.result)
        return answer

    def get_joints(self):
        return self._call(CommandIndex.GET_ROBOT_JOINTS).joints

    def get_pose(self):
        answer = self._call(CommandIndex.GET_ROBOT_CARTESIAN_POSITION)
        return answer.position, answer.orientation

    def move_j(self, joints):
        self._call(CommandIndex.MOVE_J, joints=joints)

    def move_l(self, position, orientation):
        self._call(CommandIndex.MOVE_L, position=position, orientation=orientation)

    def set_gripper(self, closed):
        self._call(CommandIndex.SET_GRIPPER, joints=[1.0 if closed else 0.0])


@pytest.fixture(scope="module")
def setup():
    scene = [
        {"name": "floor", "urdf": "plane.urdf", "fixed": True},
        {"name": "part", "box": [0.02, 0.02, 0.02], "mass": 0.05, "position": [-0.45, -0.20, 0.02]},
    ]
    sim = PybulletSimDriver(UR5E, initial_joints=HOME, real_time=False, scene=scene)
    sim.login()
    api = ManipulationAPI(DispatcherController(CommandDispatcher(sim)))
    yield sim, api
    sim.disconnect()


def test_paper_calls(setup):
    sim, api = setup
    api.move_j(HOME)
    np.testing.assert_allclose(api.info_get_joints(), HOME, atol=2e-3)
    position, orientation = api.info_getPose()
    assert api.motion_setPose((position + [0.03, 0.02, -0.05], orientation))
    np.testing.assert_allclose(api.info_getPose()[0], position + [0.03, 0.02, -0.05], atol=2e-3)
    assert not api.motion_setPose((position + [5.0, 0.0, 0.0], orientation))
    assert "workspace" in api.last_error or "unreachable" in api.last_error.lower()


def test_vocabulary(setup):
    sim, api = setup
    api.move_j(HOME)
    api.move_r(0, 0.2)
    np.testing.assert_allclose(api.info_get_joints(), HOME + [0.2, 0, 0, 0, 0, 0], atol=2e-3)
    start, orientation = api.info_getPose()
    api.move_l([0.0, 0.05, -0.03])
    np.testing.assert_allclose(api.info_getPose()[0], start + [0.0, 0.05, -0.03], atol=2e-3)
    before = Rotation.from_quat(api.info_getPose()[1])
    api.move_rot([0.0, 0.0, 0.3])
    position, after = api.info_getPose()
    assert (before.inv() * Rotation.from_quat(after)).magnitude() == pytest.approx(0.3, abs=5e-3)
    pivot = position + [0.0, 0.0, -0.1]  # 10 cm below the flange, e.g. a held part's tip
    api.move_rp([0.0, 0.2, 0.0], pivot)
    moved, _ = api.info_getPose()
    assert np.linalg.norm(moved - pivot) == pytest.approx(0.1, abs=2e-3)
    with pytest.raises(MotionCommanderError):
        api.move_r(9, 0.1)


def test_pick_and_place_moves_the_part(setup):
    sim, api = setup
    api.move_j(HOME)
    down = Rotation.from_euler("x", np.pi).as_quat()  # tool pointing down
    part, _ = sim.body_pose("part")
    api.pick_and_place(part + [0.0, 0.0, 0.025], [-0.45, 0.05, 0.045], down)
    moved, _ = sim.body_pose("part")
    np.testing.assert_allclose(moved[:2], [-0.45, 0.05], atol=0.01)
    assert moved[2] < 0.05 and sim.gripped_body is None
