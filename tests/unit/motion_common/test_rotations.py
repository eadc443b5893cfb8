"""motion_common.rotations: the one quaternion/matrix module. Its matrix-to-quaternion
conversion replaces pinocchio's (whose matrix constructor leaks memory on every call) in the
kinematics and the teleop core, so it must give pinocchio's numbers."""

import math

import numpy as np
import pinocchio as pin
import pytest
from scipy.spatial.transform import Rotation

from motion_common.kinematics import matrix_to_quat
from motion_common.rotations import (
    UNIT_QUATERNION_TOLERANCE,
    is_unit_quaternion,
    matrix_to_quaternion,
    multiply_quaternions,
    quaternion_norm,
    with_positive_w,
)


def edge_rotations():
    """Rotations that take every branch: positive trace, and each diagonal element the
    largest with a trace <= 0 (half turns and near-half turns about each axis)."""
    out = [np.eye(3)]
    for axis in np.eye(3):
        for angle in (math.pi, math.pi - 1e-9, 0.5 * math.pi, -0.75 * math.pi, 2.0 * math.pi / 3.0):
            out.append(Rotation.from_rotvec(axis * angle).as_matrix())
    out.append(Rotation.from_rotvec(np.array([1.0, 1.0, 1.0]) / math.sqrt(3.0) * math.pi).as_matrix())
    return out


def test_matrix_to_quaternion_gives_pinocchio_numbers():
    matrices = list(Rotation.random(2000, random_state=3).as_matrix()) + edge_rotations()
    for matrix in matrices:
        expected = np.array(pin.Quaternion(matrix).coeffs())
        np.testing.assert_allclose(matrix_to_quaternion(matrix), expected, rtol=0, atol=1e-12)
        np.testing.assert_allclose(matrix_to_quat(matrix), expected, rtol=0, atol=1e-12)


def test_matrix_to_quaternion_is_the_rotation_xyzw():
    for matrix in list(Rotation.random(200, random_state=4).as_matrix()) + edge_rotations():
        q = matrix_to_quaternion(matrix)
        assert quaternion_norm(q.tolist()) == pytest.approx(1.0, abs=1e-12)
        np.testing.assert_allclose(Rotation.from_quat(q).as_matrix(), matrix, atol=1e-12)
    quarter_z = Rotation.from_rotvec([0.0, 0.0, math.pi / 2]).as_matrix()
    np.testing.assert_allclose(matrix_to_quaternion(quarter_z), [0.0, 0.0, math.sqrt(0.5), math.sqrt(0.5)])


def test_the_teleop_partial_step_rotation_matches_the_matrix_constructor():
    start = Rotation.random(random_state=5).as_quat()
    for target in Rotation.random(50, random_state=6).as_matrix():
        for fraction in (0.0, 0.3, 1.0):
            old = pin.Quaternion(start).slerp(fraction, pin.Quaternion(target)).matrix()
            new = pin.Quaternion(start).slerp(fraction, pin.Quaternion(matrix_to_quaternion(target))).matrix()
            np.testing.assert_allclose(new, old, rtol=0, atol=1e-12)


def test_unit_quaternion_check():
    assert is_unit_quaternion([0.0, 0.0, 0.0, 1.0])
    assert is_unit_quaternion(np.array([0.5, 0.5, 0.5, 0.5]))
    assert is_unit_quaternion([0.0, 0.0, 0.0, 1.0 + 0.5 * UNIT_QUATERNION_TOLERANCE])
    assert not is_unit_quaternion([0.0, 0.0, 0.0, 1.0 + 2.0 * UNIT_QUATERNION_TOLERANCE])
    assert not is_unit_quaternion([0.0, 0.0, 0.0, 0.0])
    assert not is_unit_quaternion([math.nan, 0.0, 0.0, 1.0])
    assert not is_unit_quaternion([math.inf, 0.0, 0.0, 1.0])
    assert is_unit_quaternion([0.0, 0.0, 0.0, 1.1], tolerance=0.2)
    assert quaternion_norm([1.0, 2.0, 2.0, 4.0]) == 5.0


def test_multiply_is_the_hamilton_product():
    a, b = Rotation.random(2, random_state=7)
    product = multiply_quaternions(a.as_quat().tolist(), b.as_quat().tolist())
    assert isinstance(product, tuple) and all(isinstance(v, float) for v in product)
    np.testing.assert_allclose(Rotation.from_quat(product).as_matrix(), (a * b).as_matrix(), atol=1e-12)


def test_with_positive_w():
    np.testing.assert_array_equal(with_positive_w([0.0, 0.6, 0.0, -0.8]), [-0.0, -0.6, -0.0, 0.8])
    np.testing.assert_array_equal(with_positive_w([0.0, 0.6, 0.0, 0.8]), [0.0, 0.6, 0.0, 0.8])
