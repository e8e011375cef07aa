"""The dense QP solver (pedi_drake.control.dense_qp): KKT conditions checked directly, DAQP as the
reference on random and recorded controller QPs, the statuses of bad problems, the compiled
kernel against its Python source.

Tolerances: a solution is accepted when
  stationarity   |H y + f + C'lam|_inf <= 1e-7 max(1, |f|_inf, |H y|_inf, |C'lam|_inf),
  primal         C y - u <= 1e-8,
  dual           lam >= 0 (the solver clips its multipliers at zero),
  complementarity |lam_i (c_i y - u_i)| <= 1e-7 max(1, the same gradient scale).
The solver's own tolerances are 100 times tighter; these leave room for the conditioning of
H + eps I (up to 1e5 / 1e-5 here).
"""

import os
import subprocess
import sys
import textwrap

import daqp
import numpy as np
import pytest

from pedi_drake.benchmarks.dense_qp import DEFAULT_FIXTURE, load_qps, objective, solution_is_unique
from pedi_drake.control import dense_qp
from pedi_drake.control.dense_qp import (
    INFEASIBLE,
    ITERATION_LIMIT,
    NUMERICAL_FAILURE,
    OPTIMAL,
    UNBOUNDED,
    DenseQpSettings,
    solve,
    solve_qp,
)
from pedi_drake.runtime import jit
from pedi_drake.runtime.jit import kernel

RNG_SEED = 20261202
STATIONARITY = 1e-7
PRIMAL = 1e-8
# DAQP's exit flags.
DAQP_OPTIMAL = (1, 2)
DAQP_INFEASIBLE = -1
DAQP_UNBOUNDED = -3


def daqp_reference(H, f, C, u):
    """DAQP with proximal iterations run to a tight tolerance (its default stops at about 1e-5)."""
    y, _, exitflag, info = daqp.solve(H, f, C, u, np.full(len(u), -1e30), eps_prox=1e-5, eta_prox=1e-12)
    return np.asarray(y), exitflag


def assert_kkt(H, f, C, u, solution):
    """The four KKT conditions of min 0.5 y'Hy + f'y s.t. C y <= u at (y, multipliers)."""
    y, lam = solution.y, solution.multipliers
    assert solution.status == OPTIMAL
    assert np.isfinite(y).all()
    gradient = H @ y + f
    scale = max(1.0, np.abs(f).max(initial=0), np.abs(H @ y).max(initial=0), np.abs(C.T @ lam).max(initial=0))
    assert np.abs(gradient + C.T @ lam).max(initial=0) <= STATIONARITY * scale, "stationarity"
    bounded = u < dense_qp.INFINITE_BOUND
    assert (C[bounded] @ y - u[bounded]).max(initial=-np.inf) <= PRIMAL, "primal feasibility"
    assert lam.min(initial=0) >= 0.0, "dual feasibility"
    assert np.abs(lam[bounded] * (C[bounded] @ y - u[bounded])).max(initial=0) <= STATIONARITY * scale, (
        "complementarity"
    )
    assert lam[~bounded].max(initial=0) == 0.0


def random_problem(rng, n, m, rank=None, hqp_like=False, active=True):
    """(H, f, C, u): H = A'A of rank `rank` (n: strictly convex); hqp_like: variables (z, v) of a
    level with soft rows G z - v <= h weighted in H, as the controller builds them; bounded by a
    box on z so a singular H cannot make it unbounded. `active`: u cuts off the unconstrained
    minimum, so constraints are active at the solution."""
    if hqp_like:
        ms = max(1, min(m // 3, n // 2))
        nz = n - ms
        rank = nz if rank is None else min(rank, nz)
        A = rng.normal(size=(rank, nz))
        b = rng.normal(size=rank)
        H = np.zeros((n, n))
        H[:nz, :nz] = A.T @ A
        H[nz:, nz:] = np.diag(rng.uniform(0.1, 10.0, ms))
        f = np.zeros(n)
        f[:nz] = -A.T @ b
        G = rng.normal(size=(m - ms, nz))
        Gs = rng.normal(size=(ms, nz))
        C = np.zeros((m + 2 * nz, n))
        C[: m - ms, :nz] = G
        C[m - ms : m, :nz] = Gs
        C[m - ms : m, nz:] = -np.eye(ms)
        C[m : m + nz, :nz] = np.eye(nz)
        C[m + nz :, :nz] = -np.eye(nz)
        # Hard rows with u >= 0 keep z = 0 feasible; soft rows are always feasible.
        u = np.concatenate([rng.uniform(0.0, 1.0, m - ms), rng.uniform(-0.5, 0.5, ms), np.full(2 * nz, 10.0)])
        return H, f, C, u
    rank = n if rank is None else rank
    A = rng.normal(size=(rank, n))
    H = A.T @ A
    if rank == n:
        H += 0.1 * np.eye(n)
    f = rng.normal(size=n) * 3.0
    C = np.vstack([rng.normal(size=(m, n)), np.eye(n), -np.eye(n)])
    if active:
        y_free = np.linalg.lstsq(H, -f, rcond=None)[0]
        u_rows = C[:m] @ y_free - rng.uniform(-0.5, 1.0, m)
        # Keep 0 feasible for half of them at least: not every random cut is consistent.
        u_rows = np.maximum(u_rows, rng.uniform(0.01, 0.3, m) * (rng.random(m) < 0.5))
    else:
        u_rows = rng.uniform(5.0, 10.0, m)
    u = np.concatenate([u_rows, np.full(2 * n, 10.0)])
    return H, f, C, u


def check_against_daqp(H, f, C, u, unique_tolerance=1e-6):
    solution = solve(H, f, C, u)
    y_ref, flag = daqp_reference(H, f, C, u)
    assert flag in DAQP_OPTIMAL
    assert_kkt(H, f, C, u, solution)
    scale = max(1.0, np.abs(y_ref).max())

    def cost(y):
        return 0.5 * y @ H @ y + f @ y

    # Never worse than DAQP; equal to its optimum up to DAQP's own accuracy.
    assert cost(solution.y) <= cost(y_ref) + 1e-9 * scale * max(1.0, abs(cost(y_ref)))
    assert cost(solution.y) == pytest.approx(cost(y_ref), rel=1e-7, abs=1e-9 * scale)
    return solution, y_ref, scale


def test_strictly_convex_qps_match_daqp_and_meet_kkt():
    rng = np.random.default_rng(RNG_SEED)
    with_active = 0
    for _ in range(300):
        n = int(rng.integers(2, 30))
        H, f, C, u = random_problem(rng, n, int(rng.integers(1, 60)), active=bool(rng.random() < 0.8))
        solution, y_ref, scale = check_against_daqp(H, f, C, u)
        np.testing.assert_allclose(solution.y, y_ref, rtol=0, atol=1e-6 * scale)
        with_active += len(solution.active) > 0
    assert with_active > 200


def test_semidefinite_qps_reach_daqp_s_optimum_and_meet_kkt():
    rng = np.random.default_rng(RNG_SEED + 1)
    unique = 0
    for k in range(300):
        n = int(rng.integers(4, 40))
        hqp_like = k % 2 == 0
        H, f, C, u = random_problem(rng, n, int(rng.integers(4, 80)), rank=int(rng.integers(0, n)), hqp_like=hqp_like)
        solution, y_ref, scale = check_against_daqp(H, f, C, u)
        if solution_is_unique(_Qp(H, f, C, u), solution.y, solution.multipliers):
            unique += 1
            np.testing.assert_allclose(solution.y, y_ref, rtol=0, atol=1e-6 * scale)
    assert 0 < unique < 300  # both kinds were met


class _Qp:
    def __init__(self, H, f, C, u):
        self.H, self.f, self.C, self.u = H, f, C, u


def test_duplicated_and_redundant_rows_give_the_same_solution():
    rng = np.random.default_rng(RNG_SEED + 2)
    for _ in range(100):
        n = int(rng.integers(3, 20))
        H, f, C, u = random_problem(rng, n, int(rng.integers(3, 30)), rank=int(rng.integers(1, n + 1)))
        base = solve(H, f, C, u)
        assert_kkt(H, f, C, u, base)
        active = base.active
        if len(active) < 2:
            continue
        i, j = active[0], active[1]
        # Every active row twice, and the sum of two active rows (active too at the solution:
        # a degenerate vertex), in shuffled order.
        C2 = np.vstack([C, C[active], C[i] + C[j]])
        u2 = np.concatenate([u, u[active], [u[i] + u[j]]])
        order = rng.permutation(len(u2))
        degenerate = solve(H, f, C2[order], u2[order])
        assert_kkt(H, f, C2[order], u2[order], degenerate)
        scale = max(1.0, np.abs(base.y).max())
        assert objective(_Qp(H, f, C, u), degenerate.y) == pytest.approx(
            objective(_Qp(H, f, C, u), base.y), rel=1e-9, abs=1e-9 * scale
        )


def test_a_constraint_through_the_unconstrained_minimum_is_weakly_active():
    # min |y - (1, 1)|^2 s.t. y0 + y1 <= 2 (active, zero multiplier) and y0 <= 1 (the same).
    H = 2.0 * np.eye(2)
    f = np.array([-2.0, -2.0])
    C = np.array([[1.0, 1.0], [1.0, 0.0], [0.0, 1.0]])
    u = np.array([2.0, 1.0, 5.0])
    solution = solve(H, f, C, u)
    assert_kkt(H, f, C, u, solution)
    np.testing.assert_allclose(solution.y, [1.0, 1.0], atol=1e-12)


def test_contradicting_rows_are_infeasible_like_daqp():
    rng = np.random.default_rng(RNG_SEED + 3)
    for k in range(100):
        n = int(rng.integers(2, 25))
        H, f, C, u = random_problem(rng, n, int(rng.integers(2, 40)), rank=int(rng.integers(0, n + 1)))
        # A hidden contradiction: a'y <= -1, b'y <= -1 and -(a + b)'y <= 1.5 cannot hold together.
        a, b = rng.normal(size=n), rng.normal(size=n)
        C = np.vstack([C, a, b, -(a + b)])
        u = np.concatenate([u, [-1.0, -1.0, 1.5]])
        order = rng.permutation(len(u))
        C, u = C[order], u[order]
        solution = solve(H, f, C, u)
        assert solution.status == INFEASIBLE, k
        assert np.isfinite(solution.y).all()
        _, flag = daqp_reference(H, f, C, u)
        assert flag == DAQP_INFEASIBLE


def test_an_impossible_bound_is_infeasible():
    H, f = np.eye(2), np.zeros(2)
    assert solve_qp(H, f, np.zeros((1, 2)), np.array([-1.0]))[1] == INFEASIBLE
    assert solve_qp(H, f, np.ones((1, 2)), np.array([-np.inf]))[1] == INFEASIBLE
    # A zero row with u >= 0 is no constraint, and u = +inf or >= 1e30 is none either.
    y, status = solve_qp(
        H, np.array([-1.0, -2.0]), np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]]), np.array([0.0, np.inf, 1e30])
    )
    assert status == OPTIMAL
    np.testing.assert_allclose(y, [1.0, 2.0], atol=1e-12)


def test_a_descent_direction_without_a_bound_is_unbounded():
    rng = np.random.default_rng(RNG_SEED + 4)
    for _ in range(30):
        n = int(rng.integers(2, 15))
        A = rng.normal(size=(n - 1, n))
        H = A.T @ A
        null = np.linalg.svd(A)[2][-1]
        f = rng.normal(size=n)
        f += np.sign(rng.normal()) * (1.0 + abs(f @ null)) * null  # a real slope along the null space
        descent = -np.sign(f @ null) * null
        # Rows that only bound directions the descent does not take (c'descent <= 0).
        C = rng.normal(size=(int(rng.integers(0, 10)), n))
        C -= np.outer(np.maximum(C @ descent, 0.0) + 0.1, descent)
        u = rng.uniform(0.5, 2.0, len(C))
        solution = solve(H, f, C, u)
        assert solution.status == UNBOUNDED
        assert np.isfinite(solution.y).all()
        _, flag = daqp_reference(H, f, C, u)
        assert flag == DAQP_UNBOUNDED


def test_a_workspace_too_small_is_refused():
    H, f, C, u = np.eye(3), np.ones(3), np.ones((2, 3)), np.ones(2)
    y = np.full(3, 7.0)
    small = dense_qp.make_workspace(2, 2)
    status, _, _ = dense_qp.solve_dense_qp_kernel(
        H, f, C, u, 1e-5, 1e-9, 1e-9, 1e-9, 100, y, np.zeros(2), np.zeros(3, dtype=np.int64), 0,
        small.matrices, small.transposed, small.vectors, small.integers,
    )  # fmt: skip
    assert status == NUMERICAL_FAILURE


def test_bad_numbers_fail_without_nan():
    H, f, C, u = np.eye(3), np.ones(3), np.ones((2, 3)), np.ones(2)
    for bad in ("H", "f", "C", "u"):
        args = {"H": H.copy(), "f": f.copy(), "C": C.copy(), "u": u.copy()}
        args[bad].flat[0] = np.nan
        y, status = solve_qp(**args)
        assert status == NUMERICAL_FAILURE and np.array_equal(y, np.zeros(3))
    # Not semi-definite: H + eps I has a negative eigenvalue.
    y, status = solve_qp(np.diag([1.0, -1.0, 1.0]), f, C, u)
    assert status == NUMERICAL_FAILURE and np.array_equal(y, np.zeros(3))


def test_the_iteration_bound_is_kept():
    rng = np.random.default_rng(RNG_SEED + 5)
    H, f, C, u = random_problem(rng, 20, 40)
    full = solve(H, f, C, u)
    assert full.status == OPTIMAL and full.iterations > 3
    limited = solve(H, f, C, u, DenseQpSettings(max_iterations=2))
    assert limited.status == ITERATION_LIMIT
    assert limited.iterations <= 3
    assert np.isfinite(limited.y).all()


def test_without_constraints_it_is_least_squares():
    rng = np.random.default_rng(RNG_SEED + 6)
    A = rng.normal(size=(4, 7))
    b = rng.normal(size=4)
    y, status = solve_qp(A.T @ A, -A.T @ b, np.zeros((0, 7)), np.zeros(0))
    assert status == OPTIMAL
    np.testing.assert_allclose(A @ y, b, atol=1e-9)


def test_warm_start_from_the_previous_active_set_gives_the_same_solution_sooner():
    rng = np.random.default_rng(RNG_SEED + 7)
    fewer = 0
    for _ in range(100):
        n = int(rng.integers(4, 30))
        H, f, C, u = random_problem(rng, n, int(rng.integers(5, 60)), rank=int(rng.integers(1, n + 1)), hqp_like=True)
        cold = solve(H, f, C, u)
        assert_kkt(H, f, C, u, cold)
        # The next tick: the same problem slightly moved.
        f2 = f + 1e-3 * rng.normal(size=len(f))
        u2 = u + 1e-3 * rng.normal(size=len(u))
        again_cold = solve(H, f2, C, u2)
        warm = solve(H, f2, C, u2, initial_active=cold.active)
        assert_kkt(H, f2, C, u2, warm)
        assert objective(_Qp(H, f2, C, u2), warm.y) == pytest.approx(
            objective(_Qp(H, f2, C, u2), again_cold.y), rel=1e-9, abs=1e-9
        )
        fewer += warm.iterations < again_cold.iterations
    assert fewer > 50


def test_a_wrong_warm_start_is_harmless():
    rng = np.random.default_rng(RNG_SEED + 8)
    for _ in range(50):
        n = int(rng.integers(4, 20))
        H, f, C, u = random_problem(rng, n, int(rng.integers(5, 40)), rank=int(rng.integers(1, n + 1)))
        cold = solve(H, f, C, u)
        m = len(u)
        # Out of range, repeated, and arbitrary rows (inactive ones, dependent ones).
        guess = np.concatenate([[-1, m, m + 5], rng.integers(0, m, 3 * n)])
        warm = solve(H, f, C, u, initial_active=guess)
        assert_kkt(H, f, C, u, warm)
        assert objective(_Qp(H, f, C, u), warm.y) == pytest.approx(
            objective(_Qp(H, f, C, u), cold.y), rel=1e-9, abs=1e-9
        )


def test_the_kernel_equals_its_python_source():
    if not jit.ENABLED:
        pytest.skip("PEDI_DRAKE_JIT=0: the kernel is its Python source")
    # The kernel's body (the kernel itself only adds a guard against exceptions).
    kernel_ = dense_qp._solve
    assert kernel_.py_func is not kernel_
    rng = np.random.default_rng(RNG_SEED + 9)
    statuses = set()
    for k in range(40):
        n = int(rng.integers(2, 16))
        H, f, C, u = random_problem(
            rng, n, int(rng.integers(2, 25)), rank=int(rng.integers(0, n + 1)), hqp_like=k % 2 == 0
        )
        if k % 10 == 9:  # infeasible ones too
            C = np.vstack([C, C[0], -C[0]])
            u = np.concatenate([u, [-1.0, -1.0]])
        outputs = []
        for function in (kernel_, kernel_.py_func):
            workspace = dense_qp.make_workspace(n, len(u))
            y, multipliers, active = np.zeros(n), np.zeros(len(u)), np.zeros(n, dtype=np.int64)
            settings = DenseQpSettings()
            result = function(
                H, f, C, u, settings.prox_weight, settings.primal_tolerance, settings.dual_tolerance,
                settings.stationarity_tolerance, settings.max_iterations, y, multipliers, active, 0,
                workspace.matrices, workspace.transposed, workspace.vectors, workspace.integers,
            )  # fmt: skip
            outputs.append((result, y, multipliers, active[: result[1]]))
        (compiled, y_c, lam_c, active_c), (reference, y_r, lam_r, active_r) = outputs
        assert compiled == reference
        np.testing.assert_array_equal(active_c, active_r)
        np.testing.assert_allclose(y_c, y_r, rtol=1e-12, atol=1e-12)
        np.testing.assert_allclose(lam_c, lam_r, rtol=1e-10, atol=1e-12)
        statuses.add(compiled[0])
    assert statuses == {OPTIMAL, INFEASIBLE}


@kernel
def _solve_twice_from_a_kernel(H, f, C, u, y, multipliers, active, matrices, transposed, vectors, integers):
    """A compiled caller: solves, then solves again warm-started from the first active set."""
    status, q, first = dense_qp.solve_dense_qp_kernel(
        H, f, C, u, 1e-5, 1e-9, 1e-9, 1e-9, 1000, y, multipliers, active, 0, matrices, transposed, vectors, integers
    )
    status, q, second = dense_qp.solve_dense_qp_kernel(
        H, f, C, u, 1e-5, 1e-9, 1e-9, 1e-9, 1000, y, multipliers, active, q, matrices, transposed, vectors, integers
    )
    return status, first, second


def test_the_kernel_is_callable_from_another_kernel():
    rng = np.random.default_rng(RNG_SEED + 10)
    H, f, C, u = random_problem(rng, 12, 20, rank=6, hqp_like=True)
    workspace = dense_qp.make_workspace(20, 40)  # larger than needed: any size up to it works
    y, multipliers, active = np.zeros(12), np.zeros(len(u)), np.zeros(12, dtype=np.int64)
    status, first, second = _solve_twice_from_a_kernel(
        H,
        f,
        C,
        u,
        y,
        multipliers,
        active,
        workspace.matrices,
        workspace.transposed,
        workspace.vectors,
        workspace.integers,
    )
    assert status == OPTIMAL
    assert second <= first
    reference = solve(H, f, C, u)
    assert objective(_Qp(H, f, C, u), y) == pytest.approx(objective(_Qp(H, f, C, u), reference.y), rel=1e-9, abs=1e-12)


def test_it_runs_as_plain_python_without_numba():
    script = textwrap.dedent(
        """
        import numpy as np
        from pedi_drake.runtime import jit
        from pedi_drake.control import dense_qp
        assert not jit.ENABLED
        rng = np.random.default_rng(0)
        A = rng.normal(size=(3, 6))
        H, f = A.T @ A, -A.T @ rng.normal(size=3)
        C, u = rng.normal(size=(8, 6)), rng.uniform(-0.2, 0.5, 8)
        solution = dense_qp.solve(H, f, C, u)
        print(solution.status, *solution.y)
        """
    )
    environment = dict(os.environ, PEDI_DRAKE_JIT="0")
    output = subprocess.run([sys.executable, "-c", script], env=environment, capture_output=True, text=True, check=True)
    status, *y = output.stdout.split()
    rng = np.random.default_rng(0)
    A = rng.normal(size=(3, 6))
    H, f = A.T @ A, -A.T @ rng.normal(size=3)
    C, u = rng.normal(size=(8, 6)), rng.uniform(-0.2, 0.5, 8)
    compiled = solve(H, f, C, u)
    assert int(status) == compiled.status == OPTIMAL
    np.testing.assert_allclose([float(v) for v in y], compiled.y, rtol=1e-10, atol=1e-12)


@pytest.fixture(scope="module")
def controller_qps():
    return load_qps(DEFAULT_FIXTURE)


def test_the_fixture_holds_a_few_hundred_qps_of_every_level(controller_qps):
    assert len(controller_qps) >= 200
    levels = {(qp.mission, qp.level) for qp in controller_qps}
    assert {mission for mission, _ in levels} == {"hit_target_front", "prong_push_box"}
    assert len(levels) >= 6


def test_recorded_controller_qps_are_solved_to_daqp_s_solution(controller_qps):
    """Every recorded level QP: KKT conditions, DAQP's optimal value, and DAQP's solution within
    1e-6 of its scale where the solution is unique (DAQP run to eta_prox = 1e-12; the controller's
    DAQP, with its default proximal tolerance, is itself only within about 1e-4 of it)."""
    unique = 0
    for index, qp in enumerate(controller_qps):
        solution = solve(qp.H, qp.f, qp.C, qp.u, DenseQpSettings(prox_weight=1e-5))
        assert_kkt(qp.H, qp.f, qp.C, qp.u, solution)
        y_ref, flag = daqp_reference(qp.H, qp.f, qp.C, qp.u)
        assert flag in DAQP_OPTIMAL
        scale = max(1.0, np.abs(y_ref).max())
        for reference in (y_ref, qp.y_daqp):
            assert objective(qp, solution.y) <= objective(qp, reference) + 1e-12 * scale, index
        assert objective(qp, solution.y) == pytest.approx(objective(qp, qp.y_daqp), rel=1e-6, abs=1e-9 * scale)
        if solution_is_unique(qp, solution.y, solution.multipliers):
            unique += 1
            assert np.abs(solution.y - y_ref).max() <= 1e-6 * scale, (index, qp.level)
            assert np.abs(solution.y - qp.y_daqp).max() <= 1e-4 * scale, (index, qp.level)
    assert unique >= 50


def test_a_proximal_weight_far_above_the_curvature_changes_neither_solution_nor_much_the_count():
    """eps = 100 puts H (eigenvalues 0 to about 50) far below the proximal weight in most
    directions, where proximal steps alone move a small fraction of the way each: the primal steps
    to each face's minimiser (or along a descent ray) keep the count small, and the exact step
    makes the solution the same as with eps = 1e-5 (the controller's, and DAQP's here)."""
    rng = np.random.default_rng(RNG_SEED + 11)
    for k in range(60):
        n = int(rng.integers(6, 30))
        H, f, C, u = random_problem(
            rng, n, int(rng.integers(10, 60)), rank=int(rng.integers(0, n)), hqp_like=k % 2 == 0
        )
        solution = solve(H, f, C, u, DenseQpSettings(prox_weight=100.0))
        assert_kkt(H, f, C, u, solution)
        assert solution.iterations <= 2 * (n + len(u)), k
        y_ref, _ = daqp_reference(H, f, C, u)
        scale = max(1.0, np.abs(y_ref).max())
        qp = _Qp(H, f, C, u)
        assert objective(qp, solution.y) == pytest.approx(objective(qp, y_ref), rel=1e-7, abs=1e-9 * scale), k
