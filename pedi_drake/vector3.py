"""Small 3D helpers for code that runs every control tick.

numpy's general routines pay for their generality on 3-vectors: `np.cross` costs about 12 us a
call (axis handling), the scalar form below about 1 us. Likewise a quaternion's rotation matrix
through pydrake (Quaternion, RotationMatrix) costs about 5 us, the scalar form 1.4 us. The
sensors, the estimator and the controller call these a few times every tick, at 500-1000 Hz.
"""

import numpy as np


def cross3(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """a x b for two 3-vectors (same result as np.cross)."""
    return np.array([a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]])


def axis_angle_matrix(axis_angle: np.ndarray) -> np.ndarray:
    """Rodrigues: the (3, 3) rotation by |axis_angle| [rad] about axis_angle / |axis_angle|."""
    angle = float(np.linalg.norm(axis_angle))
    if angle < 1e-12:
        return np.eye(3)
    x, y, z = np.asarray(axis_angle, dtype=float) / angle
    K = np.array([[0.0, -z, y], [z, 0.0, -x], [-y, x, 0.0]])
    return np.eye(3) + np.sin(angle) * K + (1.0 - np.cos(angle)) * (K @ K)


def rotation_matrix_wxyz(quaternion: np.ndarray) -> np.ndarray:
    """The (3, 3) rotation matrix of a quaternion (w, x, y, z), normalised here (any non-zero norm).

    Same result as RotationMatrix(Quaternion(q / |q|)).matrix() to rounding.
    """
    w, x, y, z = np.asarray(quaternion, dtype=float).tolist()
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
