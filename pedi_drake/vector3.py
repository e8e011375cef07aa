"""Small 3D helpers for code that runs every control tick, in Python and in compiled kernels.

numpy's general routines pay for their generality on 3-vectors: `np.cross` spends most of a
call on axis handling, and a quaternion's rotation matrix through pydrake (Quaternion,
RotationMatrix) on building objects; the scalar forms below do neither. The sensors, the
estimator and the controllers call these a few times every tick, at 500-1000 Hz.

Each rotation helper is a compiled kernel (`*_kernel`, for other kernels: the controllers'
compiled ticks) with a Python function on top that takes any array-like; both are the same code.
"""

import math

import numpy as np

from pedi_drake.runtime.jit import kernel


def cross3(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """a x b for two 3-vectors (same result as np.cross)."""
    return np.array([a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]])


@kernel
def axis_angle_kernel(axis_angle: np.ndarray) -> np.ndarray:
    """Rodrigues: the (3, 3) rotation by |axis_angle| [rad] about axis_angle / |axis_angle|."""
    angle = math.sqrt(axis_angle[0] ** 2 + axis_angle[1] ** 2 + axis_angle[2] ** 2)
    if angle < 1e-12:
        return np.eye(3)
    x, y, z = axis_angle[0] / angle, axis_angle[1] / angle, axis_angle[2] / angle
    K = np.array([[0.0, -z, y], [z, 0.0, -x], [-y, x, 0.0]])
    return np.eye(3) + math.sin(angle) * K + (1.0 - math.cos(angle)) * (K @ K)


def axis_angle_matrix(axis_angle: np.ndarray) -> np.ndarray:
    """Rodrigues: the (3, 3) rotation by |axis_angle| [rad] about axis_angle / |axis_angle|."""
    return axis_angle_kernel(np.array(axis_angle, dtype=float))


@kernel
def rotation_matrix_kernel(quaternion: np.ndarray) -> np.ndarray:
    """The (3, 3) rotation matrix of a quaternion (w, x, y, z), normalised here (any non-zero norm)."""
    w, x, y, z = quaternion[0], quaternion[1], quaternion[2], quaternion[3]
    s = 2.0 / (w * w + x * x + y * y + z * z)
    xx, yy, zz = x * x * s, y * y * s, z * z * s
    xy, xz, yz = x * y * s, x * z * s, y * z * s
    wx, wy, wz = w * x * s, w * y * s, w * z * s
    return np.array(
        [
            [1.0 - yy - zz, xy - wz, xz + wy],
            [xy + wz, 1.0 - xx - zz, yz - wx],
            [xz - wy, yz + wx, 1.0 - xx - yy],
        ]
    )


def rotation_matrix_wxyz(quaternion: np.ndarray) -> np.ndarray:
    """The (3, 3) rotation matrix of a quaternion (w, x, y, z), normalised here (any non-zero norm).

    Same result as RotationMatrix(Quaternion(q / |q|)).matrix() to rounding.
    """
    return rotation_matrix_kernel(np.array(quaternion, dtype=float))


@kernel
def orientation_error_kernel(R_ref: np.ndarray, R: np.ndarray, out: np.ndarray) -> None:
    """Rotation vector of R_ref R^T (world frame) [rad] into out (3,): the rotation taking R to R_ref."""
    E = R_ref @ R.T
    cos_angle = min(max((E[0, 0] + E[1, 1] + E[2, 2] - 1.0) / 2.0, -1.0), 1.0)
    angle = math.acos(cos_angle)
    out[0] = (E[2, 1] - E[1, 2]) / 2.0
    out[1] = (E[0, 2] - E[2, 0]) / 2.0
    out[2] = (E[1, 0] - E[0, 1]) / 2.0
    if angle >= 1e-9:
        scale = angle / math.sin(angle)
        for i in range(3):
            out[i] *= scale


def orientation_error_W(R_ref: np.ndarray, R: np.ndarray) -> np.ndarray:
    """Rotation vector of R_ref R^T (world frame) [rad]: the rotation taking R to R_ref."""
    out = np.empty(3)
    orientation_error_kernel(np.array(R_ref, dtype=float), np.array(R, dtype=float), out)
    return out
