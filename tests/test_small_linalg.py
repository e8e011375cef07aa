"""The compiled controller's Householder QR: factor, null-space columns and Q times a vector."""

import numpy as np
import pytest

from pedi_drake.control.small_linalg import householder_factor, householder_q_columns, householder_q_times


def _factor(A: np.ndarray, pivot: bool, kernels=(householder_factor,)):
    m, n = A.shape
    W, tau, R = np.full((n, n), np.nan), np.full(n, np.nan), np.empty((m, m))
    order = np.empty(n, dtype=np.int64)
    kernels[0](A, W, tau, R, order, pivot)
    return W, tau, R, order[:m].copy()


def _q(W, tau, m, n, first=0, kernel=householder_q_columns) -> np.ndarray:
    out = np.full((n, n), np.nan)
    kernel(W, tau, m, n, first, out)
    return out[:, : n - first]


@pytest.mark.parametrize("pivot", [False, True], ids=["plain", "pivoted"])
def test_the_factorisation_reproduces_a_and_its_q_is_orthonormal(pivot):
    rng = np.random.default_rng(3)
    for m, n in ((1, 5), (6, 30), (15, 30), (9, 15), (12, 12)):
        A = rng.normal(size=(m, n)) * (rng.random((m, n)) < 0.4)  # sparse rows, like the stack's
        A[0, 0] = 1.0  # never an all-zero first row
        W, tau, R, order = _factor(A, pivot)
        Q = _q(W, tau, m, n)
        np.testing.assert_allclose(Q.T @ Q, np.eye(n), atol=1e-13)
        np.testing.assert_array_equal(np.triu(R), R)
        np.testing.assert_allclose(A[order].T, Q[:, :m] @ R, atol=1e-12)
        if pivot:
            assert np.all(np.diff(np.abs(np.diag(R))) <= 1e-12)
        else:
            np.testing.assert_array_equal(order, np.arange(m))


def test_null_space_columns_are_the_full_q_s_columns_bit_for_bit():
    rng = np.random.default_rng(4)
    A = rng.normal(size=(15, 30))
    A[10:] = rng.normal(size=(5, 10)) @ A[:10]  # rank 10: a pivoted split keeps 20 columns
    for pivot in (False, True):
        W, tau, _, _ = _factor(A, pivot)
        Q = _q(W, tau, 15, 30)
        for first in (0, 10, 15, 30):
            np.testing.assert_array_equal(_q(W, tau, 15, 30, first), Q[:, first:])


def test_q_times_a_vector_is_q_s_leading_columns_times_it():
    rng = np.random.default_rng(5)
    for m, n in ((3, 8), (15, 30), (20, 20)):
        W, tau, _, _ = _factor(rng.normal(size=(m, n)), False)
        Q = _q(W, tau, m, n)
        for count in (0, 1, m):
            w = rng.normal(size=max(count, 1))
            z = np.full(n, np.nan)
            householder_q_times(W, tau, m, n, w, count, z)
            np.testing.assert_allclose(z, Q[:, :count] @ w[:count], atol=1e-13)


def test_a_zero_row_gives_no_reflector_and_keeps_q_orthonormal():
    A = np.zeros((2, 4))
    A[1] = [0.0, 2.0, 0.0, 1.0]
    W, tau, R, _ = _factor(A, False)
    assert tau[0] == 0.0 and R[0, 0] == 0.0
    Q = _q(W, tau, 2, 4)
    np.testing.assert_allclose(Q.T @ Q, np.eye(4), atol=1e-15)


def test_the_compiled_kernels_equal_their_interpreted_code():
    rng = np.random.default_rng(6)
    A = rng.normal(size=(9, 14))
    for pivot in (False, True):
        compiled = _factor(A, pivot)
        interpreted = _factor(A, pivot, (householder_factor.py_func,))
        for a, b in zip(compiled, interpreted, strict=True):
            np.testing.assert_allclose(a[np.isfinite(a)], b[np.isfinite(b)], rtol=0, atol=1e-14)
        W, tau = compiled[0], compiled[1]
        np.testing.assert_allclose(
            _q(W, tau, 9, 14, 4), _q(W, tau, 9, 14, 4, householder_q_columns.py_func), rtol=0, atol=1e-14
        )
        w, z, z_ref = rng.normal(size=9), np.empty(14), np.empty(14)
        householder_q_times(W, tau, 9, 14, w, 9, z)
        householder_q_times.py_func(W, tau, 9, 14, w, 9, z_ref)
        np.testing.assert_allclose(z, z_ref, rtol=0, atol=1e-14)
