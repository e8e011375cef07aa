"""Closed-form inverse kinematics of one Go1 leg: every solution within the joint limits.

The leg (hip abduction about e0, thigh and calf about the parallel axis e1) reduces to a
rotation of the hip plane followed by a planar two-link chain. In the leg's own basis
(e0 = hip axis, e1 = thigh axis at zero hip angle, e2 = e0 x e1) every point below the thigh
joint keeps a constant lateral coordinate `lateral` along e1, and its other two coordinates,
written as the complex number w = z + i x, rotate by e^{i q} under a rotation q about e1; the
(y, z) coordinates, as v = y + i z, rotate by e^{i q} under the hip. `LegChain` holds the
model's geometry in that form; it is shared with the FABRIK solver, so both read one source.

This solver is the test oracle and the benchmark baseline, not a replacement for FABRIK.
"""

import cmath
import dataclasses
import functools
import math

import numpy as np

from pedi_drake.exceptions import PediError, UnreachableTarget
from pedi_drake.leg_kinematics import leg_geometry

_TWO_PI = 2.0 * math.pi
_STRUCTURE_TOL = 1e-9  # [m] or [-]: how far the model may depart from the supported structure.


@dataclasses.dataclass(frozen=True)
class LegChain:
    """One leg's geometry in its hip-plane / sagittal-plane coordinates (see the module doc)."""

    leg: str
    p_BH: tuple[float, float, float]  # hip joint origin in the trunk frame [m]
    e0: tuple[float, float, float]  # hip axis in the trunk frame (unit)
    e1: tuple[float, float, float]  # thigh (= calf) axis at zero hip angle, trunk frame (unit)
    e2: tuple[float, float, float]  # e0 x e1
    lateral: float  # e1 coordinate of the thigh joint, calf joint and foot in the hip frame [m]
    w_HT: complex  # thigh joint in the sagittal plane, z + i x, hip frame [m]
    w_TC: complex  # calf joint from the thigh joint at zero thigh angle, z + i x [m]
    w_CF: complex  # foot centre from the calf joint at zero calf angle, z + i x [m]
    q_lower: tuple[float, float, float]  # (hip, thigh, calf) [rad]
    q_upper: tuple[float, float, float]  # (hip, thigh, calf) [rad]

    def to_local(self, p_B: np.ndarray) -> tuple[float, float, float]:
        """(x, y, z) of a trunk-frame point relative to the hip, in the (e0, e1, e2) basis [m]."""
        dx = float(p_B[0]) - self.p_BH[0]
        dy = float(p_B[1]) - self.p_BH[1]
        dz = float(p_B[2]) - self.p_BH[2]
        e0, e1, e2 = self.e0, self.e1, self.e2
        return (
            dx * e0[0] + dy * e0[1] + dz * e0[2],
            dx * e1[0] + dy * e1[1] + dz * e1[2],
            dx * e2[0] + dy * e2[1] + dz * e2[2],
        )

    def to_trunk(self, x: float, y: float, z: float) -> np.ndarray:
        """The trunk-frame point [m] of local coordinates (x, y, z) relative to the hip."""
        e0, e1, e2 = self.e0, self.e1, self.e2
        return np.array(
            [self.p_BH[k] + x * e0[k] + y * e1[k] + z * e2[k] for k in range(3)],
        )

    def foot_local(self, q0: float, q1: float, q2: float) -> tuple[float, float, float]:
        """Forward kinematics: foot (x, y, z) relative to the hip in the (e0, e1, e2) basis [m]."""
        w = self.w_HT + cmath.exp(1j * q1) * (self.w_TC + cmath.exp(1j * q2) * self.w_CF)
        v = cmath.exp(1j * q0) * complex(self.lateral, w.real)
        return w.imag, v.real, v.imag


@functools.lru_cache(maxsize=4)
def leg_chain(leg: str) -> LegChain:
    """The reduced geometry of `leg` (FR, FL, RR, RL), read from the Go1 model.

    Raises PediError if the model is not a hip-abduction + two parallel pitch joints leg with
    the links in the pitch plane (the only structure these solvers support).
    """
    g = leg_geometry(leg)
    e0 = g.axes[0] / np.linalg.norm(g.axes[0])
    e1 = g.axes[1] / np.linalg.norm(g.axes[1])
    if abs(e0 @ e1) > _STRUCTURE_TOL or np.linalg.norm(np.cross(g.axes[1], g.axes[2])) > _STRUCTURE_TOL:
        raise PediError(f"{leg}: leg IK needs a hip axis perpendicular to parallel thigh and calf axes")
    if g.axes[1] @ g.axes[2] < 0.0:
        raise PediError(f"{leg}: leg IK needs thigh and calf axes of the same sign")
    if abs(g.p_TC @ e1) > _STRUCTURE_TOL or abs(g.p_CF @ e1) > _STRUCTURE_TOL:
        raise PediError(f"{leg}: leg IK needs the thigh and calf links in their joints' plane")
    e2 = np.cross(e0, e1)

    def planar(p: np.ndarray) -> complex:
        return complex(p @ e2, p @ e0)

    return LegChain(
        leg=leg,
        p_BH=tuple(float(v) for v in g.p_BH),
        e0=tuple(float(v) for v in e0),
        e1=tuple(float(v) for v in e1),
        e2=tuple(float(v) for v in e2),
        lateral=float(g.p_HT @ e1),
        w_HT=planar(g.p_HT),
        w_TC=planar(g.p_TC),
        w_CF=planar(g.p_CF),
        q_lower=tuple(float(v) for v in g.q_lower),
        q_upper=tuple(float(v) for v in g.q_upper),
    )


def _in_limits(angle: float, lower: float, upper: float, tol: float) -> float | None:
    """The representation angle + 2 pi k within [lower, upper] (widened by tol), clipped; else None."""
    k = math.ceil((lower - tol - angle) / _TWO_PI)
    candidate = angle + k * _TWO_PI
    if candidate > upper + tol:
        return None
    return min(max(candidate, lower), upper)


def leg_ik_solutions(
    leg: str, p_target_B: np.ndarray, *, limit_tol: float = 1e-9, respect_limits: bool = True
) -> list[np.ndarray]:
    """All joint solutions (hip, thigh, calf) [rad] placing the foot of `leg` at `p_target_B`.

    `p_target_B` is the foot-centre target in the trunk frame [m]. Only solutions within the
    joint limits are returned (angles within `limit_tol` [rad] of a limit are clipped onto it),
    deduplicated; an empty list means the target is unreachable within the limits. With
    `respect_limits=False` every solution of the chain is returned, angles in [-pi, pi) (used to
    tell "beyond the leg's reach" from "blocked by the joint limits"). Non-finite targets raise
    UnreachableTarget.
    """
    p = np.asarray(p_target_B, dtype=float).reshape(3)
    if not np.all(np.isfinite(p)):
        raise UnreachableTarget(f"{leg}: non-finite foot target {p}")
    c = leg_chain(leg)
    x, y, z = c.to_local(p)
    if respect_limits:
        lo, hi = c.q_lower, c.q_upper
    else:
        lo, hi = (-math.pi,) * 3, (math.pi - 1e-12,) * 3
        limit_tol = 0.0
    a, b = abs(c.w_TC), abs(c.w_CF)
    phi = cmath.phase(c.w_CF) - cmath.phase(c.w_TC)  # calf angle offset of the link directions
    v = complex(y, z)
    # The hip turns the point (lateral, z_plane) onto the target's (y, z): the target's
    # distance from the hip axis must be at least the lateral offset.
    radial_sq = abs(v) ** 2 - c.lateral**2
    if radial_sq < -1e-12:
        return []
    radial = math.sqrt(max(radial_sq, 0.0))
    solutions: list[np.ndarray] = []
    for z_plane in {radial, -radial}:
        # z_plane is the target's e2 coordinate in the (rotated) hip frame.
        q0 = _in_limits(cmath.phase(v) - cmath.phase(complex(c.lateral, z_plane)), lo[0], hi[0], limit_tol)
        if q0 is None:
            continue
        u = complex(z_plane, x) - c.w_HT  # target from the thigh joint, sagittal plane
        cos_knee = (abs(u) ** 2 - a * a - b * b) / (2.0 * a * b)
        if abs(cos_knee) > 1.0 + 1e-12:
            continue
        knee = math.acos(min(max(cos_knee, -1.0), 1.0))
        for sign in (1.0, -1.0) if knee > 0.0 else (1.0,):
            q2 = _in_limits(sign * knee - phi, lo[2], hi[2], limit_tol)
            if q2 is None:
                continue
            m = c.w_TC + cmath.exp(1j * q2) * c.w_CF
            q1 = _in_limits(cmath.phase(u) - cmath.phase(m), lo[1], hi[1], limit_tol)
            if q1 is None:
                continue
            q = np.array([q0, q1, q2])
            if not any(np.allclose(q, s, atol=1e-12) for s in solutions):
                solutions.append(q)
    return solutions


def solve_leg_ik_analytic(leg: str, p_target_B: np.ndarray, q_near: np.ndarray | None = None) -> np.ndarray:
    """The closed-form solution nearest `q_near` (hip, thigh, calf) [rad], or the first one.

    Raises UnreachableTarget if no solution lies within the joint limits.
    """
    solutions = leg_ik_solutions(leg, p_target_B)
    if not solutions:
        raise UnreachableTarget(f"{leg}: foot target {np.asarray(p_target_B)} [m] unreachable within the limits")
    if q_near is None:
        return solutions[0]
    q_near = np.asarray(q_near, dtype=float)
    return min(solutions, key=lambda s: float(np.sum((s - q_near) ** 2)))
