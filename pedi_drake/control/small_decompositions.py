"""Symmetric eigendecomposition, the pseudo-inverse it gives, and LU solves, for small matrices in
compiled code.

Paper 002's controller takes the pseudo-inverse of a symmetric positive semi-definite matrix (a
contact Gram matrix, a task's inverse inertia) five to seven times a tick, on matrices of 2 to 18
rows. On matrices that small LAPACK's dsyevd spends most of its time in its setup and its
divide-and-conquer machinery, which pays off only for matrices in the hundreds. The classical
algorithm below (Householder reduction to tridiagonal form, then implicit QL iterations with
Wilkinson shifts: EISPACK's tred2 and tql2 as published in JAMA) is several times faster there,
to the same accuracy (eigenvalues to about machine epsilon times the largest one, orthonormal
eigenvectors).

* `symmetric_eigen(A, w, W)`: A = W^T diag(w) W with w ascending, as LAPACK returns them, and
  the eigenvectors as the rows of W (LAPACK's columns). Reads the lower triangle of A. False (w,
  W meaningless) for non-finite input or an iteration that does not converge, never an
  exception.
* `symmetric_pseudo_inverse(A, rank_tolerance, scale, out)`: projected_dynamics'
  `symmetric_pseudo_inverse` (the same rule: eigenvalues above rank_tolerance times `scale`, or
  times the largest eigenvalue, kept) into `out`; returns the rank, -1 on failure.
* `lu_solve(A, B)`: A X = B in place (B becomes X) by Gaussian elimination with partial pivoting
  (LAPACK's dgesv); False for an exactly singular or non-finite A.
"""

import math

import numpy as np

from pedi_drake.runtime.jit import kernel

_EPSILON = 2.0**-52
# QL sweeps allowed per eigenvalue before giving up (JAMA sets none; 30 is EISPACK's limit and
# converged matrices take 1 to 3).
_MAX_SWEEPS = 30


@kernel
def _all_finite_matrix(A: np.ndarray) -> bool:
    for i in range(A.shape[0]):
        for j in range(A.shape[1]):
            if not math.isfinite(A[i, j]):
                return False
    return True


@kernel
def symmetric_eigen(A: np.ndarray, w: np.ndarray, W: np.ndarray) -> bool:
    """A (n, n) symmetric (lower triangle read) = W^T diag(w) W into w (n,) ascending and W (n, n),
    whose ROW k is the unit eigenvector of w[k]; False on non-finite input or no convergence.

    Rows rather than LAPACK's columns: every inner loop (the Householder updates, the QL
    rotations, the pseudo-inverse's sum) then runs along contiguous memory."""
    n = A.shape[0]
    if n == 0:
        return True
    if not _all_finite_matrix(A):
        return False
    for i in range(n):
        for j in range(i + 1):
            W[j, i] = A[i, j]
            W[i, j] = A[i, j]
    d = w
    e = np.zeros(n)
    # Householder reduction to tridiagonal form (tred2): d diagonal, e sub-diagonal.
    for j in range(n):
        d[j] = W[j, n - 1]
    for i in range(n - 1, 0, -1):
        scale = 0.0
        h = 0.0
        for k in range(i):
            scale += abs(d[k])
        if scale == 0.0:
            e[i] = d[i - 1]
            for j in range(i):
                d[j] = W[j, i - 1]
                W[j, i] = 0.0
                W[i, j] = 0.0
        else:
            for k in range(i):
                d[k] /= scale
                h += d[k] * d[k]
            f = d[i - 1]
            g = math.sqrt(h)
            if f > 0.0:
                g = -g
            e[i] = scale * g
            h -= f * g
            d[i - 1] = f - g
            for j in range(i):
                e[j] = 0.0
            for j in range(i):
                f = d[j]
                W[i, j] = f
                g = e[j] + W[j, j] * f
                for k in range(j + 1, i):
                    g += W[j, k] * d[k]
                    e[k] += W[j, k] * f
                e[j] = g
            f = 0.0
            for j in range(i):
                e[j] /= h
                f += e[j] * d[j]
            hh = f / (h + h)
            for j in range(i):
                e[j] -= hh * d[j]
            for j in range(i):
                f = d[j]
                g = e[j]
                for k in range(j, i):
                    W[j, k] -= f * e[k] + g * d[k]
                d[j] = W[j, i - 1]
                W[j, i] = 0.0
        d[i] = h
    # Accumulate the transformations.
    for i in range(n - 1):
        W[i, n - 1] = W[i, i]
        W[i, i] = 1.0
        h = d[i + 1]
        if h != 0.0:
            for k in range(i + 1):
                d[k] = W[i + 1, k] / h
            for j in range(i + 1):
                g = 0.0
                for k in range(i + 1):
                    g += W[i + 1, k] * W[j, k]
                for k in range(i + 1):
                    W[j, k] -= g * d[k]
        for k in range(i + 1):
            W[i + 1, k] = 0.0
    for j in range(n):
        d[j] = W[j, n - 1]
        W[j, n - 1] = 0.0
    W[n - 1, n - 1] = 1.0
    e[0] = 0.0

    # Implicit QL iterations on the tridiagonal matrix (tql2).
    for i in range(1, n):
        e[i - 1] = e[i]
    e[n - 1] = 0.0
    f = 0.0
    tst1 = 0.0
    for l in range(n):  # noqa: E741 - the published algorithm's name for the current index
        tst1 = max(tst1, abs(d[l]) + abs(e[l]))
        m = l
        while m < n - 1:
            if abs(e[m]) <= _EPSILON * tst1:
                break
            m += 1
        if m > l:
            sweeps = 0
            while True:
                sweeps += 1
                if sweeps > _MAX_SWEEPS:
                    return False
                g = d[l]
                p = (d[l + 1] - g) / (2.0 * e[l])
                r = math.sqrt(p * p + 1.0)
                if p < 0.0:
                    r = -r
                d[l] = e[l] / (p + r)
                d[l + 1] = e[l] * (p + r)
                dl1 = d[l + 1]
                h = g - d[l]
                for i in range(l + 2, n):
                    d[i] -= h
                f += h
                p = d[m]
                c = 1.0
                c2 = c
                c3 = c
                el1 = e[l + 1]
                s = 0.0
                s2 = 0.0
                for i in range(m - 1, l - 1, -1):
                    c3 = c2
                    c2 = c
                    s2 = s
                    g = c * e[i]
                    h = c * p
                    r = math.sqrt(p * p + e[i] * e[i])
                    e[i + 1] = s * r
                    s = e[i] / r
                    c = p / r
                    p = c * d[i] - s * g
                    d[i + 1] = h + s * (c * g + s * d[i])
                    for k in range(n):
                        h = W[i + 1, k]
                        W[i + 1, k] = s * W[i, k] + c * h
                        W[i, k] = c * W[i, k] - s * h
                p = -s * s2 * c3 * el1 * e[l] / dl1
                e[l] = s * p
                d[l] = c * p
                if not abs(e[l]) > _EPSILON * tst1:
                    break
        d[l] = d[l] + f
        e[l] = 0.0
    # Ascending order, eigenvectors with their eigenvalues.
    for i in range(n - 1):
        k = i
        p = d[i]
        for j in range(i + 1, n):
            if d[j] < p:
                k = j
                p = d[j]
        if k != i:
            d[k] = d[i]
            d[i] = p
            for j in range(n):
                p = W[i, j]
                W[i, j] = W[k, j]
                W[k, j] = p
    for i in range(n):
        if not math.isfinite(d[i]):
            return False
    return True


@kernel
def symmetric_pseudo_inverse(A: np.ndarray, rank_tolerance: float, scale: float, out: np.ndarray) -> int:
    """A^+ of a symmetric positive semi-definite A (n, n) into out (n, n); returns its rank, or -1
    when the decomposition fails (non-finite A).

    Eigenvalues above `rank_tolerance * scale` are kept, a negative `scale` meaning the largest
    eigenvalue; a largest eigenvalue (or scale) that is not positive gives zero and rank 0
    (projected_dynamics.symmetric_pseudo_inverse, whose docstring says why a scale is passed)."""
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
    """Solves A X = B for square A (n, n) and B (n, k), X written over B; A is overwritten by its
    LU factors. Partial pivoting (the largest magnitude in the column, as LAPACK's dgetrf); False
    for a non-finite or exactly singular A (B then meaningless)."""
    n = A.shape[0]
    k = B.shape[1]
    if not _all_finite_matrix(A):
        return False
    for c in range(n):
        pivot = c
        largest = abs(A[c, c])
        for i in range(c + 1, n):
            if abs(A[i, c]) > largest:
                largest = abs(A[i, c])
                pivot = i
        if largest == 0.0:
            return False
        if pivot != c:
            for j in range(n):
                A[c, j], A[pivot, j] = A[pivot, j], A[c, j]
            for j in range(k):
                B[c, j], B[pivot, j] = B[pivot, j], B[c, j]
        inverse = 1.0 / A[c, c]
        for i in range(c + 1, n):
            factor = A[i, c] * inverse
            A[i, c] = factor
            if factor != 0.0:
                for j in range(c + 1, n):
                    A[i, j] -= factor * A[c, j]
                for j in range(k):
                    B[i, j] -= factor * B[c, j]
    for c in range(n - 1, -1, -1):
        inverse = 1.0 / A[c, c]
        for j in range(k):
            B[c, j] *= inverse
        for i in range(c):
            factor = A[i, c]
            if factor != 0.0:
                for j in range(k):
                    B[i, j] -= factor * B[c, j]
    return True
