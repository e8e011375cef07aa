"""Dense convex QP, compiled with numba and callable from other compiled kernels.

    minimise   0.5 y'H y + f'y      over y (n,)
    subject to C y <= u             (m rows; u_i >= 1e30 or +inf: no bound)

with H symmetric positive SEMI-definite. The hierarchical QP's levels are such problems (H = A'A
of a level's least squares, often singular, plus weights on soft violations), and each must be
solved exactly, not regularised: a Tikhonov term would trade a level's own optimum for a smaller
step, which breaks the strict priorities.

Algorithm: proximal-point outer iterations around a dual active-set inner solver, with an exact
step on the active face and primal active-set steps between outer iterations. Why these: a dual
active-set method needs no feasible starting point (no phase 1), is exact once its active set is
right, costs O(n^2) per change of the active set (the controller's levels have 6 to 45
variables, 30 to 110 rows and rarely more than 15 active), and restarts from a given active set
(the previous tick's). It needs a positive definite Hessian, which the proximal term supplies
without changing the problem's solution, unlike a Tikhonov term.

1. Proximal point (Rockafellar 1976). For a weight eps > 0 and a centre y_k,

       y_k+1 = argmin 0.5 y'H y + f'y + eps/2 ||y - y_k||^2   s.t.  C y <= u,

   a strictly convex QP (Hessian G = H + eps I, factorised once per solve). Its KKT conditions are
   those of the original problem except stationarity, whose residual is exactly
   H y_k+1 + f + C'lam = -eps (y_k+1 - y_k): the iterates converge to a solution of the original
   problem, and eps ||y_k+1 - y_k|| is the stationarity residual of the current iterate.

2. Each strictly convex subproblem is solved by the dual active-set method of Goldfarb and Idnani
   (1983). It keeps an active set A of linearly independent rows, the minimiser y of the
   subproblem with the rows of A as equalities, and multipliers lam_A >= 0. With G = L L'
   (Cholesky) and the QR factorisation L^-1 C_A' = Q [R; 0], the matrix J = L^-T Q = [J1 J2] gives
   everything: J2 spans the null space of C_A, and for a violated row p (c_p'y > u_p), with
   d = J'c_p = [d1; d2], the primal direction is z = -J2 d2 and the dual one r = R^-1 d1: along
   y + t z, lam_A - t r, lam_p = t, the rows of A stay active, stationarity holds and the violation
   of p falls as s_p - t ||d2||^2. The step is the smaller of the full step t2 = s_p / ||d2||^2
   (p joins A) and the partial step t1 = min over r_j > 0 of lam_j / r_j (row j leaves A, then the
   same p again). The dual objective never decreases and rises strictly with each full step, so
   no active set repeats. J and R are updated in O(n^2) when a row joins (a Householder
   reflection of J2 that maps d2 to a multiple of its first axis) or leaves (Givens rotations
   that restore R's triangle); a row whose d2 vanishes (dependent on A: redundant or degenerate rows) can only
   be added after partial steps make room, and when it is dependent with no r_j > 0, row p with
   the rows of A is a Farkas certificate of infeasibility: c_p = C_A'r with r <= 0 while
   c_p'y > u_p where C_A y = u_A, so no y meets all of them, by the margin r'u_A - u_p. A margin
   within the primal tolerance is no certificate: the violation is the rounding of y at a
   degenerate vertex (many rows of very different norms through one point), row p is implied by
   A, and it is left out until A changes.

   Between outer iterations only the linear term f - eps y_k changes, so the factorisation of A
   stays valid: each outer iteration restarts from the previous active set at the cost of
   recomputing (y, lam_A) from it, dropping rows whose multiplier turned negative. A caller's
   active set (the previous control tick's) warm-starts the first one the same way. The same
   recomputation ends each inner solve: the steps move y by increments, whose rounding would
   otherwise leave an ill-conditioned vertex 1e-10 off its rows.

3. Exact step. The proximal iterates approach the solution only linearly where H is small
   compared with eps, but once the active set A is the optimal one the solution is that of an
   equality-constrained QP. In the coordinates y = y_k+1 + J2 w its reduced Hessian is
   J2'H J2 = I - eps J2'J2 (because J2'G J2 = I) and its gradient J2'(H y_k+1 + f), so a pivoted
   Cholesky factorisation of that (n - q)-square matrix (semi-definite: zero pivots are the
   directions in which the solution is not unique, left at zero) gives the face's minimiser y*.
   Its multipliers follow from stationarity, lam* = -R^-1 J1'(H y* + f). If y* passes the KKT
   test of the original problem (stationarity, primal feasibility, lam* >= 0, each to its
   tolerance below) it is returned: an exact solution, typically after the first outer iteration
   (9 in 10 of the recorded controller QPs).

4. Primal active-set steps (the classic primal method, e.g. Nocedal and Wright, ch. 16.5) from
   the feasible y_k+1 when y* fails that test. Where the curvature is far below eps the proximal
   steps move about |gradient| / eps each, 1e-6 of the way in a controller QP that needed 30 000
   outer iterations without these steps. So, until a step cannot change the face:
   * y* violates rows: y moves towards y* until the first row blocks, and that row joins A (the
     objective is convex on the segment with its minimum at y*, so it falls);
   * y* is feasible but a multiplier is negative: y = y*, and that row leaves A;
   * the reduced system is inconsistent (the objective falls without bound on the face): y moves
     along d = -sum (g2'n_j) n_j over the null vectors n_j of the reduced Hessian (zero
     curvature, slope -sum (g2'n_j)^2) until the first row blocks, which joins A; if none does,
     d is a direction of unbounded descent. Each step ends with a new exact step.
   The proximal iterations then go on from this better feasible point; its active set warm-starts
   the next inner solve (rows whose multiplier there is negative leave first).

Stopping and status:

* OPTIMAL: the exact step passed the KKT test, or the proximal step became small enough,
  eps ||y_k+1 - y_k||_inf <= stationarity_tolerance * scale (y_k+1 is then feasible within
  primal_tolerance, with multipliers >= 0 meeting complementarity, and stationary within that
  residual). The scale is the largest of 1, |f|_inf, |H y|_inf and |C_A'lam|_inf [units of f]:
  a gradient below the tolerance in absolute terms counts as zero. Without that floor a level
  whose tasks are already met (H and f of rounding size, 1e-33 and 1e-18 in the controller) would
  chase its rounding: the proximal steps along a linear objective of size |f| are |f| / eps long.
* INFEASIBLE: the certificate of step 2 (or a row with u_i = -inf).
* UNBOUNDED: a direction of recession (H d = 0, C d <= 0, f'd < 0, each to a relative tolerance
  of 1e-9): a proximal step, or the descent ray of step 4 that no row blocks.
* ITERATION_LIMIT: `max_iterations` inner steps (full, partial, primal, and one per outer
  iteration) used; y is the last iterate, not proven optimal (and, stopped inside an inner solve, not
  feasible either).
* NUMERICAL_FAILURE: non-finite input, H + eps I not positive definite (H not semi-definite), a
  non-finite iterate, arrays too small for the problem, or any exception in the compiled code
  (the kernel never raises). y is then zero.

y is never NaN. Where the solution is not unique the one returned is the exact step's (zero in
the reduced Hessian's null directions from the proximal iterate), not necessarily DAQP's.

The kernel works on caller-owned arrays: `make_workspace(n_max, m_max)` sizes them once for any
problem up to that size, so a controller allocates nothing per tick.
"""

import dataclasses
import math

import numpy as np

from pedi_drake.control.small_linalg import cholesky_in_place
from pedi_drake.runtime.jit import kernel

# Status codes returned by `solve_dense_qp_kernel`.
OPTIMAL = 1
INFEASIBLE = -1
UNBOUNDED = -2
ITERATION_LIMIT = -3
NUMERICAL_FAILURE = -4

STATUS_NAMES = {
    OPTIMAL: "optimal",
    INFEASIBLE: "infeasible",
    UNBOUNDED: "unbounded",
    ITERATION_LIMIT: "iteration limit",
    NUMERICAL_FAILURE: "numerical failure",
}

# Upper bounds at or beyond this are no bound (the convention of DAQP, which the controller used).
INFINITE_BOUND = 1e30
# A row whose component outside the active rows' span (in the metric of G) is below this fraction
# of its norm is dependent on them: adding it would make R singular.
_DEPENDENCY_TOLERANCE = 1e-10
# Dual-step entries r_j ||c_j|| below this fraction of their largest are rounding of a zero
# (degenerate rows).
_ZERO_TOLERANCE = 1e-13
# Pivots of the reduced Hessian I - eps J2'J2 (eigenvalues in [0, 1]) below this are zero
# curvature: H's curvature there is below about 1e-12 eps.
_RANK_TOLERANCE = 1e-12
# Relative tolerance of the recession-direction test (UNBOUNDED).
_RECESSION_TOLERANCE = 1e-9

# Outcomes of the exact step.
_EXACT_OPTIMAL = 0
_EXACT_FACE_MINIMISER = 1
_EXACT_RAY = 2
_EXACT_NOT_STATIONARY = 3

# Rows of the matrix workspace (each n_max x n_max).
_M_FACTOR = 0  # L, the Cholesky factor of H + eps I (lower)
_M_J = 1  # Jt = J' = Q'L^-1: J by rows, so that its column operations run along contiguous memory
_M_R = 2  # R (upper, q x q)
_M_REDUCED = 3  # reduced Hessian of the exact step and its pivoted factor
NUM_MATRICES = 4
# Rows of the vector workspace (each max(n_max, m_max) long).
_V_D = 0  # d = J'c_p
_V_Z = 1  # primal direction
_V_R = 2  # dual direction over the active rows
_V_LAMBDA = 3  # multipliers of the active rows, in active-set order
_V_ROW_SCALE = 4  # 1 / ||c_i|| (1 for a zero row)
_V_CENTRE = 5  # proximal centre y_k
_V_LINEAR = 6  # linear term of the subproblem, f - eps y_k
_V_W = 7  # scratch (n)
_V_GRADIENT = 8  # H y + f
_V_Y_EXACT = 9  # the exact step's point y*
_V_LAMBDA_EXACT = 10  # its multipliers
_V_VALUES = 11  # C y - u (m)
_V_VALUES_EXACT = 12  # C y* - u (m)
_V_RAY = 13  # a direction of zero curvature and descent on the face (n)
NUM_VECTORS = 14
# Rows of the integer workspace.
_I_IS_ACTIVE = 0  # 1 for rows in the active set, _IMPLIED for rows left out as implied by it (m)
_I_PERMUTATION = 1  # pivot order of the reduced Hessian (n)
NUM_INTEGER_ROWS = 2
_IMPLIED = 2


@dataclasses.dataclass(frozen=True)
class DenseQpSettings:
    """Settings of `solve` (the kernel takes them as plain numbers)."""

    # Proximal weight eps [units of H]: larger converges in fewer outer iterations where H is
    # small, smaller keeps H + eps I closer to H; the exact step makes the result independent of it.
    prox_weight: float = 1e-5
    # Largest accepted violation c_i'y - u_i [units of u].
    primal_tolerance: float = 1e-9
    # Most negative accepted multiplier of the exact step, times its row's norm, relative to the
    # gradient's scale [-].
    dual_tolerance: float = 1e-9
    # Largest accepted stationarity residual, relative to the gradient's scale [-].
    stationarity_tolerance: float = 1e-9
    # Bound on inner steps (full, partial and primal) plus outer iterations [-].
    max_iterations: int = 1000


_DEFAULT_SETTINGS = DenseQpSettings()


@dataclasses.dataclass
class DenseQpSolution:
    """Result of `solve`."""

    y: np.ndarray  # (n,) the solution (see `status`)
    status: int  # OPTIMAL, INFEASIBLE, UNBOUNDED, ITERATION_LIMIT or NUMERICAL_FAILURE
    multipliers: np.ndarray  # (m,) lam >= 0 of every row (zero off the active set)
    active: np.ndarray  # (q,) indices of the active rows, linearly independent
    iterations: int  # inner steps plus outer iterations used


@dataclasses.dataclass
class DenseQpWorkspace:
    """Scratch arrays of the kernel for problems of up to n_max variables and m_max rows."""

    matrices: np.ndarray  # (4, n_max, n_max)
    transposed: np.ndarray  # (n_max, m_max): C' (contiguous columns of C make C y vectorisable)
    vectors: np.ndarray  # (14, max(n_max, m_max))
    integers: np.ndarray  # (2, max(n_max, m_max)) int64

    @property
    def n_max(self) -> int:
        return self.matrices.shape[1]

    @property
    def m_max(self) -> int:
        return self.transposed.shape[1]


@kernel
def workspace_arrays(n_max: int, m_max: int):
    """(matrices, transposed, vectors, integers): the kernel's scratch arrays for any problem with
    n <= n_max variables and m <= m_max rows (callable from compiled code)."""
    length = max(n_max, m_max, 1)
    return (
        np.zeros((NUM_MATRICES, n_max, n_max)),
        np.zeros((n_max, m_max)),
        np.zeros((NUM_VECTORS, length)),
        np.zeros((NUM_INTEGER_ROWS, length), dtype=np.int64),
    )


_PRIMAL_TOLERANCE = _DEFAULT_SETTINGS.primal_tolerance
_DUAL_TOLERANCE = _DEFAULT_SETTINGS.dual_tolerance
_STATIONARITY_TOLERANCE = _DEFAULT_SETTINGS.stationarity_tolerance
_MAX_ITERATIONS = _DEFAULT_SETTINGS.max_iterations


@kernel
def solve_with_defaults(H, f, C, u, prox_weight, y, workspace) -> int:
    """`solve_dense_qp_kernel` at the default tolerances (DenseQpSettings) from compiled code,
    without a warm start: y (n,) and the status. `workspace`: (matrices, transposed, vectors,
    integers) of `workspace_arrays` for at least this size."""
    n, m = f.shape[0], u.shape[0]
    matrices, transposed, vectors, integers = workspace
    status, _, _ = solve_dense_qp_kernel(
        H,
        f,
        C,
        u,
        prox_weight,
        _PRIMAL_TOLERANCE,
        _DUAL_TOLERANCE,
        _STATIONARITY_TOLERANCE,
        _MAX_ITERATIONS,
        y,
        np.empty(m),
        np.empty(max(n, 1), np.int64),
        0,
        matrices,
        transposed,
        vectors,
        integers,
    )
    return status


def make_workspace(n_max: int, m_max: int) -> DenseQpWorkspace:
    """Workspace for any problem with n <= n_max variables and m <= m_max rows."""
    matrices, transposed, vectors, integers = workspace_arrays(n_max, m_max)
    return DenseQpWorkspace(matrices=matrices, transposed=transposed, vectors=vectors, integers=integers)


def solve(
    H: np.ndarray,
    f: np.ndarray,
    C: np.ndarray,
    u: np.ndarray,
    settings: DenseQpSettings | None = None,
    initial_active: np.ndarray | None = None,
    workspace: DenseQpWorkspace | None = None,
) -> DenseQpSolution:
    """min 0.5 y'Hy + f'y s.t. C y <= u (see the module docstring); never raises on a bad problem:
    the status says what happened.

    `initial_active`: row indices to warm-start from (e.g. the previous solve's `active`).
    """
    settings = settings or _DEFAULT_SETTINGS
    H = np.ascontiguousarray(H, dtype=float)
    f = np.ascontiguousarray(f, dtype=float)
    u = np.ascontiguousarray(u, dtype=float)
    n, m = len(f), len(u)
    C = np.ascontiguousarray(C, dtype=float).reshape(m, n)
    if H.shape != (n, n):
        raise ValueError(f"H must be ({n}, {n}), got {H.shape}")
    if workspace is None or workspace.n_max < n or workspace.m_max < m:
        workspace = make_workspace(n, m)
    y = np.zeros(n)
    multipliers = np.zeros(m)
    active = np.zeros(max(n, 1), dtype=np.int64)
    num_initial = 0
    if initial_active is not None:
        initial = np.asarray(initial_active, dtype=np.int64)[:n]
        num_initial = len(initial)
        active[:num_initial] = initial
    status, num_active, iterations = solve_dense_qp_kernel(
        H,
        f,
        C,
        u,
        float(settings.prox_weight),
        float(settings.primal_tolerance),
        float(settings.dual_tolerance),
        float(settings.stationarity_tolerance),
        int(settings.max_iterations),
        y,
        multipliers,
        active,
        num_initial,
        workspace.matrices,
        workspace.transposed,
        workspace.vectors,
        workspace.integers,
    )
    return DenseQpSolution(y, int(status), multipliers, active[:num_active].copy(), int(iterations))


def solve_qp(
    H: np.ndarray,
    f: np.ndarray,
    C: np.ndarray,
    u: np.ndarray,
    settings: DenseQpSettings = _DEFAULT_SETTINGS,
    workspace: DenseQpWorkspace | None = None,
) -> tuple[np.ndarray, int]:
    """(y, status) of min 0.5 y'Hy + f'y s.t. C y <= u; status is OPTIMAL on success.

    The lean path of `solve` (no multipliers, no warm start, no shape checks) for callers in
    Python that solve many small QPs; the arrays reach the kernel as C-contiguous float64 (one
    compiled signature, loaded by `warm_up`).
    """
    n = f.shape[0]
    m = u.shape[0]
    if workspace is None or workspace.n_max < n or workspace.m_max < m:
        workspace = make_workspace(n, m)
    y = np.empty(n)
    status, _, _ = solve_dense_qp_kernel(
        np.ascontiguousarray(H, dtype=float),
        np.ascontiguousarray(f, dtype=float),
        np.ascontiguousarray(C, dtype=float).reshape(m, n),
        np.ascontiguousarray(u, dtype=float),
        float(settings.prox_weight),
        float(settings.primal_tolerance),
        float(settings.dual_tolerance),
        float(settings.stationarity_tolerance),
        int(settings.max_iterations),
        y,
        np.empty(m),
        np.empty(max(n, 1), dtype=np.int64),
        0,
        workspace.matrices,
        workspace.transposed,
        workspace.vectors,
        workspace.integers,
    )
    return y, status


def warm_up() -> None:
    """Compiles the kernel (or loads it from numba's cache) for the arrays `solve` and `solve_qp`
    pass: call it in a constructor, so that no control tick compiles it."""
    solve(np.eye(2), -np.ones(2), np.ones((1, 2)), np.ones(1), initial_active=np.zeros(1, dtype=np.int64))


@kernel
def solve_dense_qp_kernel(
    H,
    f,
    C,
    u,
    prox_weight,
    primal_tolerance,
    dual_tolerance,
    stationarity_tolerance,
    max_iterations,
    y,
    multipliers,
    active,
    num_initial_active,
    matrices,
    transposed,
    vectors,
    integers,
):
    """min 0.5 y'Hy + f'y s.t. C y <= u, written into y (n,) and multipliers (m,).

    active (>= n entries, int64): on entry its first `num_initial_active` entries are a warm-start
    active set (invalid or dependent rows are skipped); on return its first q entries are the
    final active set. matrices, transposed, vectors, integers: the arrays of a `make_workspace` of
    at least this size.
    Returns (status, q, iterations). Never raises: an exception in the compiled code (a division
    by zero that a check missed would raise one in numba) is NUMERICAL_FAILURE with y = 0.
    """
    try:
        return _solve(
            H, f, C, u, prox_weight, primal_tolerance, dual_tolerance, stationarity_tolerance, max_iterations, y,
            multipliers, active, num_initial_active, matrices, transposed, vectors, integers,
        )  # fmt: skip
    except Exception:
        for i in range(f.shape[0]):
            y[i] = 0.0
        for i in range(u.shape[0]):
            multipliers[i] = 0.0
        return NUMERICAL_FAILURE, 0, 0


@kernel
def _solve(
    H,
    f,
    C,
    u,
    prox_weight,
    primal_tolerance,
    dual_tolerance,
    stationarity_tolerance,
    max_iterations,
    y,
    multipliers,
    active,
    num_initial_active,
    matrices,
    transposed,
    vectors,
    integers,
):
    """The body of `solve_dense_qp_kernel`."""
    n = f.shape[0]
    m = u.shape[0]
    # Arrays too small would be written past their ends (compiled code checks no bounds).
    if (
        H.shape[0] != n
        or H.shape[1] != n
        or C.shape[0] != m
        or C.shape[1] != n
        or y.shape[0] < n
        or multipliers.shape[0] < m
        or active.shape[0] < n
        or matrices.shape[0] < NUM_MATRICES
        or matrices.shape[1] < n
        or matrices.shape[2] < n
        or transposed.shape[0] < n
        or transposed.shape[1] < m
        or vectors.shape[0] < NUM_VECTORS
        or vectors.shape[1] < max(n, m)
        or integers.shape[0] < NUM_INTEGER_ROWS
        or integers.shape[1] < max(n, m)
    ):
        return NUMERICAL_FAILURE, 0, 0
    eps = prox_weight
    L = matrices[_M_FACTOR]
    Jt = matrices[_M_J]
    R = matrices[_M_R]
    d = vectors[_V_D]
    lam = vectors[_V_LAMBDA]
    row_scale = vectors[_V_ROW_SCALE]
    centre = vectors[_V_CENTRE]
    linear = vectors[_V_LINEAR]
    is_active = integers[_I_IS_ACTIVE]
    for i in range(m):
        multipliers[i] = 0.0
        is_active[i] = 0
    for i in range(n):
        y[i] = 0.0
    Ct = transposed
    if not _check_and_transpose(H, f, C, u, eps, Ct, row_scale):
        return NUMERICAL_FAILURE, 0, 0
    for i in range(m):
        if u[i] == -math.inf:
            return INFEASIBLE, 0, 0
    if n == 0:
        for i in range(m):
            if u[i] < -primal_tolerance:
                return INFEASIBLE, 0, 0
        return OPTIMAL, 0, 0

    # G = H + eps I = L L', and J = L^-T (Q = I while the active set is empty): Jt = L^-1.
    for i in range(n):
        for j in range(n):
            L[i, j] = H[i, j]
        L[i, i] += eps
    if not cholesky_in_place(L, n):
        return NUMERICAL_FAILURE, 0, 0
    _inverse_lower(L, Jt, n)

    # Warm start: the given rows that are valid and independent, in their order.
    q = 0
    for k in range(min(num_initial_active, n)):
        p = active[k]
        if p < 0 or p >= m or is_active[p] == 1 or u[p] >= INFINITE_BOUND:
            continue
        _times_row(Jt, C, p, d, n)
        if _dependent(d, q, n):
            continue
        _add_to_factorisation(Jt, R, d, vectors[_V_W], q, n)
        active[q] = p
        is_active[p] = 1
        q += 1

    for i in range(n):
        centre[i] = 0.0
    iterations = 0
    while True:
        iterations += 1
        if iterations > max_iterations:
            _finish(ITERATION_LIMIT, y, multipliers, active, lam, q, n)
            return ITERATION_LIMIT, q, iterations
        for i in range(n):
            linear[i] = f[i] - eps * centre[i]
        _clear_implied(is_active, m)
        q = _restart_from_active_set(Jt, R, u, linear, active, is_active, lam, q, n, y, vectors, True)
        status, q, iterations = _dual_active_set(
            C, Ct, u, linear, primal_tolerance, max_iterations, iterations, y, active, is_active, lam, q, n, m, Jt, R,
            vectors,
        )  # fmt: skip
        if status != OPTIMAL:
            _finish(status, y, multipliers, active, lam, q, n)
            return status, q, iterations
        # The inner steps moved y by increments; recomputed from the factorisation it meets the
        # active rows to rounding (an ill-conditioned vertex drifts by 1e-10 over 50 steps).
        _restart_from_active_set(Jt, R, u, linear, active, is_active, lam, q, n, y, vectors, False)
        for k in range(q):
            lam[k] = max(lam[k], 0.0)
        outcome = _exact_step(
            H, f, C, Ct, u, eps, primal_tolerance, dual_tolerance, stationarity_tolerance, y, active, q, n, m,
            Jt, R, matrices[_M_REDUCED], integers[_I_PERMUTATION], vectors,
        )  # fmt: skip
        if outcome == _EXACT_OPTIMAL:
            _take_exact_step(y, lam, vectors, q, n)
            _finish(OPTIMAL, y, multipliers, active, lam, q, n)
            return OPTIMAL, q, iterations
        # Proximal step y_k+1 - y_k: its size is the stationarity residual / eps.
        step = vectors[_V_W]
        largest_step = 0.0
        for i in range(n):
            step[i] = y[i] - centre[i]
            largest_step = max(largest_step, abs(step[i]))
        if eps * largest_step <= stationarity_tolerance * _gradient_scale(H, f, C, y, active, lam, q, n, vectors):
            _finish(OPTIMAL, y, multipliers, active, lam, q, n)
            return OPTIMAL, q, iterations
        if _is_recession_direction(H, f, C, u, step, n, m, vectors):
            _finish(UNBOUNDED, y, multipliers, active, lam, q, n)
            return UNBOUNDED, q, iterations
        # Primal active-set steps from the (feasible) proximal iterate, each to the minimiser y* of
        # the objective on the current face: where y* violates a row, as far towards it as the rows
        # allow, and the row that stops the step joins the face; where y* is feasible but a
        # multiplier is negative, to y*, and that row leaves. Where the objective falls without
        # bound on the face, along a direction of zero curvature and descent to the first row in
        # the way, which joins the face. The objective never rises. Where H is far smaller than eps
        # the proximal steps alone would crawl (|gradient| / eps a step). They stop when a step
        # cannot change the face; the proximal iterations then go on from here.
        primal_steps = 0
        while (outcome == _EXACT_FACE_MINIMISER or outcome == _EXACT_RAY) and primal_steps < n + m:
            primal_steps += 1
            iterations += 1
            if iterations > max_iterations:
                _finish(ITERATION_LIMIT, y, multipliers, active, lam, q, n)
                return ITERATION_LIMIT, q, iterations
            if outcome == _EXACT_RAY:
                blocking = _move_along(
                    Ct, u, y, vectors[_V_RAY], vectors[_V_VALUES], vectors[_V_VALUES_EXACT], vectors[_V_ROW_SCALE], n, m
                )
                if blocking < 0:
                    # Nothing stops a descent of zero curvature: unbounded, if the descent is more
                    # than rounding (the test of a proximal step); else the proximal steps decide.
                    if _is_recession_direction(H, f, C, u, vectors[_V_RAY], n, m, vectors):
                        _finish(UNBOUNDED, y, multipliers, active, lam, q, n)
                        return UNBOUNDED, q, iterations
                    break
            else:
                blocking = _move_towards(
                    Ct, u, y, vectors[_V_Y_EXACT], vectors[_V_VALUES_EXACT], vectors[_V_VALUES], n, m, primal_tolerance
                )
            if blocking >= 0:
                _times_row(Jt, C, blocking, d, n)
                if _dependent(d, q, n):
                    break
                _add_to_factorisation(Jt, R, d, vectors[_V_W], q, n)
                active[q] = blocking
                is_active[blocking] = 1
                lam[q] = 0.0
                q += 1
            else:
                leaving = _most_negative_multiplier(vectors[_V_LAMBDA_EXACT], vectors[_V_ROW_SCALE], active, q)
                if leaving < 0:
                    break
                q = _drop_from_factorisation(Jt, R, active, is_active, lam, leaving, q, n)
            outcome = _exact_step(
                H, f, C, Ct, u, eps, primal_tolerance, dual_tolerance, stationarity_tolerance, y, active, q, n, m,
                Jt, R, matrices[_M_REDUCED], integers[_I_PERMUTATION], vectors,
            )  # fmt: skip
            if outcome == _EXACT_OPTIMAL:
                _take_exact_step(y, lam, vectors, q, n)
                _finish(OPTIMAL, y, multipliers, active, lam, q, n)
                return OPTIMAL, q, iterations
        for i in range(n):
            centre[i] = y[i]


@kernel
def _take_exact_step(y, lam, vectors, q, n):
    """y <- y*, lam <- max(lam*, 0) of the exact step."""
    y_exact = vectors[_V_Y_EXACT]
    lam_exact = vectors[_V_LAMBDA_EXACT]
    for i in range(n):
        y[i] = y_exact[i]
    for k in range(q):
        lam[k] = max(lam_exact[k], 0.0)


@kernel
def _descent_ray(Jt, factor, permutation, g2, rank, k, q, n, ray, scratch):
    """ray <- J2 d for d = -(sum over the null vectors n_j of the reduced Hessian of (g2'n_j) n_j):
    zero curvature, slope -sum (g2'n_j)^2. factor: its pivoted Cholesky factor of that rank; the
    null vector of free pivot j is [x; e_j] (pivot order) with L11' x = -L21' e_j. Returns whether
    the slope is negative."""
    direction = scratch  # in pivot order, k entries
    for a in range(k):
        direction[a] = 0.0
    x = ray  # scratch for the null vectors' leading parts until the ray is formed
    slope = 0.0
    for j in range(rank, k):
        for a in range(rank - 1, -1, -1):
            value = -factor[j, a]
            for b in range(a + 1, rank):
                value -= factor[b, a] * x[b]
            x[a] = value / factor[a, a]
        along = g2[permutation[j]]
        for a in range(rank):
            along += g2[permutation[a]] * x[a]
        for a in range(rank):
            direction[a] -= along * x[a]
        direction[j] -= along
        slope -= along * along
    for i in range(n):
        ray[i] = 0.0
    for a in range(k):
        da = direction[a]
        row = q + permutation[a]
        for i in range(n):
            ray[i] += da * Jt[row, i]
    return slope < 0.0


@kernel
def _move_along(Ct, u, x, direction, values, direction_values, row_scale, n, m):
    """x <- x + t direction, t up to the first row that blocks it (x feasible). Returns that row,
    or -1 if none does (rows whose slope is below 1e-9 of |c_i| |direction| count as level)."""
    _constraint_values(Ct, u, x, values, n, m)
    norm = 0.0
    for i in range(n):
        norm += direction[i] * direction[i]
    norm = math.sqrt(norm)
    for i in range(m):
        direction_values[i] = 0.0
    for j in range(n):
        dj = direction[j]
        if dj != 0.0:
            for i in range(m):
                direction_values[i] += dj * Ct[j, i]
    t = math.inf
    blocking = -1
    for i in range(m):
        if u[i] < INFINITE_BOUND and direction_values[i] * row_scale[i] > _RECESSION_TOLERANCE * norm:
            ratio = max(-values[i], 0.0) / direction_values[i]
            if ratio < t:
                t = ratio
                blocking = i
    if blocking >= 0:
        for i in range(n):
            x[i] += t * direction[i]
    return blocking


@kernel
def _most_negative_multiplier(lam, row_scale, active, q):
    """Position in the active set of the most negative multiplier (times its row's norm), or -1."""
    leaving = -1
    smallest = 0.0
    for k in range(q):
        value = lam[k] / row_scale[active[k]]
        if value < smallest:
            smallest = value
            leaving = k
    return leaving


@kernel
def _times_row(A, B, b, out, n):
    """out <- A B[b]' for the leading n x n block of A (row b of B as a vector)."""
    for i in range(n):
        value = 0.0
        for j in range(n):
            value += A[i, j] * B[b, j]
        out[i] = value


@kernel
def _symmetric_times(H, x, out, n):
    """out <- H x for symmetric H, as a sum of H's rows (contiguous) scaled by x."""
    for i in range(n):
        out[i] = 0.0
    for j in range(n):
        xj = x[j]
        if xj != 0.0:
            for i in range(n):
                out[i] += xj * H[j, i]


@kernel
def _check_and_transpose(H, f, C, u, eps, Ct, row_scale):
    """Whether H, f, C are finite, u has no NaN, and eps is finite and >= 0; in the same pass
    over C, Ct <- C' and row_scale <- 1 / ||c_i|| (1 for a zero row)."""
    if not (eps >= 0.0 and eps < math.inf):
        return False
    # x * 0 is 0 for finite x and NaN otherwise: one sum tests every entry without a branch each.
    check = 0.0
    n = f.shape[0]
    for i in range(n):
        check += f[i] * 0.0
        for j in range(n):
            check += H[i, j] * 0.0
    for i in range(u.shape[0]):
        if math.isnan(u[i]):
            return False
        norm = 0.0
        for j in range(n):
            value = C[i, j]
            Ct[j, i] = value
            norm += value * value
        check += norm * 0.0
        row_scale[i] = 1.0 / math.sqrt(norm) if norm > 0.0 else 1.0
    return check == 0.0


@kernel
def _constraint_values(Ct, u, x, values, n, m):
    """values <- C x - u, as a sum of the columns of C (rows of Ct: contiguous, vectorised)."""
    for i in range(m):
        values[i] = -u[i]
    for j in range(n):
        xj = x[j]
        if xj != 0.0:
            for i in range(m):
                values[i] += xj * Ct[j, i]


@kernel
def _finish(status, y, multipliers, active, lam, q, n):
    """Scatters the active multipliers into `multipliers`; zeroes y if it is not finite."""
    for k in range(q):
        multipliers[active[k]] = lam[k]
    finite = True
    for i in range(n):
        if not math.isfinite(y[i]):
            finite = False
    if not finite or status == NUMERICAL_FAILURE:
        for i in range(n):
            y[i] = 0.0
        for i in range(multipliers.shape[0]):
            multipliers[i] = 0.0


@kernel
def _inverse_lower(L, X, n):
    """X <- L^-1 for lower-triangular L by forward substitution on whole rows (L X = I:
    X[i] = (e_i - sum over k < i of L[i, k] X[k]) / L[i, i], contiguous row sums)."""
    for i in range(n):
        for j in range(n):
            X[i, j] = 0.0
        X[i, i] = 1.0
        for k in range(i):
            factor = L[i, k]
            for j in range(k + 1):
                X[i, j] -= factor * X[k, j]
        inverse = 1.0 / L[i, i]
        for j in range(i + 1):
            X[i, j] *= inverse


@kernel
def _dependent(d, q, n):
    """Whether the row with d = J'c is (numerically) in the span of the q active rows."""
    total = 0.0
    outside = 0.0
    for j in range(n):
        total += d[j] * d[j]
        if j >= q:
            outside += d[j] * d[j]
    return outside <= _DEPENDENCY_TOLERANCE * _DEPENDENCY_TOLERANCE * total


@kernel
def _add_to_factorisation(Jt, R, d, w, q, n):
    """Appends the row with d = J'c to the factorisation: a Householder reflection P maps d[q:]
    to (alpha, 0, ..., 0) and turns J2 with it (J2 <- J2 P, so Jt's rows q.. <- P Jt's rows q..,
    two passes of row sums); R gains the column d[:q+1]. w: scratch (n)."""
    tail = 0.0
    for j in range(q + 1, n):
        tail += d[j] * d[j]
    if tail > 0.0:
        head = d[q]
        sigma = math.sqrt(head * head + tail)
        # alpha of the sign opposite to d[q]: v = d[q:] - alpha e_1 without cancellation.
        alpha = -sigma if head >= 0.0 else sigma
        d[q] = head - alpha  # d[q:] now holds v
        scale = 2.0 / (d[q] * d[q] + tail)
        for i in range(n):
            w[i] = 0.0
        for j in range(q, n):
            vj = d[j]
            for i in range(n):
                w[i] += vj * Jt[j, i]
        for j in range(q, n):
            vj = scale * d[j]
            for i in range(n):
                Jt[j, i] -= vj * w[i]
        d[q] = alpha
        for j in range(q + 1, n):
            d[j] = 0.0
    for i in range(q + 1):
        R[i, q] = d[i]
    for i in range(q + 1, n):
        R[i, q] = 0.0


@kernel
def _drop_from_factorisation(Jt, R, active, is_active, lam, k, q, n):
    """Removes active row number k (of q): R loses column k, rotations restore its triangle.
    Returns q - 1."""
    is_active[active[k]] = 0
    for c in range(k, q - 1):
        active[c] = active[c + 1]
        lam[c] = lam[c + 1]
        for i in range(c + 2):
            R[i, c] = R[i, c + 1]
    for c in range(k, q - 1):
        # Column c has one entry below the diagonal, R[c + 1, c]: rotate rows c, c + 1.
        a = R[c, c]
        b = R[c + 1, c]
        if b == 0.0:
            continue
        h = math.hypot(a, b)
        cos = a / h
        sin = b / h
        for j in range(c, q - 1):
            t1 = R[c, j]
            t2 = R[c + 1, j]
            R[c, j] = cos * t1 + sin * t2
            R[c + 1, j] = -sin * t1 + cos * t2
        R[c + 1, c] = 0.0
        for i in range(n):
            t1 = Jt[c, i]
            t2 = Jt[c + 1, i]
            Jt[c, i] = cos * t1 + sin * t2
            Jt[c + 1, i] = -sin * t1 + cos * t2
    for i in range(q):
        R[i, q - 1] = 0.0
    return q - 1


@kernel
def _solve_upper(R, b, x, q):
    """x <- R^-1 b for the leading q x q upper triangle of R."""
    for i in range(q - 1, -1, -1):
        value = b[i]
        for j in range(i + 1, q):
            value -= R[i, j] * x[j]
        x[i] = value / R[i, i]


@kernel
def _restart_from_active_set(Jt, R, u, linear, active, is_active, lam, q, n, y, vectors, drop_negative):
    """(y, lam) of min 0.5 y'G y + linear'y with the q active rows as equalities; with
    `drop_negative`, rows with a negative multiplier leave, most negative first, until all are
    >= 0. Returns the new q.

    With w = L'y = Q [w1; w2]: C_A y = u_A gives R'w1 = u_A, and stationarity projected on Q2 and
    Q1 gives w2 = -J2'linear and lam = -R^-1 (w1 + J1'linear); y = J1 w1 + J2 w2.
    """
    w = vectors[_V_W]
    rhs = vectors[_V_D]
    while True:
        # R' w1 = u_A by forward substitution.
        for i in range(q):
            value = u[active[i]]
            for j in range(i):
                value -= R[j, i] * w[j]
            w[i] = value / R[i, i]
        for j in range(n):
            value = 0.0
            for i in range(n):
                value += Jt[j, i] * linear[i]
            if j >= q:
                w[j] = -value
            else:
                rhs[j] = -(w[j] + value)
        _solve_upper(R, rhs, lam, q)
        if not drop_negative:
            break
        most_negative = -1
        smallest = 0.0
        for k in range(q):
            if lam[k] < smallest:
                smallest = lam[k]
                most_negative = k
        if most_negative < 0:
            break
        q = _drop_from_factorisation(Jt, R, active, is_active, lam, most_negative, q, n)
    # y = J w = sum of the rows of Jt scaled by w.
    for i in range(n):
        y[i] = 0.0
    for j in range(n):
        wj = w[j]
        for i in range(n):
            y[i] += wj * Jt[j, i]
    return q


@kernel
def _dual_active_set(
    C, Ct, u, linear, primal_tolerance, max_iterations, iterations, y, active, is_active, lam, q, n, m, Jt, R,
    vectors,
):  # fmt: skip
    """Goldfarb-Idnani from a dual-feasible (y, active set, lam) of the subproblem with linear
    term `linear`: adds the most violated row (violation over row norm) until every row is met
    within primal_tolerance. Returns (status, q, iterations)."""
    d = vectors[_V_D]
    z = vectors[_V_Z]
    r = vectors[_V_R]
    row_scale = vectors[_V_ROW_SCALE]
    values = vectors[_V_VALUES]
    while True:
        p = -1
        worst = 0.0
        _constraint_values(Ct, u, y, values, n, m)
        for i in range(m):
            if is_active[i] != 0 or u[i] >= INFINITE_BOUND:
                continue
            violation = values[i]
            if violation > primal_tolerance and violation * row_scale[i] > worst:
                worst = violation * row_scale[i]
                p = i
        if p < 0:
            return OPTIMAL, q, iterations
        lam_p = 0.0
        while True:
            iterations += 1
            if iterations > max_iterations:
                return ITERATION_LIMIT, q, iterations
            _times_row(Jt, C, p, d, n)
            dependent = _dependent(d, q, n)
            _solve_upper(R, d, r, q)
            # r_j ||c_j|| is row j's share of c_p in the combination c_p = C_A'r (+ the part
            # outside): the zero test compares those shares, so that row scaling cannot hide one.
            largest_r = 0.0
            for k in range(q):
                largest_r = max(largest_r, abs(r[k]) / row_scale[active[k]])
            t_partial = math.inf
            leaving = -1
            for k in range(q):
                if r[k] / row_scale[active[k]] > _ZERO_TOLERANCE * largest_r:
                    ratio = lam[k] / r[k]
                    if ratio < t_partial:
                        t_partial = ratio
                        leaving = k
            t_full = math.inf
            if not dependent:
                # z = -J2 d2: minus the rows q.. of Jt scaled by d; the violation falls by
                # t ||d2||^2 along it.
                for i in range(n):
                    z[i] = 0.0
                for j in range(q, n):
                    dj = d[j]
                    for i in range(n):
                        z[i] -= dj * Jt[j, i]
                violation = -u[p]
                for j in range(n):
                    violation += C[p, j] * y[j]
                norm2 = 0.0
                for j in range(q, n):
                    norm2 += d[j] * d[j]
                t_full = max(violation, 0.0) / norm2
            if t_partial == math.inf and t_full == math.inf:
                # c_p = C_A'r with every r_j <= 0: on the face c_p'y = r'u_A, and since
                # C_A y <= u_A gives c_p'y >= r'u_A everywhere, row p is infeasible with the rows
                # of A by r'u_A - u_p. Where that is within the tolerance, p's violation is the
                # rounding of y at a degenerate vertex (rows of very different norms through one
                # point): p is implied by A, and is left out until A changes.
                margin = -u[p]
                for k in range(q):
                    margin += r[k] * u[active[k]]
                if margin > primal_tolerance:
                    return INFEASIBLE, q, iterations
                is_active[p] = _IMPLIED
                # Partial steps moved multiplier onto p; from A alone (y, lam) are recomputed.
                before = q
                q = _restart_from_active_set(Jt, R, u, linear, active, is_active, lam, q, n, y, vectors, True)
                if q != before:
                    _clear_implied(is_active, m)
                break
            t = min(t_partial, t_full)
            if not dependent:
                for i in range(n):
                    y[i] += t * z[i]
            for k in range(q):
                lam[k] -= t * r[k]
            lam_p += t
            if t_full <= t_partial:
                _add_to_factorisation(Jt, R, d, vectors[_V_W], q, n)
                active[q] = p
                lam[q] = lam_p
                is_active[p] = 1
                q += 1
                _clear_implied(is_active, m)
                break
            lam[leaving] = 0.0
            q = _drop_from_factorisation(Jt, R, active, is_active, lam, leaving, q, n)
            _clear_implied(is_active, m)


@kernel
def _clear_implied(is_active, m):
    """Rows left out as implied by the active set are candidates again (the set changed)."""
    for i in range(m):
        if is_active[i] == _IMPLIED:
            is_active[i] = 0


@kernel
def _gradient_scale(H, f, C, y, active, lam, q, n, vectors):
    """max(1, |f|_inf, |H y|_inf, |C_A'lam|_inf): the scale of the stationarity residual."""
    hy = vectors[_V_GRADIENT]
    ca = vectors[_V_Z]
    _symmetric_times(H, y, hy, n)
    _active_rows_times(C, active, lam, q, ca, n)
    scale = 1.0
    for i in range(n):
        scale = max(scale, abs(f[i]), abs(hy[i]), abs(ca[i]))
    return scale


@kernel
def _active_rows_times(C, active, lam, q, out, n):
    """out <- C_A' lam: the active rows scaled by their multipliers."""
    for i in range(n):
        out[i] = 0.0
    for k in range(q):
        lk = lam[k]
        row = active[k]
        for i in range(n):
            out[i] += lk * C[row, i]


@kernel
def _move_towards(Ct, u, x, target, target_values, values, n, m, primal_tolerance):
    """x <- x + alpha (target - x), with the largest alpha in [0, 1] that keeps every row met
    (x feasible; target_values = C target - u; values: scratch). Returns the row that limits
    alpha below 1, or -1."""
    _constraint_values(Ct, u, x, values, n, m)
    alpha = 1.0
    blocking = -1
    for i in range(m):
        if u[i] < INFINITE_BOUND and target_values[i] > primal_tolerance and target_values[i] > values[i]:
            # The row is met at x and not at the target: it blocks where c'x reaches u.
            ratio = max(-values[i], 0.0) / (target_values[i] - values[i])
            if ratio < alpha:
                alpha = ratio
                blocking = i
    if alpha > 0.0:
        for i in range(n):
            x[i] += alpha * (target[i] - x[i])
    return blocking


@kernel
def _exact_step(
    H, f, C, Ct, u, eps, primal_tolerance, dual_tolerance, stationarity_tolerance, y, active, q, n, m,
    Jt, R, reduced, permutation, vectors,
):  # fmt: skip
    """The minimiser y* of the original QP on the face C_A y = u_A, from y (see the module
    docstring), into vectors[_V_Y_EXACT] with its multipliers, and C y* - u into
    vectors[_V_VALUES_EXACT]. Returns _EXACT_OPTIMAL if y* meets the KKT conditions of the
    original problem to the tolerances, _EXACT_FACE_MINIMISER if it only minimises the objective on
    the face (some multiplier negative or some row violated), _EXACT_RAY if the objective falls
    without bound on the face (a direction of zero curvature and descent is then in
    vectors[_V_RAY]), else _EXACT_NOT_STATIONARY."""
    y_exact = vectors[_V_Y_EXACT]
    lam_exact = vectors[_V_LAMBDA_EXACT]
    gradient = vectors[_V_GRADIENT]
    g2 = vectors[_V_Z]
    w = vectors[_V_W]
    rhs = vectors[_V_D]
    row_scale = vectors[_V_ROW_SCALE]
    k = n - q
    rank = 0
    _symmetric_times(H, y, gradient, n)
    for i in range(n):
        gradient[i] += f[i]
        y_exact[i] = y[i]
    if k > 0:
        # Reduced Hessian I - eps J2'J2 and gradient J2'(H y + f).
        for a in range(k):
            value = 0.0
            for i in range(n):
                value += Jt[q + a, i] * gradient[i]
            g2[a] = value
            for b in range(a, k):
                value = 0.0
                for i in range(n):
                    value += Jt[q + a, i] * Jt[q + b, i]
                entry = -eps * value
                if a == b:
                    entry += 1.0
                reduced[a, b] = entry
                reduced[b, a] = entry
        rank = _pivoted_cholesky_in_place(reduced, permutation, k)
        # Basic solution: zero in the unpivoted (zero-curvature) directions.
        for a in range(rank):
            value = -g2[permutation[a]]
            for b in range(a):
                value -= reduced[a, b] * w[b]
            w[a] = value / reduced[a, a]
        for a in range(rank - 1, -1, -1):
            value = w[a]
            for b in range(a + 1, rank):
                value -= reduced[b, a] * w[b]
            w[a] = value / reduced[a, a]
        for a in range(rank):
            wa = w[a]
            row = q + permutation[a]
            for i in range(n):
                y_exact[i] += wa * Jt[row, i]
        _symmetric_times(H, y_exact, gradient, n)
        for i in range(n):
            gradient[i] += f[i]
    # lam* = -R^-1 J1'(H y* + f).
    for a in range(q):
        value = 0.0
        for i in range(n):
            value += Jt[a, i] * gradient[i]
        rhs[a] = -value
    _solve_upper(R, rhs, lam_exact, q)
    # Stationarity: H y* + f + C_A'lam* = 0 within tolerance of the gradient's scale.
    ca = vectors[_V_R]
    _active_rows_times(C, active, lam_exact, q, ca, n)
    scale = 1.0
    residual = 0.0
    for i in range(n):
        scale = max(scale, abs(f[i]), abs(gradient[i] - f[i]), abs(ca[i]))
        residual = max(residual, abs(gradient[i] + ca[i]))
    if not residual <= stationarity_tolerance * scale:
        if rank < k and _descent_ray(Jt, reduced, permutation, g2, rank, k, q, n, vectors[_V_RAY], w):
            return _EXACT_RAY
        return _EXACT_NOT_STATIONARY
    values = vectors[_V_VALUES_EXACT]
    _constraint_values(Ct, u, y_exact, values, n, m)
    # Dual feasibility in the same units: lam_j ||c_j|| is row j's share of the gradient.
    for a in range(q):
        if lam_exact[a] < -dual_tolerance * scale * row_scale[active[a]]:
            return _EXACT_FACE_MINIMISER
    for i in range(m):
        if u[i] < INFINITE_BOUND and not values[i] <= primal_tolerance:
            return _EXACT_FACE_MINIMISER
    return _EXACT_OPTIMAL


@kernel
def _pivoted_cholesky_in_place(A, permutation, k):
    """Semi-definite A (k x k, full symmetric) <- P'A P = L L' with diagonal pivoting, stopping at
    pivots below _RANK_TOLERANCE (relative to 1, the scale of the reduced Hessian). L is left in
    the lower triangle of the leading rank x rank block; permutation[a] is the original index of
    pivot a. Returns the rank."""
    for a in range(k):
        permutation[a] = a
    for j in range(k):
        best = j
        for i in range(j + 1, k):
            if A[i, i] > A[best, best]:
                best = i
        if not A[best, best] > _RANK_TOLERANCE:
            return j
        if best != j:
            for i in range(k):
                t = A[i, j]
                A[i, j] = A[i, best]
                A[i, best] = t
            for i in range(k):
                t = A[j, i]
                A[j, i] = A[best, i]
                A[best, i] = t
            t = permutation[j]
            permutation[j] = permutation[best]
            permutation[best] = t
        diagonal = math.sqrt(A[j, j])
        A[j, j] = diagonal
        for i in range(j + 1, k):
            A[i, j] /= diagonal
        # Trailing block (symmetric, kept whole for the pivot search and swaps), row by row.
        for a in range(j + 1, k):
            factor = A[a, j]
            for b in range(j + 1, k):
                A[a, b] -= factor * A[b, j]
    return k


@kernel
def _is_recession_direction(H, f, C, u, step, n, m, vectors):
    """Whether step is a direction of unbounded descent: H step = 0, C step <= 0, f'step < 0
    (each relative to the sizes involved)."""
    norm = 0.0
    f_norm = 0.0
    for i in range(n):
        norm = max(norm, abs(step[i]))
        f_norm = max(f_norm, abs(f[i]))
    descent = 0.0
    for i in range(n):
        descent += f[i] * step[i]
    if norm == 0.0 or not descent < -_RECESSION_TOLERANCE * f_norm * norm:
        return False
    h_norm = 0.0
    for i in range(n):
        for j in range(n):
            h_norm = max(h_norm, abs(H[i, j]))
    curvature = vectors[_V_GRADIENT]
    _symmetric_times(H, step, curvature, n)
    for i in range(n):
        if abs(curvature[i]) > _RECESSION_TOLERANCE * h_norm * norm:
            return False
    for i in range(m):
        if u[i] >= INFINITE_BOUND:
            continue
        c_norm = 0.0
        for j in range(n):
            c_norm = max(c_norm, abs(C[i, j]))
        value = 0.0
        for j in range(n):
            value += C[i, j] * step[j]
        if value > _RECESSION_TOLERANCE * c_norm * norm:
            return False
    return True
