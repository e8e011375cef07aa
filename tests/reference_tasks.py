"""The oracle of the compiled stack's tasks (pedi_drake.control.compiled_stack): each task a small
class producing rows over the decision variables, in numpy.

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

import numpy as np
from reference_hqp import EqualityTask, InequalityTask

from pedi_drake import robot
from pedi_drake.control.robot_model import RobotSnapshot
from pedi_drake.friction import friction_pyramid_edges
from pedi_drake.vector3 import orientation_error_W

GRAVITY = robot.GRAVITY


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


def contact_rows(selected: np.ndarray) -> np.ndarray:
    """Rows (3 per contact) of the stacked contact Jacobian of the contacts where `selected` is true."""
    return (3 * np.flatnonzero(selected)[:, None] + _XYZ).ravel()


_XYZ = np.arange(3)


def torque_map(s: RobotSnapshot, layout: VariableLayout) -> tuple[np.ndarray, np.ndarray]:
    """(T, t0) with joint torques tau = T x + t0 in Unitree order [N m] (actuated dynamics rows).

    Computed once per snapshot (several tasks and the command need it); treat as read-only.
    """
    if s.torque_map is None:
        rows = layout.v_joints
        T = np.empty((len(rows), layout.size))
        T[:, : layout.nv] = s.M[rows]
        np.negative(s.J_contacts[:, rows].T, out=T[:, layout.nv :])
        s.torque_map = (T, s.h[rows])
    return s.torque_map


class FloatingBaseDynamics:
    """The six unactuated rows of M vdot + h = S^T tau + J_c^T f: M_u vdot - J_c,u^T f = -h_u."""

    def rows(self, s: RobotSnapshot, layout: VariableLayout) -> EqualityTask:
        u = layout.unactuated
        A = np.empty((len(u), layout.size))
        A[:, : layout.nv] = s.M[u]
        np.negative(s.J_contacts[:, u].T, out=A[:, layout.nv :])
        return EqualityTask("floating_base_dynamics", A, -s.h[u])


@dataclasses.dataclass
class ContactNoMotion:
    """No motion of the contact points in contact: J_i vdot = -Jdot_i v - kd J_i v (3 rows each).

    The small velocity damping kd [1/s] bleeds off residual contact-point velocity (estimator
    noise, impacts) instead of letting it integrate.
    """

    kd: float = 10.0

    def rows(self, s: RobotSnapshot, layout: VariableLayout, in_contact: np.ndarray) -> EqualityTask:
        rows = contact_rows(in_contact)
        J = s.J_contacts[rows]
        A = np.zeros((len(rows), layout.size))
        A[:, : layout.nv] = J
        b = -s.Jdot_v_contacts[rows] - self.kd * (J @ s.v)
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
    inscribed: bool = True  # the pyramid inside the Coulomb cone (pedi_drake.friction)
    # G by (nc, size, mu): built once, as only the bounds change from tick to tick.
    _matrices: dict = dataclasses.field(default_factory=dict, init=False, repr=False, compare=False)

    def rows(self, layout: VariableLayout, ramp: np.ndarray, mu: float) -> InequalityTask:
        h = np.zeros(6 * layout.nc)
        h[0::6] = -self.f_min * ramp
        h[1::6] = self.f_max * ramp
        key = (layout.nc, layout.size, mu)
        G = self._matrices.get(key)
        if G is None:
            G = self._matrices[key] = self._matrix(layout, mu)
        return InequalityTask("contact_forces", G, h, hard=True)

    def _matrix(self, layout: VariableLayout, mu: float) -> np.ndarray:
        """G (6 nc, size), read-only: it changes only with the friction coefficient."""
        if len(self._matrices) > 16:
            self._matrices.clear()  # a friction that keeps changing: do not grow without bound
        # Rows: -f_z <= -r f_min, f_z <= r f_max, then the pyramid's four faces.
        local = np.vstack([[[0.0, 0.0, -1.0], [0.0, 0.0, 1.0]], friction_pyramid_edges(mu, inscribed=self.inscribed)])
        G = np.zeros((6 * layout.nc, layout.size))
        for i in range(layout.nc):
            G[6 * i : 6 * i + 6, layout.force(i)] = local
        G.flags.writeable = False
        return G


@dataclasses.dataclass
class TorqueLimits:
    """|tau| <= scale * effort limit, with tau eliminated (see `torque_map`)."""

    scale: float = 0.9  # keep headroom for the joint PD around the reference [-]

    def rows(self, s: RobotSnapshot, layout: VariableLayout, effort_limit: np.ndarray) -> InequalityTask:
        T, t0 = torque_map(s, layout)
        limit = self.scale * effort_limit
        m = len(t0)
        G = np.empty((2 * m, T.shape[1]))
        G[:m] = T
        np.negative(T, out=G[m:])
        h = np.empty(2 * m)
        np.subtract(limit, t0, out=h[:m])
        np.add(limit, t0, out=h[m:])
        return InequalityTask("torque_limits", G, h, hard=True)


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
        # h = [upper; -lower], filled in place: this runs every tick, where each numpy call counts.
        h = np.empty(2 * len(q))
        upper, minus_lower = h[: len(q)], h[len(q) :]
        reach = q + qd * T  # where the joint would coast to
        np.minimum((2.0 / T**2) * (q_upper - self.margin - reach), (v_max - qd) / T, out=upper)
        np.minimum((2.0 / T**2) * (reach - q_lower - self.margin), (v_max + qd) / T, out=minus_lower)
        # Never demand an impossible interval (lower > upper): keep the braking side only.
        bad = upper + minus_lower < 0.0
        if bad.any():
            mid = 0.5 * (upper - minus_lower)
            upper[bad] = mid[bad]
            minus_lower[bad] = -mid[bad]
        return InequalityTask("joint_limits", layout.joint_selector, h, hard=True)


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
        gains: PdGains | None = None,
    ) -> EqualityTask:
        """The foot's rows at `gains` (None: the task's own)."""
        gains = self.gains if gains is None else gains
        J = s.J_contacts[3 * contact : 3 * contact + 3]
        v = J @ s.v
        a = a_ref + gains.kp * (p_ref - s.p_contacts[contact]) + gains.kd * (v_ref - v)
        A = np.zeros((3, layout.size))
        A[:, : layout.nv] = J
        return EqualityTask("foot_position", A, a - s.Jdot_v_contacts[3 * contact : 3 * contact + 3])


@dataclasses.dataclass
class CalfOrientation:
    """The orientation rows of the foot-pose tasks: the calf's rotation towards R_ref, Eq. 1 with
    a zero reference rate, about world x and y (roll and pitch: the 5-D task, `axes` 2, the yaw
    left free) or about all three (the 6-D shank task, `axes` 3)."""

    gains: PdGains

    def rows(
        self,
        s: RobotSnapshot,
        layout: VariableLayout,
        contact: int,
        R_ref: np.ndarray,
        axes: int = 2,
    ) -> EqualityTask:
        R_WC, J_w, bias_w = s.calf_orientations[contact]
        e = orientation_error_W(R_ref, R_WC)[:axes]
        a = self.gains.kp * e - self.gains.kd * (J_w @ s.v)[:axes]
        A = np.zeros((axes, layout.size))
        A[:, : layout.nv] = J_w[:axes]
        return EqualityTask("calf_orientation", A, a - bias_w[:axes])


@dataclasses.dataclass
class JointPosture:
    """Joint-space tracking of selected joints (Unitree indices): qdd = qdd_ref + Kp (q_ref - q) + Kd (qd_ref - qd)."""

    gains: PdGains
    name: str = "joint_posture"
    # Selection matrices by (size, joints...): constant, so built once.
    _selectors: dict = dataclasses.field(default_factory=dict, init=False, repr=False, compare=False)

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
        key = (layout.size, *joints.tolist())
        A = self._selectors.get(key)
        if A is None:
            A = np.zeros((len(joints), layout.size))
            A[np.arange(len(joints)), layout.v_joints[joints]] = 1.0
            A.flags.writeable = False
            self._selectors[key] = A
        b = qdd_ref + self.gains.kp * (q_ref - s.q_joints[joints]) + self.gains.kd * (qd_ref - s.v_joints[joints])
        return EqualityTask(self.name, A, b, weight)


@functools.lru_cache(maxsize=8)
def _force_selector(nv: int, nc: int) -> np.ndarray:
    """(3 nc, nv + 3 nc) [0 I]: the contact forces of x (read-only)."""
    A = np.zeros((3 * nc, nv + 3 * nc))
    A[:, nv:] = np.eye(3 * nc)
    A.flags.writeable = False
    return A


class ContactForceRegularization:
    """Contact forces towards an even share of the weight over the loaded contacts (weighted rows)."""

    def rows(self, layout: VariableLayout, ramp: np.ndarray, total_weight: float, weight: float) -> EqualityTask:
        A = _force_selector(layout.nv, layout.nc)
        b = np.zeros(3 * layout.nc)
        share = total_weight / max(float(ramp.sum()), 1e-6)
        b[2::3] = ramp * share
        return EqualityTask("force_regularization", A, b, weight)


class TorqueMinimization:
    """sum tau^2 with tau eliminated: rows T x = -t0 (weighted)."""

    def rows(self, s: RobotSnapshot, layout: VariableLayout, weight: float) -> EqualityTask:
        T, t0 = torque_map(s, layout)
        return EqualityTask("torque_minimization", T, -t0, weight)
