"""DAQP called from compiled code (pedi_drake.numerics.daqp_kernel) against DAQP's Python module on
the same problems: the same solver, so the same solution to rounding."""

import daqp
import numpy as np
import pytest

from pedi_drake.numerics import daqp_kernel


def random_qp(rng: np.random.Generator, n: int, m: int, rank: int):
    """A QP with a Hessian of the given rank (semi-definite below n) and a feasible polytope."""
    A = rng.normal(size=(rank, n))
    H = A.T @ A
    f = rng.normal(size=n)
    C = rng.normal(size=(m, n))
    upper = rng.random(m) + 0.1  # y = 0 is strictly feasible
    lower = np.full(m, -daqp_kernel.INFINITE_BOUND)
    lower[: m // 3] = -upper[: m // 3] - rng.random(m // 3)  # some two-sided rows
    return H, f, C, upper, lower


def solve(H, f, C, upper, lower, eps_prox, sense=None):
    n, m = len(f), len(upper)
    y, multipliers = np.zeros(n), np.zeros(m)
    sense = np.zeros(m, np.int32) if sense is None else sense
    exit_flag = daqp_kernel.solve_qp(H, f, C, upper, lower, sense, eps_prox, -1.0, 0.0, y, multipliers)
    return exit_flag, y, multipliers


@pytest.mark.parametrize("seed", range(12))
def test_the_compiled_call_solves_as_daqps_python_module(seed):
    rng = np.random.default_rng(seed)
    n = int(rng.integers(4, 40))
    m = int(rng.integers(1, 100))
    # Positive definite, semi-definite (a hierarchical level) and zero (an LP), bounded by a box.
    for rank, eps_prox in ((n + 2, -1e-6), (n // 2, 1e-5), (0, 1e-5)):
        H, f, C, upper, lower = random_qp(rng, n, m, rank)
        C = np.vstack([C, np.eye(n), -np.eye(n)])
        upper = np.concatenate([upper, np.full(2 * n, 10.0)])
        lower = np.concatenate([lower, np.full(2 * n, -daqp_kernel.INFINITE_BOUND)])
        exit_flag, y, multipliers = solve(H, f, C, upper, lower, eps_prox)
        expected, _, expected_flag, info = daqp.solve(H, f, C, upper, lower, eps_prox=eps_prox)
        assert exit_flag == expected_flag and daqp_kernel.solved(exit_flag)
        np.testing.assert_allclose(y, expected, atol=1e-9)
        np.testing.assert_allclose(multipliers, info["lam"], atol=1e-9)
        assert np.all(C @ y <= upper + 1e-6) and np.all(C @ y >= lower - 1e-6)


def test_an_infeasible_problem_says_so():
    H, f = np.eye(2), np.zeros(2)
    C = np.array([[1.0, 0.0], [-1.0, 0.0]])
    upper = np.array([-1.0, -1.0])  # x <= -1 and x >= 1
    exit_flag, _, _ = solve(H, f, C, upper, np.full(2, -daqp_kernel.INFINITE_BOUND), -1e-6)
    assert exit_flag == daqp_kernel.EXIT_INFEASIBLE and not daqp_kernel.solved(exit_flag)


def test_a_warm_start_at_the_optimal_working_set_gives_the_same_solution():
    rng = np.random.default_rng(7)
    H, f, C, upper, lower = random_qp(rng, 12, 40, 14)
    exit_flag, y, multipliers = solve(H, f, C, upper, lower, -1e-6)
    active = np.zeros(12, np.int64)
    count = daqp_kernel.active_rows(multipliers, active)
    assert count > 0
    sense = np.zeros(40, np.int32)
    for row in active[:count]:
        sense[row] = daqp_kernel.SENSE_ACTIVE | (daqp_kernel.SENSE_LOWER if multipliers[row] < 0 else 0)
    warm_flag, warm_y, _ = solve(H, f, C, upper, lower, -1e-6, sense)
    assert daqp_kernel.solved(warm_flag)
    np.testing.assert_allclose(warm_y, y, atol=1e-9)


def test_a_strided_or_mistyped_argument_is_refused_not_misread():
    rng = np.random.default_rng(3)
    H, f, C, upper, lower = random_qp(rng, 5, 10, 6)
    wide = np.zeros((5, 10))
    wide[:, ::2] = H
    assert solve(wide[:, ::2], f, C, upper, lower, -1e-6)[0] == daqp_kernel.EXIT_BAD_ARRAY
    assert solve(H, f, C, upper, lower, -1e-6, np.zeros(10, np.int64))[0] == daqp_kernel.EXIT_BAD_ARRAY


def test_active_rows_never_writes_past_its_array():
    multipliers = np.array([1.0, 0.0, -2.0, 3.0, 4.0])
    active = np.full(3, -1, np.int64)
    assert daqp_kernel.active_rows(multipliers, active) == 3
    assert active.tolist() == [0, 2, 3]
