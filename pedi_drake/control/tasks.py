"""Whole-body tasks: each a small class producing rows over the decision variables.

Decision variables x = [vdot (nv = 18); f (3 nc)]: generalised accelerations (trunk angular and
linear acceleration in world, then joint accelerations in the plant's order) and one world-frame
force per contact point (the four feet, then the prongs). Joint torques are *eliminated* with
the actuated rows of the dynamics,

    tau = M_a vdot + h_a - J_c,a^T f,

so every torque task (limits, minimisation) is linear in x. Why: the QP shrinks from
18 + 12 + 3 nc to 18 + 3 nc variables (30 with four feet, 36 with two prongs), the actuated
dynamics rows disappear as equality constraints, and dense active-set solvers scale with the
cube of the size (paper 003 uses the same trick, its ref. [34]). Contacts that are not in
contact keep their force variables, bounded to zero: the QP keeps a fixed size and adding or
removing a contact is a continuous change of bounds (the ramp).

Acceleration tasks follow Eq. 1 of paper 000: J vdot = a_ref + Kp (x_ref - x) + Kd (v_ref - v) - Jdot v.
"""

import dataclasses
import functools
import math

import numpy as np

from pedi_drake.control.hqp import EqualityTask, InequalityTask
from pedi_drake.control.robot_model import RobotSnapshot

GRAVITY = 9.81  # [m/s^2]


@dataclasses.dataclass(frozen=True)
class VariableLayout:
    """Index map of x = [vdot; f]."""

    nv: int  # generalised velocities (18)
    nc: int  # contact points
    v_joints: np.ndarray  # (12,) indices of the joint accelerations, Unitree order

    @property
    def size(self) -> int:
        return self.nv + 3 * self.nc

    @functools.cached_property
    def unactuated(self) -> np.ndarray:
        """Indices of the floating-base velocities (those that are not joints)."""
        mask = np.ones(self.nv, dtype=bool)
        mask[self.v_joints] = False
        return np.flatnonzero(mask)

    @functools.cached_property
    def joint_selector(self) -> np.ndarray:
        """(24, size): [S; -S] with S x = the joint accelerations in Unitree order (read-only)."""
        n = len(self.v_joints)
        S = np.zeros((n, self.size))
        S[np.arange(n), self.v_joints] = 1.0
        selector = np.vstack([S, -S])
        selector.flags.writeable = False
        return selector

    def force(self, contact: int) -> slice:
        return slice(self.nv + 3 * contact, self.nv + 3 * contact + 3)

    def split(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(vdot (nv,), forces (nc, 3)) from a solution."""
        return x[: self.nv], x[self.nv :].reshape(self.nc, 3)


def torque_map(s: RobotSnapshot, layout: VariableLayout) -> tuple[np.ndarray, np.ndarray]:
    """(T, t0) with joint torques tau = T x + t0 in Unitree order [N m] (actuated dynamics rows).

    Computed once per snapshot (several tasks and the command need it); treat as read-only.
    """
    if s.torque_map is None:
        rows = layout.v_joints
        s.torque_map = (np.hstack([s.M[rows, :], -s.J_contacts[:, rows].T]), s.h[rows].copy())
    return s.torque_map


class FloatingBaseDynamics:
    """The six unactuated rows of M vdot + h = S^T tau + J_c^T f: M_u vdot - J_c,u^T f = -h_u."""

    def rows(self, s: RobotSnapshot, layout: VariableLayout) -> EqualityTask:
        u = layout.unactuated
        A = np.hstack([s.M[u, :], -s.J_contacts[:, u].T])
        return EqualityTask("floating_base_dynamics", A, -s.h[u])


@dataclasses.dataclass
class ContactNoMotion:
    """No motion of the contact points in contact: J_i vdot = -Jdot_i v - kd J_i v (3 rows each).

    The small velocity damping kd [1/s] bleeds off residual contact-point velocity (estimator
    noise, impacts) instead of letting it integrate.
    """

    kd: float = 10.0

    def rows(self, s: RobotSnapshot, layout: VariableLayout, in_contact: np.ndarray) -> EqualityTask:
        idx = np.flatnonzero(in_contact)
        A = np.zeros((3 * len(idx), layout.size))
        b = np.zeros(3 * len(idx))
        for k, i in enumerate(idx):
            J = s.J_contacts[3 * i : 3 * i + 3]
            A[3 * k : 3 * k + 3, : layout.nv] = J
            b[3 * k : 3 * k + 3] = -s.Jdot_v_contacts[3 * i : 3 * i + 3] - self.kd * (J @ s.v)
        return EqualityTask("contact_no_motion", A, b)


@dataclasses.dataclass
class ContactForceLimits:
    """Unilateral normal force with a minimum and a 4-edge friction pyramid (flat ground, normal +z).

    Each contact i has an activation ramp r_i in [0, 1]: f_z in [r_i f_min, r_i f_max] and
    |f_x|, |f_y| <= mu_eff f_z, so r_i = 0 forces the contact's force to zero and a ramp from
    0 to 1 (or back) bounds how fast its force can appear (or must vanish).
    """

    f_min: float = 5.0  # [N]
    f_max: float = 250.0  # [N]
    inscribed: bool = True  # use mu / sqrt(2): the pyramid inside the cone, conservative

    def rows(self, layout: VariableLayout, ramp: np.ndarray, mu: float) -> InequalityTask:
        mu_eff = mu / np.sqrt(2.0) if self.inscribed else mu
        local = np.array(
            [
                [0.0, 0.0, -1.0],
                [0.0, 0.0, 1.0],
                [1.0, 0.0, -mu_eff],
                [-1.0, 0.0, -mu_eff],
                [0.0, 1.0, -mu_eff],
                [0.0, -1.0, -mu_eff],
            ]
        )
        G = np.zeros((6 * layout.nc, layout.size))
        h = np.zeros(6 * layout.nc)
        for i in range(layout.nc):
            G[6 * i : 6 * i + 6, layout.force(i)] = local
            h[6 * i] = -ramp[i] * self.f_min
            h[6 * i + 1] = ramp[i] * self.f_max
        return InequalityTask("contact_forces", G, h, hard=True)


@dataclasses.dataclass
class TorqueLimits:
    """|tau| <= scale * effort limit, with tau eliminated (see `torque_map`)."""

    scale: float = 0.9  # keep headroom for the joint PD around the reference [-]

    def rows(self, s: RobotSnapshot, layout: VariableLayout, effort_limit: np.ndarray) -> InequalityTask:
        T, t0 = torque_map(s, layout)
        limit = self.scale * effort_limit
        return InequalityTask("torque_limits", np.vstack([T, -T]), np.concatenate([limit - t0, limit + t0]), hard=True)


@dataclasses.dataclass
class JointLimits:
    """Joint position and velocity limits as joint-acceleration bounds over a horizon.

    Position: q + qd T + qdd T^2 / 2 stays in [q_lower, q_upper]; velocity: |qd + qdd T| <= v_max.
    If the joint is already beyond a limit, the bound is relaxed to braking only (never crossing).
    """

    horizon: float = 0.05  # [s]
    margin: float = 0.02  # kept from the position limits [rad]

    def rows(
        self,
        s: RobotSnapshot,
        layout: VariableLayout,
        q_lower: np.ndarray,
        q_upper: np.ndarray,
        v_max: np.ndarray,
    ) -> InequalityTask:
        T = self.horizon
        q, qd = s.q_joints, s.v_joints
        upper = np.minimum(2.0 * (q_upper - self.margin - q - qd * T) / T**2, (v_max - qd) / T)
        lower = np.maximum(2.0 * (q_lower + self.margin - q - qd * T) / T**2, (-v_max - qd) / T)
        # Never demand an impossible interval: keep the braking side only.
        bad = lower > upper
        mid = 0.5 * (lower + upper)
        upper = np.where(bad, mid, upper)
        lower = np.where(bad, mid, lower)
        return InequalityTask("joint_limits", layout.joint_selector, np.concatenate([upper, -lower]), hard=True)


def convex_hull_ccw(points_xy: np.ndarray) -> np.ndarray:
    """Vertices of the convex hull of `points_xy` (k, 2), counter-clockwise (Andrew's monotone chain)."""
    # Python floats: the chain below does scalar arithmetic, slow on numpy scalars.
    pts = sorted(map(tuple, np.asarray(points_xy, float).tolist()))
    if len(pts) <= 2:
        return np.array(pts)

    def half(sequence):
        chain: list[tuple[float, float]] = []
        for p in sequence:
            while len(chain) >= 2:
                (ax, ay), (bx, by) = chain[-2], chain[-1]
                if (bx - ax) * (p[1] - ay) - (by - ay) * (p[0] - ax) > 1e-12:
                    break
                chain.pop()
            chain.append(p)
        return chain

    lower, upper = half(pts), half(reversed(pts))
    return np.array(lower[:-1] + upper[:-1])


def polygon_halfplanes(vertices_xy: np.ndarray, margin: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """(N, d) with N p <= d: the convex hull of `vertices_xy` (k >= 3, [m]) shrunk by `margin` [m]."""
    hull = convex_hull_ccw(vertices_xy)
    edges = np.roll(hull, -1, axis=0) - hull
    normals = np.column_stack([edges[:, 1], -edges[:, 0]])  # outward for a counter-clockwise ring
    normals /= np.sqrt(np.sum(normals * normals, axis=1))[:, None]
    return normals, np.sum(normals * hull, axis=1) - margin


def rectangle_halfplanes(centre: np.ndarray, half_sizes: np.ndarray, yaw: float) -> tuple[np.ndarray, np.ndarray]:
    """(N, d) with N p <= d of a rectangle of `half_sizes` [m] at `centre` [m], rotated by `yaw` [rad]."""
    c, s_ = np.cos(yaw), np.sin(yaw)
    axes = np.array([[c, s_], [-s_, c]])  # rows: the rectangle's x and y axes in world
    N = np.vstack([axes, -axes])
    d = N @ np.asarray(centre, float) + np.concatenate([half_sizes, half_sizes])
    return N, d


@dataclasses.dataclass
class CapturePointBalance:
    """Keeps the capture point xi = c + cdot / omega inside a polygon N xi <= d (paper 000, task 2).

    The bound is applied to the capture point predicted `horizon` ahead,
    xi + T (cdot + cddot / omega) with cddot = J_com vdot + Jdot_com v, so it is linear in x.
    omega = sqrt(g / z) with z the CoM height over the mean contact height.
    """

    horizon: float = 0.05  # [s]

    def capture_point(self, s: RobotSnapshot, ground_height: float) -> tuple[np.ndarray, float]:
        z = max(s.p_com[2] - ground_height, 0.05)
        omega = np.sqrt(GRAVITY / z)
        return s.p_com[:2] + s.v_com[:2] / omega, omega

    def rows(
        self, s: RobotSnapshot, layout: VariableLayout, N: np.ndarray, d: np.ndarray, ground_height: float
    ) -> InequalityTask:
        xi, omega = self.capture_point(s, ground_height)
        T = self.horizon
        G = np.zeros((len(d), layout.size))
        G[:, : layout.nv] = (T / omega) * N @ s.J_com[:2]
        h = d - N @ (xi + T * s.v_com[:2] + (T / omega) * s.Jdot_v_com[:2])
        return InequalityTask("capture_point", G, h, hard=False)


@dataclasses.dataclass
class PdGains:
    """Eq. 1 gains: stiffness kp [1/s^2] and damping kd [1/s]."""

    kp: float
    kd: float


def orientation_error_W(R_ref: np.ndarray, R: np.ndarray) -> np.ndarray:
    """Rotation vector of R_ref R^T (world frame) [rad]: the rotation taking R to R_ref."""
    E = R_ref @ R.T
    # Scalar maths: numpy's ufuncs cost microseconds each on a 3x3 and this runs twice a tick.
    cos_angle = min(max((E[0, 0] + E[1, 1] + E[2, 2] - 1.0) / 2.0, -1.0), 1.0)
    angle = math.acos(cos_angle)
    axis_sin = np.array([E[2, 1] - E[1, 2], E[0, 2] - E[2, 0], E[1, 0] - E[0, 1]]) / 2.0
    if angle < 1e-9:
        return axis_sin
    return axis_sin * (angle / math.sin(angle))


@dataclasses.dataclass
class TrunkOrientation:
    """Trunk angular acceleration tracking (3 rows): J_w vdot = wdot_ref + Kp e_R + Kd (w_ref - w) - Jdot_w v."""

    gains: PdGains

    def rows(
        self, s: RobotSnapshot, layout: VariableLayout, R_ref: np.ndarray, w_ref: np.ndarray, wdot_ref: np.ndarray
    ) -> EqualityTask:
        w = s.V_trunk[:3]
        a = wdot_ref + self.gains.kp * orientation_error_W(R_ref, s.R_WB) + self.gains.kd * (w_ref - w)
        A = np.zeros((3, layout.size))
        A[:, : layout.nv] = s.J_trunk[:3]
        return EqualityTask("trunk_orientation", A, a - s.Jdot_v_trunk[:3])


@dataclasses.dataclass
class TrunkPosition:
    """Trunk origin acceleration tracking (3 rows), Eq. 1."""

    gains: PdGains

    def rows(
        self, s: RobotSnapshot, layout: VariableLayout, p_ref: np.ndarray, v_ref: np.ndarray, a_ref: np.ndarray
    ) -> EqualityTask:
        v = s.V_trunk[3:]
        a = a_ref + self.gains.kp * (p_ref - s.p_WB) + self.gains.kd * (v_ref - v)
        A = np.zeros((3, layout.size))
        A[:, : layout.nv] = s.J_trunk[3:]
        return EqualityTask("trunk_position", A, a - s.Jdot_v_trunk[3:])


@dataclasses.dataclass
class FootPosition:
    """Swing / pedipulation foot centre tracking in world (3 rows), Eq. 1."""

    gains: PdGains

    def rows(
        self,
        s: RobotSnapshot,
        layout: VariableLayout,
        contact: int,
        p_ref: np.ndarray,
        v_ref: np.ndarray,
        a_ref: np.ndarray,
    ) -> EqualityTask:
        J = s.J_contacts[3 * contact : 3 * contact + 3]
        v = J @ s.v
        a = a_ref + self.gains.kp * (p_ref - s.p_contacts[contact]) + self.gains.kd * (v_ref - v)
        A = np.zeros((3, layout.size))
        A[:, : layout.nv] = J
        return EqualityTask("foot_position", A, a - s.Jdot_v_contacts[3 * contact : 3 * contact + 3])


@dataclasses.dataclass
class JointPosture:
    """Joint-space tracking of selected joints (Unitree indices): qdd = qdd_ref + Kp (q_ref - q) + Kd (qd_ref - qd)."""

    gains: PdGains
    name: str = "joint_posture"

    def rows(
        self,
        s: RobotSnapshot,
        layout: VariableLayout,
        joints: np.ndarray,
        q_ref: np.ndarray,
        qd_ref: np.ndarray,
        qdd_ref: np.ndarray,
        weight: float = 1.0,
    ) -> EqualityTask:
        joints = np.asarray(joints, int)
        A = np.zeros((len(joints), layout.size))
        A[np.arange(len(joints)), layout.v_joints[joints]] = 1.0
        b = qdd_ref + self.gains.kp * (q_ref - s.q_joints[joints]) + self.gains.kd * (qd_ref - s.v_joints[joints])
        return EqualityTask(self.name, A, b, weight)


class ContactForceRegularization:
    """Contact forces towards an even share of the weight over the loaded contacts (weighted rows)."""

    def rows(self, layout: VariableLayout, ramp: np.ndarray, total_weight: float, weight: float) -> EqualityTask:
        A = np.zeros((3 * layout.nc, layout.size))
        A[:, layout.nv :] = np.eye(3 * layout.nc)
        b = np.zeros(3 * layout.nc)
        share = total_weight / max(float(np.sum(ramp)), 1e-6)
        b[2::3] = ramp * share
        return EqualityTask("force_regularization", A, b, weight)


class TorqueMinimization:
    """sum tau^2 with tau eliminated: rows T x = -t0 (weighted)."""

    def rows(self, s: RobotSnapshot, layout: VariableLayout, weight: float) -> EqualityTask:
        T, t0 = torque_map(s, layout)
        return EqualityTask("torque_minimization", T, -t0, weight)
