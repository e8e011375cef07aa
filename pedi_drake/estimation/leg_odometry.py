"""Fast forward kinematics of the four Go1 legs for the state estimator: foot positions and velocities.

The estimator needs every foot's position and Jacobian in the trunk frame at 500 Hz. The general
`pedi_drake.leg_kinematics` functions build rotation matrices with numpy (~170 us a leg); the Go1's
legs have the structure hip about x, thigh and calf about y, with unrotated joint frames, so the
same quantities follow from a few sines and cosines (~10 us a leg). The offsets come from the
model through `leg_geometry`, so there is still one source of truth.
"""

import dataclasses
import functools
import math

import numpy as np

from pedi_drake import robot
from pedi_drake.exceptions import PediError
from pedi_drake.leg_kinematics import leg_geometry


@dataclasses.dataclass(frozen=True)
class _LegOffsets:
    p_BH: tuple[float, float, float]
    p_HT: tuple[float, float, float]
    p_TC: tuple[float, float, float]
    p_CF: tuple[float, float, float]


@functools.lru_cache(maxsize=1)
def _offsets() -> tuple[_LegOffsets, ...]:
    legs = []
    for leg in robot.LEG_NAMES:
        g = leg_geometry(leg)
        expected = np.array([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 1.0, 0.0]])
        if not np.allclose(g.axes, expected):
            raise PediError(f"{leg}: leg odometry expects joint axes x, y, y; the model has {g.axes.tolist()}")
        legs.append(_LegOffsets(*(tuple(float(v) for v in p) for p in (g.p_BH, g.p_HT, g.p_TC, g.p_CF))))
    return tuple(legs)


def _rot_y(c: float, s: float, v: tuple[float, float, float]) -> tuple[float, float, float]:
    return (c * v[0] + s * v[2], v[1], -s * v[0] + c * v[2])


def _rot_x(c: float, s: float, v: tuple[float, float, float]) -> tuple[float, float, float]:
    return (v[0], c * v[1] - s * v[2], s * v[1] + c * v[2])


def foot_kinematics_B(q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Foot centres p_BF (4, 3) [m] and their Jacobians J (4, 3, 3) wrt each leg's joints, trunk frame.

    `q` holds the 12 joint angles in Unitree order [rad].
    """
    q = np.asarray(q, dtype=float).tolist()
    # Python floats throughout, one array each at the end: numpy calls per leg cost more than the maths.
    positions, jacobians = [], []
    for i, o in enumerate(_offsets()):
        q0, q1, q2 = q[3 * i : 3 * i + 3]
        c0, s0 = math.cos(q0), math.sin(q0)
        c1, s1 = math.cos(q1), math.sin(q1)
        c2, s2 = math.cos(q2), math.sin(q2)
        f = _rot_y(c2, s2, o.p_CF)  # calf link, in the thigh frame after the calf joint
        v = (o.p_TC[0] + f[0], o.p_TC[1] + f[1], o.p_TC[2] + f[2])  # thigh joint -> foot, thigh frame
        rv = _rot_y(c1, s1, v)
        w = (o.p_HT[0] + rv[0], o.p_HT[1] + rv[1], o.p_HT[2] + rv[2])  # hip joint -> foot, hip frame
        rw = _rot_x(c0, s0, w)
        positions.append((o.p_BH[0] + rw[0], o.p_BH[1] + rw[1], o.p_BH[2] + rw[2]))
        # d/dq0: x x (Rx w); d/dq1: Rx (y x Ry v); d/dq2: Rx Ry1 (y x Ry2 p_CF). (y x u = (u_z, 0, -u_x))
        d1 = _rot_x(c0, s0, (rv[2], 0.0, -rv[0]))
        d2 = _rot_x(c0, s0, _rot_y(c1, s1, (f[2], 0.0, -f[0])))
        jacobians.append(((0.0, d1[0], d2[0]), (-rw[2], d1[1], d2[1]), (rw[1], d1[2], d2[2])))
    return np.array(positions), np.array(jacobians)
