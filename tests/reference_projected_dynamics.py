"""The oracle of paper 002's compiled control law (pedi_drake.control.compiled_projected_dynamics,
whose docstring states the maths): the same quantities in numpy, by LAPACK (scipy) and DAQP's
Python module, raising where the kernels return a status."""

import dataclasses
import functools
import time

import daqp
import numpy as np
from scipy.linalg import lapack

from pedi_drake.control.compiled_projected_dynamics import RELAXED_BALANCE_WEIGHT
from pedi_drake.exceptions import QpInfeasible
from pedi_drake.friction import UP, write_pyramid_faces

# Default relative tolerance of the SVD pseudo-inverses: singular values below this times the
# largest one are treated as zero [-].
RANK_TOLERANCE = 1e-6
_INFINITY = 1e30
_DAQP_OK = (1, 2)


def symmetric_pseudo_inverse(
    A: np.ndarray, rank_tolerance: float = RANK_TOLERANCE, scale: float | None = None
) -> tuple[np.ndarray, int]:
    """(A^+, rank) of a symmetric positive semi-definite A (n, n) by its eigendecomposition.

    For such a matrix the eigenvalues are its singular values, so this is `pseudo_inverse` with
    the same rule (eigenvalues below `rank_tolerance * scale` dropped, `scale` the largest by
    default), at a fraction of the cost of an SVD: LAPACK's dsyevd is called directly, as numpy's
    wrappers cost more than the decomposition at these sizes. A task projected into a null space
    passes the scale of its unprojected matrix, so that a null space that is used up (every
    eigenvalue at rounding level) gives rank 0 instead of amplified rounding noise.
    """
    n = A.shape[0]
    if n == 0:
        return np.zeros((0, 0)), 0
    w, V, info = lapack.dsyevd(A)
    if info != 0:
        raise np.linalg.LinAlgError(f"dsyevd failed (info {info})")
    reference = w[-1] if scale is None else scale
    if w[-1] <= 0.0 or reference <= 0.0:
        return np.zeros((n, n)), 0
    keep = w > rank_tolerance * reference
    Vk = V[:, keep]
    return (Vk / w[keep]) @ Vk.T, int(np.count_nonzero(keep))


@dataclasses.dataclass
class ConstraintProjection:
    """Eq. 2: the projector onto the motions the held contacts allow."""

    P: np.ndarray  # (nv, nv) I - Jc^+ Jc [-]
    Jc_pinv: np.ndarray  # (nv, 3k)
    rank: int  # rank of Jc (at most 3k; less with dependent prong rows)


def constraint_projection(Jc: np.ndarray, rank_tolerance: float = RANK_TOLERANCE) -> ConstraintProjection:
    """P = I - Jc^+ Jc of the stacked contact Jacobian Jc (3k, nv); k = 0 gives P = I."""
    nv = Jc.shape[1]
    # Jc^+ = Jc^T (Jc Jc^T)^+; the eigenvalues of Jc Jc^T are the squared singular values of Jc.
    gram_pinv, rank = symmetric_pseudo_inverse(Jc @ Jc.T, rank_tolerance**2)
    Jc_pinv = Jc.T @ gram_pinv
    P = np.eye(nv) - Jc_pinv @ Jc
    P = 0.5 * (P + P.T)  # symmetric to rounding
    return ConstraintProjection(P, Jc_pinv, rank)


@dataclasses.dataclass
class ConstrainedDynamics:
    """Eq. 5: vdot = A u + vdot_0 for a projected generalised force u = P S^T tau."""

    projection: ConstraintProjection
    M_c: np.ndarray  # (nv, nv) P M + I - P
    A: np.ndarray  # (nv, nv) M_c^-1 P, symmetric positive semi-definite
    vdot_0: np.ndarray  # (nv,) acceleration with u = 0 [m/s^2, rad/s^2]


def constrained_dynamics(
    M: np.ndarray,
    h: np.ndarray,
    Jc: np.ndarray,
    Jcdot_v: np.ndarray,
    v: np.ndarray,
    contact_damping: float = 0.0,
    rank_tolerance: float = RANK_TOLERANCE,
) -> ConstrainedDynamics:
    """Projector, constrained inertia and drift acceleration of Eqs. 2 to 5 (see the module docstring)."""
    nv = M.shape[0]
    projection = constraint_projection(Jc, rank_tolerance)
    P = projection.P
    identity = np.eye(nv)
    M_c = P @ M + identity - P
    # One factorisation for both: A = M_c^-1 P and the drift.
    constraint_acceleration = projection.Jc_pinv @ (Jcdot_v + contact_damping * (Jc @ v)) if len(Jcdot_v) else 0.0
    rhs = np.column_stack([P, -(P @ h) - constraint_acceleration])
    solved = np.linalg.solve(M_c, rhs)
    A = solved[:, :nv]
    A = 0.5 * (A + A.T)
    return ConstrainedDynamics(projection, M_c, A, solved[:, nv])


@dataclasses.dataclass
class ImpedanceTask:
    """A task of the first priority: the impedance of Eq. 10 (stiffness K, damping D)."""

    name: str
    J: np.ndarray  # (m, nv)
    Jdot_v: np.ndarray  # (m,) bias acceleration [m/s^2 | rad/s^2]
    error: np.ndarray  # (m,) e = x - x_ref [m | rad]
    error_rate: np.ndarray  # (m,) edot = xdot - xdot_ref [m/s | rad/s]
    acceleration_ref: np.ndarray  # (m,) xddot_ref [m/s^2 | rad/s^2]
    stiffness: np.ndarray  # (m,) diagonal of K [N/m | N m/rad]
    damping: np.ndarray  # (m,) diagonal of D [N s/m | N m s/rad]


@dataclasses.dataclass
class AccelerationTask:
    """A task below the first priority: J vdot + Jdot v = desired (gains per unit inertia)."""

    name: str
    J: np.ndarray  # (m, nv)
    Jdot_v: np.ndarray  # (m,)
    desired: np.ndarray  # (m,) a* = a_ref + Kp (x_ref - x) + Kd (v_ref - v) [m/s^2 | rad/s^2]


def stack_impedance_tasks(tasks: list[ImpedanceTask], nv: int) -> ImpedanceTask:
    """The tasks as one stacked task (the first priority level)."""
    if not tasks:
        empty = np.zeros(0)
        return ImpedanceTask("none", np.zeros((0, nv)), empty, empty, empty, empty, empty, empty)
    return ImpedanceTask(
        "+".join(t.name for t in tasks),
        np.vstack([t.J for t in tasks]),
        *(np.concatenate([getattr(t, f) for t in tasks]) for f in _STACKED_FIELDS),
    )


_STACKED_FIELDS = ("Jdot_v", "error", "error_rate", "acceleration_ref", "stiffness", "damping")


@dataclasses.dataclass
class PrioritizedForce:
    """The constraint-free law's result: the projected generalised force and per-level figures."""

    u: np.ndarray  # (nv,) projected generalised force of all levels [N, N m]
    impedance_force: np.ndarray  # (m,) F of the first level (Eq. 10) [N | N m]
    impedance_inertia: np.ndarray  # (m, m) Lambda of the first level [kg | kg m^2]
    residuals: list[float]  # per level, |xddot - desired| the law achieves [m/s^2 ...]


def prioritized_force(
    dynamics: ConstrainedDynamics,
    v: np.ndarray,
    impedance: ImpedanceTask,
    lower: list[AccelerationTask],
    rank_tolerance: float = RANK_TOLERANCE,
) -> PrioritizedForce:
    """Eqs. 9 and 10: the impedance tasks first, each further task in the dynamically consistent
    null space of all the tasks above (Sentis' recursion on the constrained inverse inertia A)."""
    A, vdot_0 = dynamics.A, dynamics.vdot_0
    nv = A.shape[0]
    u = np.zeros(nv)
    N = np.eye(nv)  # dynamically consistent null-space projector of the levels so far
    residuals = []
    m = impedance.J.shape[0]
    Lambda_s = np.zeros((0, 0))
    F_s = np.zeros(0)
    free_dimensions = nv - dynamics.projection.rank  # of the constraint-free space
    used = 0
    if m:
        J = impedance.J
        Lambda_s, used = symmetric_pseudo_inverse(J @ A @ J.T, rank_tolerance)
        free = impedance.acceleration_ref - J @ vdot_0 - impedance.Jdot_v
        F_s = Lambda_s @ free - impedance.stiffness * impedance.error - impedance.damping * impedance.error_rate
        u = J.T @ F_s
        N = N - (A @ J.T @ Lambda_s) @ J
        # The closed loop Lambda (xddot - xddot_ref) + K e + D edot = 0 the law achieves [N].
        achieved = J @ (A @ u + vdot_0) + impedance.Jdot_v
        loop = Lambda_s @ (achieved - impedance.acceleration_ref)
        loop += impedance.stiffness * impedance.error + impedance.damping * impedance.error_rate
        residuals.append(float(np.linalg.norm(loop)))
    for task in lower:
        if used >= free_dimensions:
            # The tasks above use every constraint-free direction: nothing is left for this one.
            residuals.append(float(np.linalg.norm(task.desired - task.J @ (A @ u + vdot_0) - task.Jdot_v)))
            continue
        J_prec = task.J @ N
        scale = float(np.linalg.norm(task.J @ A @ task.J.T))  # the unprojected task's inverse inertia
        Lambda, rank = symmetric_pseudo_inverse(J_prec @ A @ J_prec.T, rank_tolerance, scale)
        used += rank
        if rank == 0:
            residuals.append(float(np.linalg.norm(task.desired - task.J @ (A @ u + vdot_0) - task.Jdot_v)))
            continue
        F = Lambda @ (task.desired - task.J @ (A @ u + vdot_0) - task.Jdot_v)
        u = u + J_prec.T @ F
        N = N - (A @ J_prec.T @ Lambda) @ J_prec
        residuals.append(float(np.linalg.norm(task.desired - task.J @ (A @ u + vdot_0) - task.Jdot_v)))
    return PrioritizedForce(dynamics.projection.P @ u, F_s, Lambda_s, residuals)


@dataclasses.dataclass
class ConstraintFreeTorque:
    """tau_m of Eq. 3 and the acceleration it produces (Eq. 5)."""

    tau_m: np.ndarray  # (12,) [N m], in the order of the selection's columns
    u: np.ndarray  # (nv,) P S^T tau_m, the projected force actually produced
    vdot: np.ndarray  # (nv,)


def constraint_free_torque(
    dynamics: ConstrainedDynamics, u: np.ndarray, S: np.ndarray, rank_tolerance: float = RANK_TOLERANCE
) -> ConstraintFreeTorque:
    """tau_m = (P S^T)^+ u, and vdot from what the joints produce (see the module docstring)."""
    P = dynamics.projection.P
    PSt = P @ S.T
    # (P S^T)^+ = (S P S^T)^+ S P (P symmetric, idempotent), and P u = u.
    joint_block_pinv, _ = symmetric_pseudo_inverse(S @ PSt, rank_tolerance)
    tau_m = joint_block_pinv @ (S @ (P @ u))
    u_eff = PSt @ tau_m
    return ConstraintFreeTorque(tau_m, u_eff, dynamics.A @ u_eff + dynamics.vdot_0)


@functools.lru_cache(maxsize=64)
def friction_pyramid_rows(num_contacts: int, mu_eff: float) -> np.ndarray:
    """G (6 k, 3 k) of G lam <= g for each contact: -f_z, f_z, +-f_x - mu f_z, +-f_y - mu f_z
    (read-only; cached, it changes only with the friction and the number of contacts)."""
    local = np.zeros((6, 3))
    local[0, 2], local[1, 2] = -1.0, 1.0
    write_pyramid_faces(local, 2, 0, mu_eff, UP)
    G = np.kron(np.eye(num_contacts), local)
    G.flags.writeable = False
    return G


@dataclasses.dataclass
class ContactForceProblem:
    """Eq. 7 at one instant (see the module docstring); arrays over the k held contacts."""

    Jc: np.ndarray  # (3k, nv) held contacts' Jacobian
    r: np.ndarray  # (nv,) M vdot + h [N, N m]
    unactuated: np.ndarray  # (6,) indices of the floating-base velocities
    actuated: np.ndarray  # (12,) indices of the joint velocities (in torque order)
    ramp: np.ndarray  # (k,) contact activation in [0, 1]
    friction: float  # mu_eff of the pyramid [-]
    f_min: float  # [N]
    f_max: float  # [N]
    torque_limit: np.ndarray  # (12,) [N m]
    force_share: np.ndarray  # (3k,) regularisation target [N]
    torque_weight: float = 1.0  # [1/(N m)^2]
    force_weight: float = 1e-3  # [1/N^2]
    rank_tolerance: float = RANK_TOLERANCE


@dataclasses.dataclass
class ContactForceSolution:
    lam: np.ndarray  # (3k,) [N]
    tau: np.ndarray  # (12,) [N m]
    equality_residual: float  # |Jc,u^T lam - r_u| [N, N m]
    solve_time: float  # [s]
    relaxed: bool = False  # the balance held only as nearly as the limits allow


def solve_contact_forces(problem: ContactForceProblem) -> ContactForceSolution:
    """Eq. 7 by elimination of the wrench balance and DAQP; where no forces within the limits hold
    the balance, the nearest balance they allow (`relaxed`); raises QpInfeasible where there are
    none at all."""
    start = time.perf_counter()
    p = problem
    n = p.Jc.shape[0]
    r_u, r_a = p.r[p.unactuated], p.r[p.actuated]
    T = -p.Jc[:, p.actuated].T  # tau = r_a + T lam
    if n == 0:
        residual = float(np.linalg.norm(r_u))
        if residual > 1e-6 * max(1.0, float(np.linalg.norm(p.r))) or np.any(np.abs(r_a) > p.torque_limit):
            raise QpInfeasible("no held contact can balance the trunk wrench (or the torques exceed their limits)")
        return ContactForceSolution(np.zeros(0), r_a.copy(), residual, time.perf_counter() - start)
    B = p.Jc[:, p.unactuated].T  # (6, 3k)
    # One eigendecomposition of B^T B gives both the minimum-norm lam_0 and the null space Z.
    w, V, info = lapack.dsyevd(B.T @ B)
    if info != 0:
        raise np.linalg.LinAlgError(f"dsyevd failed (info {info})")
    keep = w > p.rank_tolerance**2 * max(w[-1], 1e-300)
    Vk = V[:, keep]
    lam_0 = (Vk / w[keep]) @ (Vk.T @ (B.T @ r_u))
    Z = V[:, ~keep]  # (3k, 3k - rank)
    k = n // 3
    G = friction_pyramid_rows(k, p.friction)
    g = np.zeros(6 * k)
    g[0::6] = -p.f_min * p.ramp
    g[1::6] = p.f_max * p.ramp
    G_all = np.vstack([G, T, -T])
    g_all = np.concatenate([g, p.torque_limit - r_a, p.torque_limit + r_a])
    H_lam = p.torque_weight * (T.T @ T) + p.force_weight * np.eye(n)
    f_lam = p.torque_weight * (T.T @ r_a) - p.force_weight * p.force_share
    lam = None
    if Z.shape[1] == 0:
        if not np.any(G_all @ lam_0 > g_all + 1e-6):
            lam = lam_0
    else:
        H = Z.T @ H_lam @ Z
        f = Z.T @ (H_lam @ lam_0 + f_lam)
        C = G_all @ Z
        upper = g_all - G_all @ lam_0
        z, _, exitflag, _ = daqp.solve(
            np.ascontiguousarray(H),
            np.ascontiguousarray(f),
            np.ascontiguousarray(C),
            np.ascontiguousarray(upper),
            np.full(len(upper), -_INFINITY),
        )
        if exitflag in _DAQP_OK and np.isfinite(z).all():
            lam = lam_0 + Z @ np.asarray(z)
    relaxed = lam is None
    if relaxed:
        # No forces within the limits hold the balance: the nearest balance they allow.
        weight = RELAXED_BALANCE_WEIGHT
        lam, _, exitflag, _ = daqp.solve(
            np.ascontiguousarray(H_lam + weight * B.T @ B),
            np.ascontiguousarray(f_lam - weight * B.T @ r_u),
            np.ascontiguousarray(G_all),
            np.ascontiguousarray(g_all),
            np.full(len(g_all), -_INFINITY),
        )
        if exitflag not in _DAQP_OK or not np.isfinite(lam).all():
            raise QpInfeasible(f"contact-force QP, relaxed: DAQP exit flag {exitflag}")
        lam = np.asarray(lam)
    residual = float(np.linalg.norm(B @ lam - r_u))
    return ContactForceSolution(lam, r_a + T @ lam, residual, time.perf_counter() - start, relaxed)


def impedance_force_estimate(
    inertia: np.ndarray,
    stiffness: np.ndarray,
    damping: np.ndarray,
    error: np.ndarray,
    error_rate: np.ndarray,
    error_acceleration: np.ndarray,
) -> np.ndarray:
    """Eq. 11: F_ext_hat = Lambda eddot + D edot + K e [N] from the impedance error of a task."""
    return inertia @ error_acceleration + damping * error_rate + stiffness * error
