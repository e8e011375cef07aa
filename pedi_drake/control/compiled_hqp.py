"""Hierarchical quadratic programme: strictly prioritised levels, or one weighted QP, as compiled
kernels over a table of rows.

Each level holds equality tasks (A x = b, minimised in least squares) and inequality tasks
(G x <= h), each inequality either *hard* (a constraint from its level down) or *soft* (its
violation w >= G x - h is minimised in least squares at its level). Level k is solved within the
optimal set of levels 0..k-1 (the sequential scheme of Kanoun et al. 2011 / Escande et al. 2014):

* For least squares over a convex set the optimal value of (A_k x, w_k) is unique, so the optimal
  set of level k is {x feasible : A_k x = A_k x_k*, G_k,soft x <= h_k,soft + w_k*}.
* Equalities are fixed by restricting x to the affine set x = x_k* + Z_k z, where Z_k is an
  orthonormal basis of the null space of the stacked fixed equalities (a QR of their transpose,
  or an SVD when the rows come near rank deficiency, both by LAPACK: redundant rows cost nothing
  and never make a QP degenerate).
* Inequalities (hard ones and fixed soft ones) are carried down as constraints on z.
* A level without inequalities, or whose least-squares step already meets them, is plain least
  squares; any other goes to DAQP (`daqp_kernel`) as a dense QP in (z, w), its Hessian
  semi-definite, solved exactly by DAQP's proximal iterations (`HqpSettings.proximal_weight`).

The weighted mode (`solve_weighted`) instead solves one QP in which level k's equalities and soft
rows weigh `level_weights[k]` and every hard row stays hard.

The controller's tick writes every level's rows into a `RowTable` of flat arrays and calls
`solve_strict` or `solve_weighted`. The products of the rows with the null-space basis Z skip the
rows' zero entries (most rows of the stack touch one to a dozen of its 30 variables), and no
product is formed while Z is still the identity (the top level). tests/reference_hqp.py is the
same algorithm in numpy on Python lists of tasks, the oracle of tests/test_compiled_hqp.py, with
brute force over random small cases as its own.

A RowTable holds, for levels 0..L-1 in priority order (rows of a level contiguous, levels in
order; `*_start[k]:*_start[k+1]` are level k's rows):

    eq_A (mE, n), eq_b (mE,), eq_start (L+1,)      equalities, each row scaled by sqrt(weight)
    hard_G (mH, n), hard_h (mH,), hard_start (L+1,)  hard inequalities G x <= h
    soft_G (mS, n), soft_h (mS,), soft_w (mS,), soft_start (L+1,)
                                                   soft inequalities and their weights [-]

Every kernel returns a status: STATUS_OK, or STATUS_INFEASIBLE when a level's QP has no
solution, or STATUS_NUMERICAL when a factorisation failed. x and the residuals are only
meaningful with STATUS_OK.
"""

import dataclasses
import math

import numpy as np

from pedi_drake.numerics import daqp_kernel
from pedi_drake.numerics.lapack_kernel import qr_of_transpose
from pedi_drake.runtime.jit import kernel

STATUS_OK, STATUS_INFEASIBLE, STATUS_NUMERICAL = 0, 1, 2
# The tall least-squares step is accepted only when its Cholesky factor's diagonal spreads less
# than sqrt(rank_tolerance) (reference_hqp._least_squares_step).


@dataclasses.dataclass
class HqpSettings:
    """Numerical settings of the hierarchical QP."""

    # DAQP's proximal-point weight for the (semi-definite) level Hessians [-].
    proximal_weight: float = 1e-5
    # Tikhonov term added to the weighted mode's Hessian (0: none) [-].
    regularization: float = 0.0
    # Relative singular-value tolerance that decides the rank of fixed equality rows [-].
    rank_tolerance: float = 1e-9
    # Slack allowed on a fixed soft inequality beyond its optimum, absorbs solver tolerance [-].
    fix_tolerance: float = 1e-7


@dataclasses.dataclass
class RowTable:
    """Every level's rows as flat arrays (see the module docstring)."""

    n: int
    eq_A: np.ndarray
    eq_b: np.ndarray
    eq_start: np.ndarray
    hard_G: np.ndarray
    hard_h: np.ndarray
    hard_start: np.ndarray
    soft_G: np.ndarray
    soft_h: np.ndarray
    soft_w: np.ndarray
    soft_start: np.ndarray

    @property
    def num_levels(self) -> int:
        return len(self.eq_start) - 1

    def arrays(self) -> tuple:
        """The table's arrays in the order `solve_strict` and `solve_weighted` take them."""
        return tuple(getattr(self, field.name) for field in dataclasses.fields(self)[1:])


# ------------------------------------------------------------------------------------------------
# Row space and null space of a level's rows (reference_hqp._row_space_split).


# How a level's rows were split: full row rank by a QR of their transpose (A = R^T Q1^T),
# rank-deficient by the QR with column pivoting (A^T P = Q R, the rank in R's diagonal), or by an
# SVD (more rows than columns).
SPLIT_FULL_RANK, SPLIT_PIVOTED, SPLIT_SVD = 0, 1, 2


@kernel
def _row_space_split(A: np.ndarray, tolerance: float):
    """(rank r, kind, Y (n, r), N (n, n - r), R, order, U, sigma) of A (m, n): orthonormal bases of
    its row space Y and null space N, by LAPACK (`lapack_kernel`, numba's np.linalg).

    A QR of A^T first; full rank is taken only when the triangular factor's diagonal stays the
    square root of the tolerance away from rank deficiency: a QR's diagonal bounds the smallest
    singular value only from above (a stance's redundant contact rows can leave 1e-8 there over a
    singular value of 1e-17). Anything closer goes to the QR with column pivoting, whose diagonal
    reveals the rank (entries above tolerance * max(1, the largest)), as an SVD would (the oracle
    takes an SVD there: the two agree on the rank when A's singular values are clearly above or
    below the tolerance, as the stack's are). More rows than columns: an SVD. R (m, m) and order
    (m,) are the QR's triangular factor and row order; U and sigma the SVD's (else empty)."""
    m, n = A.shape
    empty = np.zeros((0, 0))
    no_order = np.zeros(0, dtype=np.int64)
    if m == 0:
        return 0, SPLIT_FULL_RANK, np.zeros((n, 0)), np.eye(n), empty, no_order, empty, np.zeros(0)
    if m <= n:
        rows = np.ascontiguousarray(A)
        ok, Q, R, order = qr_of_transpose(rows, False)
        largest, smallest = 0.0, np.inf
        for i in range(m):
            d = abs(R[i, i])
            largest = max(largest, d)
            smallest = min(smallest, d)
        if ok and smallest > math.sqrt(tolerance) * max(1.0, largest):
            Y, N = np.ascontiguousarray(Q[:, :m]), np.ascontiguousarray(Q[:, m:])
            return m, SPLIT_FULL_RANK, Y, N, R, order, empty, np.zeros(0)
        ok, Q, R, order = qr_of_transpose(rows, True)
        if ok:
            top = abs(R[0, 0])
            rank = 0
            while rank < m and abs(R[rank, rank]) > tolerance * max(1.0, top):
                rank += 1
            Y, N = np.ascontiguousarray(Q[:, :rank]), np.ascontiguousarray(Q[:, rank:])
            return rank, SPLIT_PIVOTED, Y, N, R, order, empty, np.zeros(0)
    U, sigma, Vt = np.linalg.svd(A)
    top = sigma[0] if len(sigma) else 0.0
    rank = 0
    for value in sigma:
        if value > tolerance * max(1.0, top):
            rank += 1
    Y = np.ascontiguousarray(Vt[:rank].T)
    N = np.ascontiguousarray(Vt[rank:].T)
    return rank, SPLIT_SVD, Y, N, empty, no_order, U, sigma


@kernel
def _min_norm_least_squares(r, rank, kind, Y, R, order, U, sigma, z) -> None:
    """argmin ||z|| among the minimisers of ||A z - r|| (reference_hqp._min_norm_least_squares),
    from the `_row_space_split` of A."""
    if rank == 0:
        # Every row lies (within the rank tolerance) in the span of the levels above: any z gives
        # the same residual, and the least norm is z = 0 (a least-squares solve would instead
        # invert the rows' rounding noise).
        z[:] = 0.0
        return
    if kind == SPLIT_FULL_RANK:
        # A = R^T Y^T: R^T w = r by forward substitution, z = Y w.
        w = np.empty(rank)
        for i in range(rank):
            value = r[i]
            for k in range(i):
                value -= R[k, i] * w[k]
            w[i] = value / R[i, i]
        z[:] = np.dot(Y, w)
        return
    if kind == SPLIT_PIVOTED:
        # A = P [R1^T 0] Q^T with R1 = R[:rank] (rank, m) in pivoted row order, so the minimiser
        # of least norm is z = Y w, w the least-squares solution of R1^T w = P^T r: by its normal
        # equations R1 R1^T w = R1 P^T r (R1's leading block is well conditioned).
        R1 = np.ascontiguousarray(R[:rank])
        permuted = np.empty(R.shape[0])
        for k in range(R.shape[0]):
            permuted[k] = r[order[k]]
        w = np.linalg.solve(np.dot(R1, R1.T), np.dot(R1, permuted))
        z[:] = np.dot(Y, w)
        return
    # A = U diag(sigma) V^T: z = V_r diag(1 / sigma_r) U_r^T r.
    w = np.dot(np.ascontiguousarray(U[:, :rank].T), r) / sigma[:rank]
    z[:] = np.dot(Y, w)


@kernel
def _normal_equations_step(A: np.ndarray, r: np.ndarray, tolerance: float, z: np.ndarray) -> bool:
    """argmin ||A z - r|| for A with more rows than columns, by its normal equations (a Cholesky
    factor, LAPACK's dpotrf), into z; accepted only when the factor's diagonal spreads less than
    sqrt(tolerance) (reference_hqp._least_squares_step), else False."""
    S = np.dot(A.T, A)
    try:
        L = np.linalg.cholesky(S)
    except Exception:  # numba raises LinAlgError when S is not positive definite
        return False
    largest, smallest = 0.0, np.inf
    for i in range(L.shape[0]):
        largest = max(largest, abs(L[i, i]))
        smallest = min(smallest, abs(L[i, i]))
    if not smallest > math.sqrt(tolerance) * largest:
        return False
    y = np.linalg.solve(L, np.dot(A.T, r))
    z[:] = np.linalg.solve(L.T, y)
    return True


@kernel
def _meets(G: np.ndarray, upper: np.ndarray, z: np.ndarray, tolerance: float) -> bool:
    """Whether G z <= upper + tolerance on every row."""
    for i in range(G.shape[0]):
        s = 0.0
        for j in range(G.shape[1]):
            s += G[i, j] * z[j]
        if s - upper[i] > tolerance:
            return False
    return True


@kernel
def _solve_level_qp(H, f, C, upper, eps_prox, eta_prox, y) -> int:
    """min 0.5 y'Hy + f'y s.t. C y <= upper into y by DAQP, as reference_hqp._solve_level_qp; a status."""
    n, m = f.shape[0], upper.shape[0]
    if m == 0:
        y[:] = np.linalg.lstsq(H, -f, rcond=np.finfo(np.float64).eps * n)[0]
        return STATUS_OK
    lower = np.full(m, -daqp_kernel.INFINITE_BOUND)
    exit_flag = daqp_kernel.solve_qp(
        H, f, C, upper, lower, np.zeros(m, np.int32), eps_prox, eta_prox, 0.0, y, np.empty(m)
    )
    if not daqp_kernel.solved(exit_flag):
        return STATUS_INFEASIBLE
    for v in y:
        if not math.isfinite(v):
            return STATUS_INFEASIBLE
    return STATUS_OK


@kernel
def _rows_times(M: np.ndarray, Z: np.ndarray, nz: int, identity: bool, out: np.ndarray) -> None:
    """out[i, :nz] = M[i] @ Z[:, :nz] for every row i of M (m, n); Z is the identity when
    `identity`. M's zero entries are skipped, which BLAS cannot know: the stack's rows are sparse
    (a joint limit touches one variable, a force limit two, a torque limit about a dozen of 30)."""
    m, n = M.shape
    if identity:
        for i in range(m):
            for c in range(n):
                out[i, c] = M[i, c]
        return
    for i in range(m):
        for c in range(nz):
            out[i, c] = 0.0
        for p in range(n):
            a = M[i, p]
            if a != 0.0:
                for c in range(nz):
                    out[i, c] += a * Z[p, c]


@kernel
def _row_dot(M: np.ndarray, i: int, x: np.ndarray) -> float:
    """M[i] @ x, skipping M's zero entries."""
    s = 0.0
    for j in range(x.shape[0]):
        v = M[i, j]
        if v != 0.0:
            s += v * x[j]
    return s


@kernel
def solve_strict(n, rows, rank_tolerance, fix_tolerance, eps_prox, x, residuals) -> int:
    """Solves the levels in strict priority order (reference_hqp.solve_hqp) into x (n,) and the levels'
    equality residuals (L,); returns a status. `rows`: a RowTable's arrays (`RowTable.arrays`)."""
    eq_A, eq_b, eq_start, hard_G, hard_h, hard_start, soft_G, soft_h, soft_w, soft_start = rows
    num_levels = len(eq_start) - 1
    for i in range(n):
        x[i] = 0.0
    # Z (n, nz): the null space of every level solved so far, in the leading nz columns of a
    # buffer; the identity until a level with equalities constrains x (no product with it then).
    Z = np.empty((n, n))
    Z_next = np.empty((n, n))
    identity = True
    nz = n
    capacity = hard_G.shape[0] + soft_G.shape[0]
    G_all = np.empty((capacity, n))
    h_all = np.empty(capacity)
    mh = 0
    num_verified = 0
    # G_all Z for the first `gz_rows` carried rows, kept from level to level while Z stays.
    GZ_all = np.empty((capacity, n))
    gz_rows = 0
    for level in range(num_levels):
        e0, e1 = eq_start[level], eq_start[level + 1]
        s0, s1 = soft_start[level], soft_start[level + 1]
        h0, h1 = hard_start[level], hard_start[level + 1]
        m = e1 - e0
        ms = s1 - s0
        for i in range(h0, h1):
            G_all[mh] = hard_G[i]
            h_all[mh] = hard_h[i]
            mh += 1
        if nz == 0 and ms == 0:
            continue
        if m == 0 and ms == 0 and level + 1 < num_levels:
            continue
        A = eq_A[e0:e1]
        Az = np.empty((m, nz))
        _rows_times(A, Z, nz, identity, Az)
        rz = np.empty(m)
        for i in range(m):
            rz[i] = eq_b[e0 + i] - _row_dot(eq_A, e0 + i, x)
        have_split = False
        rank = 0
        N = np.zeros((0, 0))
        z = np.zeros(nz)
        if mh == 0 and ms == 0:
            if m:
                rank, kind, Y, N, R, order, U, sigma = _row_space_split(Az, rank_tolerance)
                have_split = True
                _min_norm_least_squares(rz, rank, kind, Y, R, order, U, sigma, z)
            solved = True
        else:
            if gz_rows < mh:
                _rows_times(G_all[gz_rows:mh], Z, nz, identity, GZ_all[gz_rows:mh])
                gz_rows = mh
            GZ = GZ_all[:mh, :nz]
            upper = np.empty(mh + ms)
            for i in range(mh):
                upper[i] = h_all[i] - _row_dot(G_all, i, x)
            for i in range(num_verified):
                upper[i] = max(upper[i], 0.0)
            Gs = soft_G[s0:s1]
            GsZ = np.empty((ms, nz))
            _rows_times(Gs, Z, nz, identity, GsZ)
            for i in range(ms):
                upper[mh + i] = soft_h[s0 + i] - _row_dot(soft_G, s0 + i, x)
            solved = True
            if m and nz:
                if m <= nz:
                    rank, kind, Y, N, R, order, U, sigma = _row_space_split(Az, rank_tolerance)
                    have_split = True
                    _min_norm_least_squares(rz, rank, kind, Y, R, order, U, sigma, z)
                else:
                    solved = _normal_equations_step(Az, rz, rank_tolerance, z)
            if solved:
                solved = _meets(GZ, upper[:mh], z, 0.0) and (ms == 0 or _meets(GsZ, upper[mh:], z, 0.0))
            if not solved:
                size = nz + ms
                H = np.zeros((size, size))
                H[:nz, :nz] = Az.T @ Az
                f = np.zeros(size)
                f[:nz] = -(Az.T @ rz)
                C = np.zeros((mh + ms, size))
                C[:mh, :nz] = GZ
                for i in range(ms):
                    ws = math.sqrt(soft_w[s0 + i])
                    H[nz + i, nz + i] = ws * ws
                    C[mh + i, :nz] = GsZ[i]
                    C[mh + i, nz + i] = -1.0
                y = np.empty(size)
                status = _solve_level_qp(H, f, C, upper, eps_prox, daqp_kernel.QP_FIXED_POINT, y)
                if status != STATUS_OK:
                    return status
                z[:] = y[:nz]
        if identity:
            for i in range(n):
                x[i] += z[i]
        else:
            for i in range(n):
                s = 0.0
                for c in range(nz):
                    s += Z[i, c] * z[c]
                x[i] += s
        num_verified = mh
        if ms:
            for i in range(ms):
                G_all[mh] = soft_G[s0 + i]
                violation = _row_dot(soft_G, s0 + i, x) - soft_h[s0 + i]
                h_all[mh] = soft_h[s0 + i] + max(violation, 0.0) + fix_tolerance
                mh += 1
        if m and nz and level + 1 < num_levels:
            if not have_split:
                rank, _, _, N, _, _, _, _ = _row_space_split(Az, rank_tolerance)
            kept = nz - rank
            if identity:
                Z[:, :kept] = N[:n, :kept]
            else:
                Z_next[:, :kept] = np.dot(np.ascontiguousarray(Z[:, :nz]), N)
                Z, Z_next = Z_next, Z
            identity = False
            gz_rows = 0  # GZ_all is recomputed for the new Z, from the sparse rows
            nz = kept
    for level in range(num_levels):
        e0, e1 = eq_start[level], eq_start[level + 1]
        total = 0.0
        for i in range(e0, e1):
            r = _row_dot(eq_A, i, x) - eq_b[i]
            total += r * r
        residuals[level] = math.sqrt(total)
    return STATUS_OK


@kernel
def solve_weighted(n, rows, level_weights, regularization, eps_prox, x, residuals) -> int:
    """One QP with level k's equalities and soft rows weighted by level_weights[k], hard rows kept
    hard (reference_hqp.solve_weighted), into x (n,) and the residuals (L,); returns a status.
    `rows`: a RowTable's arrays (`RowTable.arrays`)."""
    eq_A, eq_b, eq_start, hard_G, hard_h, hard_start, soft_G, soft_h, soft_w, soft_start = rows
    num_levels = len(eq_start) - 1
    mh = hard_G.shape[0]
    ms = soft_G.shape[0]
    size = n + ms
    H = np.zeros((size, size))
    f = np.zeros(size)
    for i in range(n):
        H[i, i] = regularization
    for level in range(num_levels):
        e0, e1 = eq_start[level], eq_start[level + 1]
        A = eq_A[e0:e1]
        weight = level_weights[level]
        # Grouped as reference_hqp.solve_weighted does: the weights span many decades, so the rounding of
        # this sum is the solution's (the weighted QP is that ill-conditioned).
        weighted_At = weight * A.T
        H[:n, :n] += weighted_At @ A
        f[:n] -= weighted_At @ eq_b[e0:e1]
        for i in range(soft_start[level], soft_start[level + 1]):
            H[n + i, n + i] = weight * soft_w[i] + regularization
    C = np.zeros((mh + ms, size))
    upper = np.empty(mh + ms)
    C[:mh, :n] = hard_G
    upper[:mh] = hard_h
    for i in range(ms):
        C[mh + i, :n] = soft_G[i]
        C[mh + i, n + i] = -1.0
        upper[mh + i] = soft_h[i]
    y = np.empty(size)
    status = _solve_level_qp(H, f, C, upper, eps_prox, daqp_kernel.AUTOMATIC_FIXED_POINT, y)
    if status != STATUS_OK:
        return status
    x[:] = y[:n]
    for level in range(num_levels):
        e0, e1 = eq_start[level], eq_start[level + 1]
        r = eq_A[e0:e1] @ x - eq_b[e0:e1]
        residuals[level] = math.sqrt(r @ r)
    return STATUS_OK


def solve_table_strict(table: RowTable, settings: HqpSettings | None = None) -> tuple[int, np.ndarray, np.ndarray]:
    """(status, x, residuals) of `solve_strict` on a RowTable (tests, benchmarks)."""
    settings = settings or HqpSettings()
    x, residuals = np.zeros(table.n), np.zeros(table.num_levels)
    tolerances = (settings.rank_tolerance, settings.fix_tolerance, settings.proximal_weight)
    status = solve_strict(table.n, table.arrays(), *tolerances, x, residuals)
    return status, x, residuals


def solve_table_weighted(
    table: RowTable, level_weights, settings: HqpSettings | None = None
) -> tuple[int, np.ndarray, np.ndarray]:
    """(status, x, residuals) of `solve_weighted` on a RowTable (tests, benchmarks)."""
    settings = settings or HqpSettings()
    x, residuals = np.zeros(table.n), np.zeros(table.num_levels)
    weights = np.asarray(level_weights, float)
    status = solve_weighted(
        table.n, table.arrays(), weights, settings.regularization, settings.proximal_weight, x, residuals
    )
    return status, x, residuals
