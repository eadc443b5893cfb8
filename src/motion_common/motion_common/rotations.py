"""Quaternions and rotation matrices, in plain numpy and Python floats (no pinocchio, no ROS).

Conventions, everywhere in the framework:

- a quaternion is (x, y, z, w): the vector part first, the scalar last, as in
  geometry_msgs/Quaternion, scipy's ``Rotation.as_quat`` and Eigen's ``coeffs()``;
  q and -q are the same rotation;
- a rotation matrix is 3x3 and rotates column vectors (``v' = R @ v``); its columns are
  the rotated frame's axes expressed in the fixed frame;
- "unit" means a norm within ``UNIT_QUATERNION_TOLERANCE`` of 1: values that crossed the
  wire as float32, or were typed into a file with four decimals, pass; a quaternion that
  was not produced as a rotation does not.

The per-frame callers (sequencer, teleop core) run these on every hand frame, so the
checks work on plain floats: numpy's per-call overhead on a 4-vector costs more than the
arithmetic (see ``motion_common.float_list``). ``matrix_to_quaternion`` replaces
``pinocchio.Quaternion(matrix)``, which allocates memory it never frees on every call, and
gives the same numbers (the same branches and the same operations as Eigen's conversion).
"""

import math

import numpy as np

__all__ = [
    "UNIT_QUATERNION_TOLERANCE",
    "quaternion_norm",
    "is_unit_quaternion",
    "multiply_quaternions",
    "matrix_to_quaternion",
    "with_positive_w",
]

#: Quaternions further than this from unit norm were not produced as rotations.
UNIT_QUATERNION_TOLERANCE = 1e-3


def quaternion_norm(quaternion) -> float:
    """Euclidean norm of a quaternion given as four numbers (x, y, z, w)."""
    x, y, z, w = quaternion
    return math.sqrt(x * x + y * y + z * z + w * w)


def is_unit_quaternion(quaternion, tolerance: float = UNIT_QUATERNION_TOLERANCE) -> bool:
    """True when four finite numbers (x, y, z, w) have a norm within ``tolerance`` of 1.

    Pass plain floats on a per-frame path (``float_list``); a numpy array works too. A
    non-finite component makes the answer False."""
    return abs(quaternion_norm(quaternion) - 1.0) <= tolerance


def multiply_quaternions(a, b) -> tuple:
    """Hamilton product a * b of quaternions (x, y, z, w), as a tuple of floats: the
    rotation b first, then a (as matrices: R(a) @ R(b)). Pass plain floats."""
    ax, ay, az, aw = a
    bx, by, bz, bw = b
    return (
        aw * bx + ax * bw + ay * bz - az * by,
        aw * by - ax * bz + ay * bw + az * bx,
        aw * bz + ax * by - ay * bx + az * bw,
        aw * bw - ax * bx - ay * by - az * bz,
    )


def matrix_to_quaternion(matrix) -> np.ndarray:
    """Quaternion (x, y, z, w) of a 3x3 rotation matrix, by Shepperd's method.

    The component computed from a square root is the largest one that the diagonal
    reveals: w when the trace is positive (then w > 0), otherwise the axis of the largest
    diagonal element (then that component is > 0); the other three follow from sums and
    differences of the off-diagonal elements. The result has the norm the matrix implies
    (1 to rounding for a rotation) and is not renormalised, so it equals Eigen's (and
    pinocchio's) conversion of the same matrix to the last few bits.
    """
    m = np.asarray(matrix, dtype=float).reshape(3, 3).tolist()
    trace = m[0][0] + m[1][1] + m[2][2]
    if trace > 0.0:
        root = math.sqrt(trace + 1.0)
        w = 0.5 * root
        scale = 0.5 / root
        return np.array([(m[2][1] - m[1][2]) * scale, (m[0][2] - m[2][0]) * scale, (m[1][0] - m[0][1]) * scale, w])
    i = 0
    if m[1][1] > m[0][0]:
        i = 1
    if m[2][2] > m[i][i]:
        i = 2
    j, k = (i + 1) % 3, (i + 2) % 3
    root = math.sqrt(m[i][i] - m[j][j] - m[k][k] + 1.0)
    scale = 0.5 / root
    quaternion = [0.0, 0.0, 0.0, (m[k][j] - m[j][k]) * scale]
    quaternion[i] = 0.5 * root
    quaternion[j] = (m[j][i] + m[i][j]) * scale
    quaternion[k] = (m[k][i] + m[i][k]) * scale
    return np.array(quaternion)


def with_positive_w(quaternion) -> np.ndarray:
    """The same rotation with w >= 0 (the quaternion negated when w < 0), as an array."""
    quaternion = np.asarray(quaternion, dtype=float)
    return -quaternion if quaternion[3] < 0 else quaternion
