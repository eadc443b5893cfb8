"""pinocchio kinematics of the shipped UR models: FK against the DH numbers, IK round trips."""

import numpy as np
import pytest

from motion_common.errors import RobotModelError
from motion_common.kinematics import RobotKinematics, pose_to_se3, se3_to_pose, singular_values, solve_positive_definite

from ..conftest import HOME, UR5E, UR10E


@pytest.fixture(scope="module")
def ur5e():
    return RobotKinematics(UR5E)


def test_zero_pose_matches_ur5e_dh(ur5e):
    # Stretched arm: x = a2 + a3, y = -(d4 + d6), z = d1 - d5 (UR's published DH).
    position, _ = ur5e.forward_pose(np.zeros(6))
    np.testing.assert_allclose(position, [-0.425 - 0.3922, -(0.1333 + 0.0996), 0.1625 - 0.0997], atol=1e-9)


def test_ur10e_loads_with_its_own_dimensions():
    kin = RobotKinematics(UR10E)
    position, _ = kin.forward_pose(np.zeros(6))
    assert position[0] == pytest.approx(-0.6127 - 0.57155)
    assert kin.dof == 6 and kin.joint_names[0] == "shoulder_pan_joint"


def test_home_points_the_tool_down(ur5e):
    transform = ur5e.forward(HOME)
    np.testing.assert_allclose(transform.rotation[:, 2], [0, 0, -1], atol=1e-9)


def test_ik_round_trip_on_random_reachable_poses(ur5e, rng):
    for _ in range(50):
        goal_q = HOME + rng.uniform(-0.4, 0.4, 6)
        target = ur5e.forward(goal_q)
        seed = goal_q + rng.uniform(-0.1, 0.1, 6)
        result = ur5e.solve_ik(target, seed)
        assert result.success, result
        reached = ur5e.forward(result.joints)
        assert np.linalg.norm(reached.translation - target.translation) < 1e-4
        assert ur5e.within_limits(result.joints)


def test_ik_on_a_continuous_path_converges_every_step(ur5e):
    q = HOME.copy()
    start, _ = ur5e.forward_pose(q)
    _, orientation = ur5e.forward_pose(q)
    for t in np.linspace(0, 1, 200):
        target = pose_to_se3(start + [0.1 * np.sin(2 * np.pi * t), 0.15 * t, -0.05 * t], orientation)
        result = ur5e.solve_ik(target, q)
        assert result.success and result.iterations <= 5
        q = result.joints


def test_a_prepared_seed_gives_the_solve_of_the_seed_itself(ur5e, rng):
    # The teleop core prepares the IK's first step at its seed before the frame arrives;
    # the solve must come out exactly as without it, also for a seed outside the limits
    # (clipped first) and for targets needing several iterations.
    iterations = set()
    for k in range(40):
        seed = HOME + rng.uniform(-0.3, 0.3, 6)
        if k == 0:
            seed[1] = ur5e.upper[1] + 0.5  # outside the limits: the prepared seed is clipped too
        target = ur5e.forward(seed + rng.uniform(-0.08, 0.08, 6))
        plain = ur5e.solve_ik(target, seed)
        prepared = ur5e.solve_ik(target, seed, prepared=ur5e.prepare_seed(seed))
        assert prepared.success == plain.success and prepared.iterations == plain.iterations
        np.testing.assert_array_equal(prepared.joints, plain.joints)
        iterations.add(plain.iterations)
    assert len(iterations) >= 2, "every solve took the same path: the test shows little"
    # Already at the target: the prepared pose alone answers, with no iteration.
    result = ur5e.solve_ik(ur5e.forward(HOME), HOME, prepared=ur5e.prepare_seed(HOME))
    assert result.success and result.iterations == 0


def test_unreachable_target_fails_inside_limits(ur5e):
    result = ur5e.solve_ik(pose_to_se3([3.0, 0.0, 0.5], [0, 0, 0, 1]), HOME)
    assert not result.success and result.position_error > 1.0
    assert ur5e.within_limits(result.joints)


def test_pose_conversions_round_trip():
    position, quat = np.array([0.1, -0.2, 0.3]), np.array([0.0, 0.0, np.sin(0.4), np.cos(0.4)])
    back_position, back_quat = se3_to_pose(pose_to_se3(position, quat))
    np.testing.assert_allclose(back_position, position)
    np.testing.assert_allclose(back_quat, quat, atol=1e-12)


def test_quaternion_to_matrix_normalises_and_matches_scipy(rng):
    from scipy.spatial.transform import Rotation

    from motion_common.kinematics import matrix_to_quat, quat_to_matrix

    for _ in range(20):
        quat = rng.normal(size=4)
        expected = Rotation.from_quat(quat / np.linalg.norm(quat)).as_matrix()
        np.testing.assert_allclose(quat_to_matrix(quat), expected, atol=1e-12)  # array, not unit
        np.testing.assert_allclose(quat_to_matrix(quat.tolist()), expected, atol=1e-12)  # list of floats
        back = matrix_to_quat(expected)
        np.testing.assert_allclose(abs(back @ quat) / np.linalg.norm(quat), 1.0, atol=1e-12)
    with pytest.raises(ValueError, match="no direction"):
        quat_to_matrix([0.0, 0.0, 0.0, 0.0])


def test_bad_model_inputs_are_explained(tmp_path):
    with pytest.raises(RobotModelError, match="does not exist"):
        RobotKinematics(str(tmp_path / "none.urdf"))
    with pytest.raises(RobotModelError, match="no frame"):
        RobotKinematics(UR5E, tool_frame="gripper_tip")


TX90 = UR5E.replace("ur5e", "tx90")


def test_tx90_zero_pose_is_upright_with_its_offsets():
    kin = RobotKinematics(TX90)
    position, _ = kin.forward_pose(np.zeros(6))
    # 50 mm shoulder offset, 50 mm elbow offset, 478 + 425 + 425 + 100 mm tall.
    np.testing.assert_allclose(position, [0.05, 0.05, 1.428], atol=1e-9)
    assert kin.joint_names == [f"joint_{i}" for i in range(1, 7)]


@pytest.mark.parametrize(
    "urdf, home",
    [
        (UR10E, HOME),
        (TX90, np.array([0.0, 0.4, 1.6, 0.0, 1.14, 0.0])),
    ],
)
def test_ik_round_trip_on_every_shipped_robot(urdf, home, rng):
    kin = RobotKinematics(urdf)
    for _ in range(30):
        goal = home + rng.uniform(-0.3, 0.3, 6)
        result = kin.solve_ik(kin.forward(goal), goal + rng.uniform(-0.05, 0.05, 6))
        assert result.success and kin.within_limits(result.joints)


def test_positive_definite_solve_matches_lu_and_falls_back_when_not_definite():
    rng = np.random.default_rng(3)
    jac = rng.normal(size=(6, 6))
    spd = jac @ jac.T + 1e-4 * np.eye(6)
    vector = rng.normal(size=6)
    np.testing.assert_allclose(solve_positive_definite(spd, vector), np.linalg.solve(spd, vector), rtol=1e-9)
    # Symmetric but indefinite: Cholesky fails, LU still answers correctly.
    indefinite = np.diag([2.0, -1.0, 3.0, 1.0, -4.0, 5.0])
    solution = solve_positive_definite(indefinite, vector)
    np.testing.assert_allclose(indefinite @ solution, vector, rtol=1e-12)


def test_singular_values_match_numpy_largest_first():
    rng = np.random.default_rng(4)
    matrix = rng.normal(size=(6, 6))
    values = singular_values(matrix)
    np.testing.assert_allclose(values, np.linalg.svd(matrix, compute_uv=False), rtol=1e-12)
    assert values[0] >= values[-1] > 0
