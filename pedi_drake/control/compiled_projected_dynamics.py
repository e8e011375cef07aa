"""Paper 002's whole-body control law as compiled kernels on plain arrays: projected inverse
dynamics, a Cartesian impedance for the lifted foot with the torso in its dynamically consistent
null space, a QP over the contact forces (by DAQP, `daqp_kernel`), and the impedance-based
estimate of the external force at the foot.

Notation (SI units; nv = 18 generalised velocities, 12 of them joints):

    M (nv, nv) [kg, kg m, kg m^2]  mass matrix          h (nv,) [N, N m]  bias: C v - tau_g + damping
    S (12, nv)                     joint selection      tau (12,) [N m]   joint torques
    Jc (3k, nv)                    world translational Jacobian of the k held contact points
    lam (3k,) [N]                  contact forces (world frame, on the robot)

Eq. 1, equations of motion:   M vdot + h = S^T tau + Jc^T lam,   with the contacts held still,
Jc vdot + Jcdot v = 0. (The contact velocity damping kd [1/s] of the HQP is kept: the held
contacts obey Jc vdot = -(Jcdot v + kd Jc v), which bleeds estimator drift off.)

Eq. 2, projector. P = I - Jc^+ Jc (nv, nv, dimensionless) is the orthogonal projector onto the
null space of Jc: the motions the contacts allow. Jc^+ is the pseudo-inverse from the singular
value decomposition, with singular values below `rank_tolerance * sigma_max` dropped (computed as
Jc^T (Jc Jc^T)^+ from the eigendecomposition of Jc Jc^T, whose eigenvalues are the squared
singular values and whose eigenvectors the left singular vectors); two prong tips on the rigid trunk give rows
that are linearly dependent (the trunk can still roll about the line through them), and the
SVD removes that dependency instead of failing. P is symmetric and idempotent and P Jc^T = 0.

Eqs. 3 and 4, the split. Multiplying Eq. 1 by P removes the constraint forces (P Jc^T = 0):

    constraint-free (Eq. 3):  P M vdot + P h = P S^T tau
    constrained     (Eq. 4):  (I - P)(M vdot + h - S^T tau) = Jc^T lam

Eq. 5, the constrained acceleration. With M_c = P M + I - P (invertible whenever M is, [mixed]),
adding (I - P) vdot = -Jc^+ (Jcdot v + kd Jc v) to Eq. 3 gives

    vdot = M_c^-1 (P S^T tau - P h - Jc^+ (Jcdot v + kd Jc v)) = A u + vdot_0,

with u = P S^T tau [N, N m] the projected generalised force, A = M_c^-1 P [1/kg ...] the
constrained inverse inertia (symmetric, positive semi-definite, rank nv - rank Jc) and vdot_0 the
acceleration of the unforced constrained system [m/s^2, rad/s^2].

Eqs. 9 and 10, the impedance law. An operational task x with Jacobian J (m, nv) accelerates as
xddot = J A u + J vdot_0 + Jdot v. Its constrained operational-space inertia is
Lambda = (J A J^T)^+ [kg | kg m^2], and the impedance force

    F = Lambda (xddot_ref - J vdot_0 - Jdot v) - K e - D edot,   e = x - x_ref,

(the term Lambda (J vdot_0 + Jdot v) is the operational-space bias mu of the paper) applied as
u = J^T F gives the closed loop Lambda eddot + D edot + K e = F_ext: a spring K [N/m] and damper
D [N s/m] against any external force F_ext on the task point, the inertia left natural so that no
force sensor is needed. The lifted (pedipulation) feet are the first task. The torso (6 rows:
angular, linear, world frame) is the second, in the foot's dynamically consistent null space:
with Jbar = A J^T Lambda and N = I - Jbar J, the projected generalised force N^T J_b^T F_b does
not change xddot of the foot (J A N^T = 0), so the torso yields wherever the foot needs it. The
torso's force is F_b = Lambda_b|s (a_b* - J_b vdot_0 - Jdot_b v - J_b A u_s) with
Lambda_b|s = (J_b A N^T J_b^T)^+, where a_b* = a_ref + Kp (x_ref - x) + Kd (v_ref - v) uses
gains per unit of its (null-space, possibly rank-deficient) inertia [1/s^2, 1/s]. Further tasks
(a joint posture) follow the same recursion in the null space of all the tasks above.

Torques of the constraint-free space: tau_m = (P S^T)^+ u. With at least three non-collinear
held feet (or the prongs plus two feet) P S^T spans the range of P and P S^T tau_m = u; if not,
u is replaced by what the joints can produce, u = P S^T tau_m, so what follows stays consistent.

Eqs. 6 to 8, the QP over contact forces. The planned acceleration vdot fixes r = M vdot + h
[N, N m]. Eq. 1 then says S^T tau + Jc^T lam = r: its six floating-base rows constrain the
forces, Jc,u^T lam = r_u (the trunk's wrench balance), and its joint rows give the torques,
tau = r_a - Jc,a^T lam. The contact QP (Eq. 7) is

    min_lam   w_tau ||tau||^2 + w_f ||lam - lam_share||^2
    s.t.      Jc,u^T lam = r_u,
              ramp_i f_min <= f_n,i <= ramp_i f_max               (unilateral, minimum normal force)
              |f_t1,i|, |f_t2,i| <= mu_eff f_n,i                   (4-edge friction pyramid)
              |r_a - Jc,a^T lam| <= scale * tau_max                (torque limits)

with lam_share an even share of the weight [N], and f_n,i, f_t1,i, f_t2,i contact i's force along
the normal of the ground under it and along its tangents (`pedi_drake.friction`). The equalities
are eliminated (lam = lam_0 + Z z with Z a null-space basis of Jc,u^T) and the rest goes to DAQP.
The final torque is tau = tau_m + tau_c (Eq. 8) with tau_c = tau - tau_m; because r - Jc^T lam
lies in the range of I - P, P S^T tau_c = 0: the constrained-space torque never disturbs the
impedance.

Eq. 11, the force estimate. From the closed loop, the external force on the foot is estimated
from the motion alone: F_ext_hat = Lambda eddot + D edot + K e [N]; the torso's error does not
enter because the torso lives in the foot's null space.

The kernels loop over caller-owned arrays (a numpy call on an 18 x 18 costs more in dispatch than
in arithmetic) and return a status instead of raising, so that a control tick calling them always
returns. Matrices are C-ordered; task rows are passed stacked, with `*_start` arrays giving each
task's rows where there are several. tests/reference_projected_dynamics.py is the same law in
numpy on LAPACK and DAQP's Python module: the oracle of tests/test_projected_impedance_tick.py.
"""

import math

import numpy as np

from pedi_drake.friction import write_contact_force_rows
from pedi_drake.numerics import daqp_kernel
from pedi_drake.runtime.jit import kernel

# Status of `contact_forces`: the planned acceleration's wrench balance held exactly; held as
# nearly as the limits allow (the balance weighted, `RELAXED_BALANCE_WEIGHT`); no forces at all.
CONTACT_FORCES_OK, CONTACT_FORCES_INFEASIBLE, CONTACT_FORCES_RELAXED = 0, 1, 2
# [1 / N^2, in the units of the torque weight] the wrench balance's weight when it cannot hold
# exactly within the friction pyramids and the torque limits: 1 N of imbalance costs what 100 N m
# of torque does, so the forces come as near to the plan as the limits let them.
RELAXED_BALANCE_WEIGHT = 1e4
# A scale below zero tells symmetric_pseudo_inverse to take the largest eigenvalue as its scale.
_LARGEST = -1.0
# The forces fixed by the wrench balance alone may exceed their bounds by this much [N, N m]
# (projected_dynamics.solve_contact_forces).
_FIXED_FORCE_SLACK = 1e-6
_INFINITY = 1e30


# ------------------------------------------------------------------------------------------------
# Products (row-major loops: the innermost index runs along contiguous memory).


@kernel
def _transposed_multiply(A: np.ndarray, B: np.ndarray, out: np.ndarray) -> None:
    """out = A^T B."""
    out[:, :] = np.dot(np.ascontiguousarray(A.T), B)


@kernel
def _times(A: np.ndarray, x: np.ndarray, out: np.ndarray) -> None:
    """out = A x."""
    for i in range(A.shape[0]):
        s = 0.0
        for j in range(A.shape[1]):
            s += A[i, j] * x[j]
        out[i] = s


@kernel
def _transposed_times(A: np.ndarray, x: np.ndarray, out: np.ndarray) -> None:
    """out = A^T x."""
    out[:] = 0.0
    for i in range(A.shape[0]):
        a = x[i]
        if a != 0.0:
            for j in range(A.shape[1]):
                out[j] += A[i, j] * a


@kernel
def _norm(x: np.ndarray) -> float:
    s = 0.0
    for value in x:
        s += value * value
    return math.sqrt(s)


@kernel
def _symmetrize(A: np.ndarray) -> None:
    """A = (A + A^T) / 2, exactly symmetric."""
    n = A.shape[0]
    for i in range(n):
        for j in range(i):
            value = 0.5 * (A[i, j] + A[j, i])
            A[i, j] = value
            A[j, i] = value


# ------------------------------------------------------------------------------------------------
# Decompositions by LAPACK, products by BLAS (numba's np.linalg and np.dot). A decomposition that
# fails (a non-finite input, no convergence) returns a failure instead of raising.


@kernel
def multiply(A: np.ndarray, B: np.ndarray, out: np.ndarray) -> None:
    """out[:rows of A, :columns of B] = A B."""
    out[: A.shape[0], : B.shape[1]] = np.dot(A, B)


@kernel
def multiply_transposed(A: np.ndarray, B: np.ndarray, out: np.ndarray) -> None:
    """out[:rows of A, :rows of B] = A B^T."""
    out[: A.shape[0], : B.shape[0]] = np.dot(A, B.T)


@kernel
def _finite(A: np.ndarray) -> bool:
    for value in A.ravel():
        if not math.isfinite(value):
            return False
    return True


@kernel
def symmetric_eigen(A: np.ndarray, w: np.ndarray, W: np.ndarray) -> bool:
    """A = W^T diag(w) W for symmetric A (n, n), w ascending, the eigenvectors as the rows of W
    (LAPACK's dsyevd); False (w, W meaningless) for a non-finite A or no convergence."""
    if not _finite(A):
        return False
    try:
        values, vectors = np.linalg.eigh(A)
    except Exception:  # numba raises LinAlgError on no convergence; a tick must return
        return False
    w[:] = values
    W[:, :] = vectors.T
    return True


@kernel
def symmetric_pseudo_inverse(A: np.ndarray, rank_tolerance: float, scale: float, out: np.ndarray) -> int:
    """A^+ of a symmetric positive semi-definite A (n, n) into out (n, n); returns its rank, or -1
    when the decomposition fails. Eigenvalues above `rank_tolerance * scale` are kept, a negative
    `scale` meaning the largest eigenvalue; a largest eigenvalue (or scale) that is not positive
    gives zero and rank 0. A task projected into a null space passes the scale of its unprojected
    matrix, so that a used-up null space (every eigenvalue at rounding level) gives rank 0 instead
    of amplified rounding noise."""
    n = A.shape[0]
    out[:, :] = 0.0
    if n == 0:
        return 0
    w = np.empty(n)
    W = np.empty((n, n))
    if not symmetric_eigen(A, w, W):
        return -1
    reference = w[n - 1] if scale < 0.0 else scale
    if w[n - 1] <= 0.0 or reference <= 0.0:
        return 0
    threshold = rank_tolerance * reference
    rank = 0
    for k in range(n):
        if w[k] > threshold:
            rank += 1
            inverse = 1.0 / w[k]
            for i in range(n):
                scaled = W[k, i] * inverse
                for j in range(n):
                    out[i, j] += scaled * W[k, j]
    return rank


@kernel
def lu_solve(A: np.ndarray, B: np.ndarray) -> bool:
    """A X = B for square A (n, n) and B (n, k) by LU with partial pivoting (LAPACK's dgesv), X
    written over B; False for a non-finite or singular A (B then meaningless)."""
    if not _finite(A):
        return False
    try:
        X = np.linalg.solve(A, B)
    except Exception:  # numba raises LinAlgError on a singular A; a tick must return
        return False
    B[:, :] = X
    return True


# ------------------------------------------------------------------------------------------------
# Eqs. 2 to 5.


@kernel
def constrained_dynamics(
    M: np.ndarray,
    h: np.ndarray,
    Jc: np.ndarray,
    Jcdot_v: np.ndarray,
    v: np.ndarray,
    contact_damping: float,
    rank_tolerance: float,
    P: np.ndarray,
    A: np.ndarray,
    vdot_0: np.ndarray,
) -> int:
    """projected_dynamics.constrained_dynamics: the projector P (nv, nv), the constrained inverse
    inertia A (nv, nv) and the drift vdot_0 (nv,) into the given arrays; returns the rank of Jc
    (3k, nv), or -1 when a decomposition fails (non-finite terms, a singular M_c)."""
    nv = M.shape[0]
    rows = Jc.shape[0]
    # Jc^+ = Jc^T (Jc Jc^T)^+; the eigenvalues of Jc Jc^T are the squared singular values of Jc.
    gram = np.empty((rows, rows))
    multiply_transposed(Jc, Jc, gram)
    gram_pinv = np.empty((rows, rows))
    rank = symmetric_pseudo_inverse(gram, rank_tolerance * rank_tolerance, _LARGEST, gram_pinv)
    if rank < 0:
        return -1
    Jc_pinv = np.empty((nv, rows))
    _transposed_multiply(Jc, gram_pinv, Jc_pinv)
    multiply(Jc_pinv, Jc, P)
    for i in range(nv):
        for j in range(nv):
            P[i, j] = -P[i, j]
        P[i, i] += 1.0
    _symmetrize(P)
    # M_c = P M + I - P, and the right-hand sides [P, -(P h) - Jc^+ (Jcdot v + kd Jc v)].
    M_c = np.empty((nv, nv))
    multiply(P, M, M_c)
    for i in range(nv):
        for j in range(nv):
            M_c[i, j] -= P[i, j]
        M_c[i, i] += 1.0
    rhs = np.empty((nv, nv + 1))
    drift = np.empty(nv)
    _times(P, h, drift)
    if rows:
        contact_velocity = np.empty(rows)
        _times(Jc, v, contact_velocity)
        for i in range(rows):
            contact_velocity[i] = Jcdot_v[i] + contact_damping * contact_velocity[i]
        constraint_acceleration = np.empty(nv)
        _times(Jc_pinv, contact_velocity, constraint_acceleration)
        for i in range(nv):
            drift[i] += constraint_acceleration[i]
    for i in range(nv):
        for j in range(nv):
            rhs[i, j] = P[i, j]
        rhs[i, nv] = -drift[i]
    if not lu_solve(M_c, rhs):
        return -1
    for i in range(nv):
        for j in range(nv):
            A[i, j] = rhs[i, j]
        vdot_0[i] = rhs[i, nv]
    _symmetrize(A)
    return rank


# ------------------------------------------------------------------------------------------------
# Eqs. 9 and 10.


@kernel
def _task_residual(J, Jdot_v, desired, A, u, vdot_0) -> float:
    """|desired - J (A u + vdot_0) - Jdot v| [m/s^2 ...]."""
    nv = A.shape[0]
    vdot = np.empty(nv)
    _times(A, u, vdot)
    for i in range(nv):
        vdot[i] += vdot_0[i]
    s = 0.0
    for i in range(J.shape[0]):
        value = desired[i] - Jdot_v[i]
        for j in range(nv):
            value -= J[i, j] * vdot[j]
        s += value * value
    return math.sqrt(s)


@kernel
def _remove_from_null_space(N, JA, Lambda, J) -> None:
    """N -= (A J^T Lambda) J, with JA = J A (A symmetric) and Lambda symmetric."""
    m, nv = JA.shape
    Y = np.empty((m, nv))  # Lambda J A = (A J^T Lambda)^T
    multiply(Lambda, JA, Y)
    for p in range(m):
        for i in range(nv):
            y = Y[p, i]
            if y != 0.0:
                for j in range(nv):
                    N[i, j] -= y * J[p, j]


@kernel
def prioritized_force(
    A: np.ndarray,
    vdot_0: np.ndarray,
    P: np.ndarray,
    free_dimensions: int,
    J: np.ndarray,
    Jdot_v: np.ndarray,
    error: np.ndarray,
    error_rate: np.ndarray,
    acceleration_ref: np.ndarray,
    stiffness: np.ndarray,
    damping: np.ndarray,
    lower_J: np.ndarray,
    lower_Jdot_v: np.ndarray,
    lower_desired: np.ndarray,
    lower_start: np.ndarray,
    rank_tolerance: float,
    u_out: np.ndarray,
    impedance_force: np.ndarray,
    impedance_inertia: np.ndarray,
    residuals: np.ndarray,
) -> int:
    """projected_dynamics.prioritized_force: the impedance task (J (m, nv) and its per-row terms)
    first, then each lower task (rows lower_start[t]:lower_start[t + 1] of lower_J, lower_Jdot_v
    and the desired accelerations lower_desired) in the dynamically consistent null space of all
    above. Writes P u into u_out (nv,), F (m,) and Lambda (m, m) of the impedance level and each
    level's residual into `residuals`; returns the number of residuals, -1 on a failed
    decomposition."""
    nv = A.shape[0]
    m = J.shape[0]
    u = np.zeros(nv)
    N = np.eye(nv)
    count = 0
    used = 0
    impedance_inertia[:, :] = 0.0
    impedance_force[:] = 0.0
    if m:
        JA = np.empty((m, nv))
        multiply(J, A, JA)
        inertia = np.empty((m, m))
        multiply_transposed(JA, J, inertia)
        used = symmetric_pseudo_inverse(inertia, rank_tolerance, _LARGEST, impedance_inertia)
        if used < 0:
            return -1
        free = np.empty(m)
        _times(J, vdot_0, free)
        for i in range(m):
            free[i] = acceleration_ref[i] - free[i] - Jdot_v[i]
        _times(impedance_inertia, free, impedance_force)
        for i in range(m):
            impedance_force[i] -= stiffness[i] * error[i] + damping[i] * error_rate[i]
        _transposed_times(J, impedance_force, u)
        _remove_from_null_space(N, JA, impedance_inertia, J)
        # The closed loop Lambda (xddot - xddot_ref) + K e + D edot = 0 the law achieves [N].
        vdot = np.empty(nv)
        _times(A, u, vdot)
        for i in range(nv):
            vdot[i] += vdot_0[i]
        achieved = np.empty(m)
        _times(J, vdot, achieved)
        for i in range(m):
            achieved[i] += Jdot_v[i] - acceleration_ref[i]
        loop = np.empty(m)
        _times(impedance_inertia, achieved, loop)
        for i in range(m):
            loop[i] += stiffness[i] * error[i] + damping[i] * error_rate[i]
        residuals[count] = _norm(loop)
        count += 1
    for t in range(lower_start.shape[0] - 1):
        rows = lower_start[t + 1] - lower_start[t]
        Jt = lower_J[lower_start[t] : lower_start[t + 1]]
        bias = lower_Jdot_v[lower_start[t] : lower_start[t + 1]]
        desired = lower_desired[lower_start[t] : lower_start[t + 1]]
        if used >= free_dimensions:
            # The tasks above use every constraint-free direction: nothing is left for this one.
            residuals[count] = _task_residual(Jt, bias, desired, A, u, vdot_0)
            count += 1
            continue
        J_prec = np.empty((rows, nv))
        multiply(Jt, N, J_prec)
        # The unprojected task's inverse inertia sets the scale of the rank decision.
        JtA = np.empty((rows, nv))
        multiply(Jt, A, JtA)
        unprojected = np.empty((rows, rows))
        multiply_transposed(JtA, Jt, unprojected)
        scale = 0.0
        for i in range(rows):
            for j in range(rows):
                scale += unprojected[i, j] * unprojected[i, j]
        scale = math.sqrt(scale)
        JpA = np.empty((rows, nv))
        multiply(J_prec, A, JpA)
        inertia = np.empty((rows, rows))
        multiply_transposed(JpA, J_prec, inertia)
        Lambda = np.empty((rows, rows))
        rank = symmetric_pseudo_inverse(inertia, rank_tolerance, scale, Lambda)
        if rank < 0:
            return -1
        used += rank
        if rank == 0:
            residuals[count] = _task_residual(Jt, bias, desired, A, u, vdot_0)
            count += 1
            continue
        vdot = np.empty(nv)
        _times(A, u, vdot)
        for i in range(nv):
            vdot[i] += vdot_0[i]
        wanted = np.empty(rows)
        _times(Jt, vdot, wanted)
        for i in range(rows):
            wanted[i] = desired[i] - wanted[i] - bias[i]
        F = np.empty(rows)
        _times(Lambda, wanted, F)
        for p in range(rows):
            f = F[p]
            if f != 0.0:
                for j in range(nv):
                    u[j] += J_prec[p, j] * f
        _remove_from_null_space(N, JpA, Lambda, J_prec)
        residuals[count] = _task_residual(Jt, bias, desired, A, u, vdot_0)
        count += 1
    _times(P, u, u_out)
    return count


@kernel
def constraint_free_torque(
    A: np.ndarray,
    vdot_0: np.ndarray,
    P: np.ndarray,
    u: np.ndarray,
    v_joints: np.ndarray,
    rank_tolerance: float,
    tau_m: np.ndarray,
    vdot: np.ndarray,
) -> bool:
    """projected_dynamics.constraint_free_torque: tau_m = (P S^T)^+ u (12,), in the order of the
    joints' velocity indices `v_joints`, and vdot = A P S^T tau_m + vdot_0 (nv,); False on a
    failed decomposition."""
    nv = A.shape[0]
    na = v_joints.shape[0]
    # (P S^T)^+ = (S P S^T)^+ S P (P symmetric, idempotent).
    joint_block = np.empty((na, na))
    for a in range(na):
        for b in range(na):
            joint_block[a, b] = P[v_joints[a], v_joints[b]]
    joint_block_pinv = np.empty((na, na))
    if symmetric_pseudo_inverse(joint_block, rank_tolerance, _LARGEST, joint_block_pinv) < 0:
        return False
    Pu = np.empty(nv)
    _times(P, u, Pu)
    SPu = np.empty(na)
    for a in range(na):
        SPu[a] = Pu[v_joints[a]]
    _times(joint_block_pinv, SPu, tau_m)
    u_effective = np.zeros(nv)
    for i in range(nv):
        s = 0.0
        for a in range(na):
            s += P[i, v_joints[a]] * tau_m[a]
        u_effective[i] = s
    _times(A, u_effective, vdot)
    for i in range(nv):
        vdot[i] += vdot_0[i]
    return True


# ------------------------------------------------------------------------------------------------
# Eqs. 6 to 8.


@kernel
def contact_forces(
    Jc: np.ndarray,
    r: np.ndarray,
    unactuated: np.ndarray,
    actuated: np.ndarray,
    ramp: np.ndarray,
    friction: float,
    normals: np.ndarray,
    f_min: float,
    f_max: float,
    torque_limit: np.ndarray,
    force_share: np.ndarray,
    torque_weight: float,
    force_weight: float,
    rank_tolerance: float,
    proximal_weight: float,
    lam: np.ndarray,
    tau: np.ndarray,
    equality_residual: np.ndarray,
) -> int:
    """projected_dynamics.solve_contact_forces (Eq. 7) for the k held contacts (Jc (3k, nv), r =
    M vdot + h, ramp (k,), force_share (3k,), normals (k, 3): the unit normal (world) of the
    ground under each, the axis of its friction pyramid of slope `friction` and of its force
    bounds): the forces lam (3k,) [N], the torques tau (12,)
    [N m] and |Jc,u^T lam - r_u| in equality_residual[0]; returns CONTACT_FORCES_OK,
    CONTACT_FORCES_RELAXED (no forces within the limits hold the balance: the nearest that do,
    `_relaxed_contact_forces`) or CONTACT_FORCES_INFEASIBLE (lam and tau then meaningless). The
    QPs go to DAQP (`daqp_kernel.solve_qp`) with `proximal_weight` [units of its Hessian]."""
    n = Jc.shape[0]
    k = n // 3
    na = actuated.shape[0]
    nu = unactuated.shape[0]
    r_u = np.empty(nu)
    for i in range(nu):
        r_u[i] = r[unactuated[i]]
    r_a = np.empty(na)
    for i in range(na):
        r_a[i] = r[actuated[i]]
    if n == 0:
        residual = _norm(r_u)
        equality_residual[0] = residual
        if not residual <= 1e-6 * max(1.0, _norm(r)):
            return CONTACT_FORCES_INFEASIBLE
        for i in range(na):
            if abs(r_a[i]) > torque_limit[i]:
                return CONTACT_FORCES_INFEASIBLE
            tau[i] = r_a[i]
        return CONTACT_FORCES_OK
    T = np.empty((na, n))  # tau = r_a + T lam
    for i in range(na):
        for j in range(n):
            T[i, j] = -Jc[j, actuated[i]]
    B = np.empty((nu, n))  # the floating base's rows of Jc^T
    for i in range(nu):
        for j in range(n):
            B[i, j] = Jc[j, unactuated[i]]
    # One eigendecomposition of B^T B gives both the minimum-norm lam_0 and the null space Z.
    BtB = np.empty((n, n))
    _transposed_multiply(B, B, BtB)
    w = np.empty(n)
    W = np.empty((n, n))  # eigenvectors as rows, eigenvalues ascending
    if not symmetric_eigen(BtB, w, W):
        return CONTACT_FORCES_INFEASIBLE
    threshold = rank_tolerance * rank_tolerance * max(w[n - 1], 1e-300)
    nz = 0
    for i in range(n):
        if not w[i] > threshold:
            nz += 1
    Bt_r = np.empty(n)
    _transposed_times(B, r_u, Bt_r)
    lam_0 = np.zeros(n)
    for i in range(n):
        if w[i] > threshold:
            coefficient = 0.0
            for j in range(n):
                coefficient += W[i, j] * Bt_r[j]
            coefficient /= w[i]
            for j in range(n):
                lam_0[j] += W[i, j] * coefficient
    # G_all lam <= g_all: the friction pyramid and force bounds per contact, then the torque limits.
    rows = 6 * k + 2 * na
    G = np.zeros((rows, n))
    g = np.empty(rows)
    for c in range(k):
        write_contact_force_rows(G, g, 6 * c, 3 * c, friction, normals[c], f_min * ramp[c], f_max * ramp[c])
    for i in range(na):
        for j in range(n):
            G[6 * k + i, j] = T[i, j]
            G[6 * k + na + i, j] = -T[i, j]
        g[6 * k + i] = torque_limit[i] - r_a[i]
        g[6 * k + na + i] = torque_limit[i] + r_a[i]
    # The objective over lam: torques and the forces' distance from their share.
    H_lam = np.empty((n, n))
    _transposed_multiply(T, T, H_lam)
    for i in range(n):
        for j in range(n):
            H_lam[i, j] *= torque_weight
        H_lam[i, i] += force_weight
    f_lam = np.empty(n)
    _transposed_times(T, r_a, f_lam)
    for i in range(n):
        f_lam[i] = torque_weight * f_lam[i] - force_weight * force_share[i]
    exact = True
    if nz == 0:
        for j in range(n):
            lam[j] = lam_0[j]
        values = np.empty(rows)
        _times(G, lam, values)
        for i in range(rows):
            if not values[i] <= g[i] + _FIXED_FORCE_SLACK:
                exact = False
    else:
        Z = np.empty((n, nz))  # the eigenvectors of the dropped eigenvalues, as columns
        for i in range(nz):
            for j in range(n):
                Z[j, i] = W[i, j]
        HZ = np.empty((n, nz))
        multiply(H_lam, Z, HZ)
        H = np.empty((nz, nz))
        _transposed_multiply(Z, HZ, H)
        linear = np.empty(n)
        _times(H_lam, lam_0, linear)
        for i in range(n):
            linear[i] += f_lam[i]
        f = np.empty(nz)
        _transposed_times(Z, linear, f)
        C = np.empty((rows, nz))
        multiply(G, Z, C)
        upper = np.empty(rows)
        _times(G, lam_0, upper)
        for i in range(rows):
            upper[i] = g[i] - upper[i]
        z = np.zeros(nz)
        lower = np.full(rows, -daqp_kernel.INFINITE_BOUND)
        sense = np.zeros(rows, np.int32)
        exit_flag = daqp_kernel.solve_qp(
            H, f, C, upper, lower, sense, proximal_weight, daqp_kernel.QP_FIXED_POINT, 0.0, z, np.empty(rows)
        )
        exact = daqp_kernel.solved(exit_flag)
        for i in range(nz):
            exact = exact and math.isfinite(z[i])
        if exact:
            _times(Z, z, lam)
            for j in range(n):
                lam[j] += lam_0[j]
    status = CONTACT_FORCES_OK
    if not exact:
        # No forces within the limits give the planned acceleration (a swing's reaction the three
        # stance feet cannot hold, say): the nearest balance the limits allow, the trunk then
        # accelerating a little off its plan, rather than no command at all.
        if not _relaxed_contact_forces(B, r_u, H_lam, f_lam, G, g, proximal_weight, lam):
            return CONTACT_FORCES_INFEASIBLE
        status = CONTACT_FORCES_RELAXED
    balance = np.empty(nu)
    _times(B, lam, balance)
    for i in range(nu):
        balance[i] -= r_u[i]
    equality_residual[0] = _norm(balance)
    _times(T, lam, tau)
    for i in range(na):
        tau[i] += r_a[i]
    return status


@kernel
def _relaxed_contact_forces(B, r_u, H_lam, f_lam, G, g, proximal_weight: float, lam) -> bool:
    """Writes into lam the forces that minimise the contact QP's objective plus
    RELAXED_BALANCE_WEIGHT ||B lam - r_u||^2 within G lam <= g; False if DAQP finds none."""
    n, rows = lam.shape[0], g.shape[0]
    H = np.empty((n, n))
    _transposed_multiply(B, B, H)
    f = np.empty(n)
    _transposed_times(B, r_u, f)
    for i in range(n):
        for j in range(n):
            H[i, j] = H_lam[i, j] + RELAXED_BALANCE_WEIGHT * H[i, j]
        f[i] = f_lam[i] - RELAXED_BALANCE_WEIGHT * f[i]
    lam[:] = 0.0
    lower = np.full(rows, -daqp_kernel.INFINITE_BOUND)
    sense = np.zeros(rows, np.int32)
    exit_flag = daqp_kernel.solve_qp(
        H, f, G, g.copy(), lower, sense, proximal_weight, daqp_kernel.QP_FIXED_POINT, 0.0, lam, np.empty(rows)
    )
    if not daqp_kernel.solved(exit_flag):
        return False
    for j in range(n):
        if not math.isfinite(lam[j]):
            return False
    return True


@kernel
def impedance_force_estimate(
    inertia_rows: np.ndarray,
    stiffness: np.ndarray,
    damping: np.ndarray,
    error: np.ndarray,
    error_rate: np.ndarray,
    error_acceleration: np.ndarray,
    out: np.ndarray,
) -> None:
    """Eq. 11: F_ext_hat = Lambda eddot + D edot + K e [N] into out, with `inertia_rows` the task's
    rows of the level's Lambda and `error_acceleration` the whole level's eddot."""
    _times(inertia_rows, error_acceleration, out)
    for i in range(out.shape[0]):
        out[i] += damping[i] * error_rate[i] + stiffness[i] * error[i]
