"""Fast forward kinematics of the four Go1 legs for the state estimator: foot positions and velocities.

The estimator needs every foot's position and Jacobian in the trunk frame at 500 Hz. The general
`pedi_drake.leg_kinematics` functions build rotation matrices with numpy, too slow at that rate;
the Go1's legs have the structure hip about x, thigh and calf about y, with unrotated joint
frames, so the same quantities follow from a few sines and cosines, compiled (`pedi_drake.runtime.jit`,
one call for all four legs). The offsets come from the model through `leg_geometry`, so there is still one
source of truth.
"""

import functools
import math

import numpy as np

from pedi_drake import robot
from pedi_drake.exceptions import PediError
from pedi_drake.leg_kinematics import leg_geometry
from pedi_drake.runtime.jit import kernel


@functools.lru_cache(maxsize=1)
def leg_offsets() -> np.ndarray:
    """(4, 4, 3) per leg (Unitree order): p_BH, p_HT, p_TC, p_CF [m] (read-only)."""
    legs = []
    for leg in robot.LEG_NAMES:
        g = leg_geometry(leg)
        expected = np.array([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 1.0, 0.0]])
        if not np.allclose(g.axes, expected):
            raise PediError(f"{leg}: leg odometry expects joint axes x, y, y; the model has {g.axes.tolist()}")
        legs.append([g.p_BH, g.p_HT, g.p_TC, g.p_CF])
    offsets = np.array(legs, dtype=float)
    offsets.flags.writeable = False
    return offsets


@kernel
def foot_kinematics_kernel(q, offsets):
    """`foot_kinematics_B` on plain arrays: q (12,) [rad], offsets (4, 4, 3) from `leg_offsets`."""
    positions = np.empty((4, 3))
    jacobians = np.empty((4, 3, 3))
    for i in range(4):
        p_BH, p_HT, p_TC, p_CF = offsets[i, 0], offsets[i, 1], offsets[i, 2], offsets[i, 3]
        c0, s0 = math.cos(q[3 * i]), math.sin(q[3 * i])
        c1, s1 = math.cos(q[3 * i + 1]), math.sin(q[3 * i + 1])
        c2, s2 = math.cos(q[3 * i + 2]), math.sin(q[3 * i + 2])
        # Rotations about y (thigh, calf): (c x + s z, y, -s x + c z); about x (hip): (x, c y - s z, s y + c z).
        f0, f1, f2 = c2 * p_CF[0] + s2 * p_CF[2], p_CF[1], -s2 * p_CF[0] + c2 * p_CF[2]  # calf link, thigh frame
        v0, v1, v2 = p_TC[0] + f0, p_TC[1] + f1, p_TC[2] + f2  # thigh joint -> foot, thigh frame
        rv0, rv1, rv2 = c1 * v0 + s1 * v2, v1, -s1 * v0 + c1 * v2
        w0, w1, w2 = p_HT[0] + rv0, p_HT[1] + rv1, p_HT[2] + rv2  # hip joint -> foot, hip frame
        rw0, rw1, rw2 = w0, c0 * w1 - s0 * w2, s0 * w1 + c0 * w2
        positions[i, 0], positions[i, 1], positions[i, 2] = p_BH[0] + rw0, p_BH[1] + rw1, p_BH[2] + rw2
        # d/dq0: x x (Rx w); d/dq1: Rx (y x Ry v); d/dq2: Rx Ry1 (y x Ry2 p_CF). (y x u = (u_z, 0, -u_x))
        d10, d11, d12 = rv2, -s0 * -rv0, c0 * -rv0
        e0, e2 = f2, -f0
        g0, g1, g2 = c1 * e0 + s1 * e2, 0.0, -s1 * e0 + c1 * e2
        d20, d21, d22 = g0, c0 * g1 - s0 * g2, s0 * g1 + c0 * g2
        jacobians[i, 0, 0], jacobians[i, 0, 1], jacobians[i, 0, 2] = 0.0, d10, d20
        jacobians[i, 1, 0], jacobians[i, 1, 1], jacobians[i, 1, 2] = -rw2, d11, d21
        jacobians[i, 2, 0], jacobians[i, 2, 1], jacobians[i, 2, 2] = rw1, d12, d22
    return positions, jacobians


def foot_kinematics_B(q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Foot centres p_BF (4, 3) [m] and their Jacobians J (4, 3, 3) wrt each leg's joints, trunk frame.

    `q` holds the 12 joint angles in Unitree order [rad].
    """
    return foot_kinematics_kernel(np.asarray(q, dtype=float), leg_offsets())
