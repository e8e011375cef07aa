"""Dense linear algebra on the controller's small matrices, as compiled kernels.

The hierarchical QP splits every level's task rows into their row space and null space and
solves small least-squares problems, on matrices of 3 to 40 rows and columns, several times a
tick. At these sizes a LAPACK call from Python costs more in call overhead than in arithmetic, so
the compiled controller does the same factorisations here, in the same algorithms as LAPACK's
unblocked routines (so results agree to rounding):

* `householder_factor(A, W, tau, R, order, pivot)`: the QR factorisation of A^T (A is m x n
  with m <= n, read as its m rows), A^T P = Q [R; 0] with Q (n x n) orthogonal, R (m x m) upper
  triangular and P the permutation of A's rows in `order`: the first m columns of Q span the row
  space of A, the last n - m its null space (LAPACK's dgeqr2: reflectors H_k = I - tau_k v_k
  v_k^T, v_k[k] = 1, kept in W and tau). Without pivoting P is the identity; with it, each step
  takes the remaining row of largest norm first (as LAPACK's dgeqp3), so |R[k, k]| does not
  increase with k and a rank-deficient A shows its rank r in R's diagonal: then the first r
  columns of Q span its row space and the last n - r its null space. Q is never formed whole:
  `householder_q_columns` forms the null-space columns (as dorg2r would, for those columns only)
  and `householder_q_times` applies Q's row-space columns to a vector (as dormqr would), which
  halves the work of a split at the stack's sizes.
* `multiply(A, B, out)`: out = A B, skipping A's zero entries (the controllers' Jacobians and
  task rows are mostly zeros); writes out's leading (rows of A, columns of B) block.
* `multiply_transposed(A, B, out)`: out = A B^T (Gram matrices, normal equations).
* `forward_substitute_transposed(R, r, w)`: R^T w = r for upper-triangular R.
* `cholesky_in_place(A, n)`: the Cholesky factor of A's leading n x n block, in place (the dense
  QP solver factors its Hessian with it).
* `cholesky_solve(S, r, z)`: S z = r for symmetric positive definite S, by the Cholesky factor
  L (S = L L^T), which is returned in S's lower triangle for callers that judge its conditioning.
"""

import math

import numpy as np

from pedi_drake.runtime.jit import kernel

# A downdated row norm is recomputed once its square has lost half of float64's digits (LAPACK's
# tol3z, sqrt(machine epsilon)).
_DOWNDATE_TOLERANCE = math.sqrt(np.finfo(np.float64).eps)


@kernel
def householder_factor(
    A: np.ndarray, W: np.ndarray, tau: np.ndarray, R: np.ndarray, order: np.ndarray, pivot: bool
) -> None:
    """A^T P = Q [R; 0] for A (m, n), m <= n, with Q kept as its reflectors: fills R (m, m), order
    (m,) (row order[k] of A was factorised k-th; always k without `pivot`), and W (at least m x n)
    and tau (at least m), where H_k = I - tau[k] v_k v_k^T with v_k[:k] = 0, v_k[k] = 1 and
    v_k[k + 1 : n] = W[k, k + 1 : n]. `householder_q_columns` and `householder_q_times` apply Q.
    A is not modified."""
    m, n = A.shape
    for k in range(m):  # row k of W is column k of the factorised matrix
        for i in range(n):
            W[k, i] = A[k, i]
        tau[k] = 0.0
        order[k] = k
    # With pivoting, each remaining row's norm in the coordinates not yet factorised, kept up to
    # date as LAPACK's dlaqp2 does: scaled down by each step's reflector, and recomputed from the
    # row when the scaling has cancelled more than half the digits of its norm at its last
    # recomputation (`reference`). This keeps the pivoting's cost O(m n) instead of O(m^2 n).
    norms = np.empty(m if pivot else 0)
    reference = np.empty(m if pivot else 0)
    if pivot:
        for j in range(m):
            s = 0.0
            for i in range(n):
                s += W[j, i] * W[j, i]
            norms[j] = math.sqrt(s)
            reference[j] = norms[j]
    for k in range(m):
        if pivot:
            best = k
            for j in range(k + 1, m):
                if norms[j] > norms[best]:
                    best = j
            if best != k:
                for i in range(n):
                    W[k, i], W[best, i] = W[best, i], W[k, i]
                order[k], order[best] = order[best], order[k]
                norms[k], norms[best] = norms[best], norms[k]
                reference[k], reference[best] = reference[best], reference[k]
        alpha = W[k, k]
        scale = 0.0
        for i in range(k + 1, n):
            scale += W[k, i] * W[k, i]
        xnorm = math.sqrt(scale)
        if xnorm == 0.0:
            tau[k] = 0.0
            continue
        beta = -math.copysign(math.hypot(alpha, xnorm), alpha)
        tau[k] = (beta - alpha) / beta
        inv = 1.0 / (alpha - beta)
        for i in range(k + 1, n):
            W[k, i] *= inv
        W[k, k] = beta
        # Apply H_k to the remaining columns (rows j > k of W), coordinates k..n-1.
        for j in range(k + 1, m):
            dot = W[j, k]
            for i in range(k + 1, n):
                dot += W[k, i] * W[j, i]
            dot *= tau[k]
            W[j, k] -= dot
            for i in range(k + 1, n):
                W[j, i] -= dot * W[k, i]
            if pivot and norms[j] != 0.0:
                ratio = abs(W[j, k]) / norms[j]
                remaining = max((1.0 + ratio) * (1.0 - ratio), 0.0)
                if remaining * (norms[j] / reference[j]) ** 2 <= _DOWNDATE_TOLERANCE:
                    s = 0.0
                    for i in range(k + 1, n):
                        s += W[j, i] * W[j, i]
                    norms[j] = math.sqrt(s)
                    reference[j] = norms[j]
                else:
                    norms[j] *= math.sqrt(remaining)
    for i in range(m):
        for j in range(m):
            R[i, j] = W[j, i] if j >= i else 0.0


@kernel
def householder_q_columns(W: np.ndarray, tau: np.ndarray, m: int, n: int, first: int, out: np.ndarray) -> None:
    """out[:n, :n - first] = Q[:, first:] of a `householder_factor` of an (m, n) matrix: the null
    space when `first` is its rank. Only these columns are formed: Q = H_0 ... H_{m-1} applied to
    the identity's columns `first`.., accumulated from the last reflector back (each touches rows
    k..; column c is still e_c in those rows while k > c, so it is skipped), with v^T Q summed row
    by row so every inner loop runs along a row."""
    columns = n - first
    for i in range(n):
        for j in range(columns):
            out[i, j] = 1.0 if i == j + first else 0.0
    w = np.empty(max(columns, 1))
    for k in range(m - 1, -1, -1):
        t = tau[k]
        if t == 0.0:
            continue
        j0 = max(k - first, 0)
        for j in range(j0, columns):
            w[j] = out[k, j]
        for i in range(k + 1, n):
            v = W[k, i]
            for j in range(j0, columns):
                w[j] += v * out[i, j]
        for j in range(j0, columns):
            w[j] *= t
            out[k, j] -= w[j]
        for i in range(k + 1, n):
            v = W[k, i]
            for j in range(j0, columns):
                out[i, j] -= v * w[j]


@kernel
def householder_q_times(
    W: np.ndarray, tau: np.ndarray, m: int, n: int, w: np.ndarray, count: int, z: np.ndarray
) -> None:
    """z (n,) = Q [w[:count]; 0] of a `householder_factor` of an (m, n) matrix: Q's first `count`
    columns times w, by the reflectors (H_{m-1} first), without forming Q."""
    for i in range(n):
        z[i] = w[i] if i < count else 0.0
    for k in range(m - 1, -1, -1):
        t = tau[k]
        if t == 0.0:
            continue
        s = z[k]
        for i in range(k + 1, n):
            s += W[k, i] * z[i]
        s *= t
        z[k] -= s
        for i in range(k + 1, n):
            z[i] -= s * W[k, i]


@kernel
def multiply(A: np.ndarray, B: np.ndarray, out: np.ndarray) -> None:
    """out = A B (into out's leading block), skipping A's zero entries; the innermost loop runs
    along B's and out's rows."""
    m, k = A.shape
    n = B.shape[1]
    for i in range(m):
        for j in range(n):
            out[i, j] = 0.0
        for p in range(k):
            a = A[i, p]
            if a != 0.0:
                for j in range(n):
                    out[i, j] += a * B[p, j]


@kernel
def multiply_transposed(A: np.ndarray, B: np.ndarray, out: np.ndarray) -> None:
    """out = A B^T (into out's leading block); every inner loop runs along a row of A and of B."""
    m, k = A.shape
    n = B.shape[0]
    for i in range(m):
        for j in range(n):
            s = 0.0
            for p in range(k):
                s += A[i, p] * B[j, p]
            out[i, j] = s


@kernel
def forward_substitute_transposed(R: np.ndarray, r: np.ndarray, w: np.ndarray) -> bool:
    """Solves R^T w = r for upper-triangular R (m, m); False (w untouched beyond) on a zero pivot."""
    m = R.shape[0]
    for i in range(m):
        s = r[i]
        for k in range(i):
            s -= R[k, i] * w[k]
        if R[i, i] == 0.0:
            return False
        w[i] = s / R[i, i]
    return True


@kernel
def cholesky_in_place(A: np.ndarray, n: int) -> bool:
    """A's leading (n, n) block <- its Cholesky factor L in the lower triangle (A = L L^T; the
    strict upper triangle is left as it was); False when A is not numerically positive definite."""
    for j in range(n):
        d = A[j, j]
        for p in range(j):
            d -= A[j, p] * A[j, p]
        if not d > 0.0:
            return False
        d = math.sqrt(d)
        A[j, j] = d
        for i in range(j + 1, n):
            s = A[i, j]
            for p in range(j):
                s -= A[i, p] * A[j, p]
            A[i, j] = s / d
    return True


@kernel
def cholesky_solve(S: np.ndarray, r: np.ndarray, z: np.ndarray) -> bool:
    """Solves S z = r for symmetric positive definite S (k, k), overwriting S's lower triangle
    with the Cholesky factor L (S = L L^T); False when S is not numerically positive definite."""
    k = S.shape[0]
    if not cholesky_in_place(S, k):
        return False
    for i in range(k):  # L y = r
        s = r[i]
        for p in range(i):
            s -= S[i, p] * z[p]
        z[i] = s / S[i, i]
    for i in range(k - 1, -1, -1):  # L^T z = y
        s = z[i]
        for p in range(i + 1, k):
            s -= S[p, i] * z[p]
        z[i] = s / S[i, i]
    return True
