"""The hierarchical QP: strict priority against a brute-force sequential solve, and the weighted mode."""

import numpy as np
import pytest
from pydrake.solvers import ClarabelSolver, MathematicalProgram
from reference_hqp import EqualityTask, HqpSettings, InequalityTask, Level, solve_hqp, solve_weighted

from pedi_drake.exceptions import QpInfeasible


def random_levels(rng: np.random.Generator, n: int = 12, num_levels: int = 4) -> list[Level]:
    """Random levels: conflicting equalities, hard inequalities with a common feasible point, soft ones."""
    x_feasible = rng.normal(size=n)
    levels = []
    for k in range(num_levels):
        m = int(rng.integers(2, 5))
        eq = EqualityTask(f"eq{k}", rng.normal(size=(m, n)), rng.normal(size=m) * 3, weight=float(rng.uniform(0.5, 2)))
        Gs = rng.normal(size=(2, n))
        soft = InequalityTask(f"soft{k}", Gs, Gs @ x_feasible - rng.uniform(0.0, 2.0, 2), hard=False)
        inequalities = [soft]
        if k == 0:
            # Hard rows belong to the top level (physical limits); they bind every level below.
            G = rng.normal(size=(6, n))
            inequalities.append(InequalityTask("hard", G, G @ x_feasible + rng.uniform(0.0, 0.5, 6), hard=True))
        levels.append(Level(f"L{k}", [eq], inequalities))
    return levels


def brute_force_sequential(levels: list[Level], n: int) -> list[float]:
    """Optimal cost of each level, each solved in full x by Clarabel with the levels above fixed."""
    fixed_eq, fixed_ineq, hard, costs = [], [], [], []
    for level in levels:
        prog = MathematicalProgram()
        x = prog.NewContinuousVariables(n, "x")
        for A, value in fixed_eq:
            prog.AddLinearConstraint(A, value - 1e-7, value + 1e-7, x)
        for G, h in fixed_ineq + hard + [(t.G, t.h) for t in level.inequalities if t.hard]:
            prog.AddLinearConstraint(G, np.full(len(h), -np.inf), h, x)
        soft = [t for t in level.inequalities if not t.hard]
        ws = []
        for t in soft:
            w = prog.NewContinuousVariables(len(t.h), "w")
            prog.AddLinearConstraint(
                np.hstack([t.G, -np.eye(len(t.h))]), np.full(len(t.h), -np.inf), t.h, np.concatenate([x, w])
            )
            prog.AddQuadraticCost(2 * t.weight * np.eye(len(t.h)), np.zeros(len(t.h)), w)
            ws.append(w)
        for t in level.equalities:
            prog.AddQuadraticCost(2 * t.weight * t.A.T @ t.A, -2 * t.weight * t.A.T @ t.b, x, is_convex=True)
        result = ClarabelSolver().Solve(prog)
        assert result.is_success()
        xs = result.GetSolution(x)
        costs.append(
            sum(t.weight * np.sum((t.A @ xs - t.b) ** 2) for t in level.equalities)
            + sum(t.weight * np.sum(np.maximum(t.G @ xs - t.h, 0) ** 2) for t in soft)
        )
        for t in level.equalities:
            fixed_eq.append((t.A, t.A @ xs))
        for t in soft:
            fixed_ineq.append((t.G, np.maximum(t.G @ xs, t.h) + 1e-7))
        hard += [(t.G, t.h) for t in level.inequalities if t.hard]
    return costs


@pytest.fixture
def settings() -> HqpSettings:
    """The level QPs by DAQP (the default)."""
    return HqpSettings()


def level_cost(level: Level, x: np.ndarray) -> float:
    return sum(t.weight * np.sum((t.A @ x - t.b) ** 2) for t in level.equalities) + sum(
        t.weight * np.sum(np.maximum(t.G @ x - t.h, 0) ** 2) for t in level.inequalities if not t.hard
    )


@pytest.mark.parametrize("seed", range(12))
def test_strict_priority_matches_brute_force_sequential(seed, settings):
    rng = np.random.default_rng(seed)
    n = 12
    levels = random_levels(rng, n)
    solution = solve_hqp(levels, n, settings)
    expected = brute_force_sequential(levels, n)
    for level, cost in zip(levels, expected, strict=True):
        assert level_cost(level, solution.x) == pytest.approx(cost, rel=1e-4, abs=1e-5)
    for level in levels:
        for t in level.inequalities:
            if t.hard:
                assert np.all(t.G @ solution.x - t.h <= 1e-6)


@pytest.mark.parametrize("seed", range(8))
def test_lower_level_never_degrades_a_higher_one(seed, settings):
    rng = np.random.default_rng(100 + seed)
    n = 12
    levels = random_levels(rng, n)
    full = solve_hqp(levels, n, settings)
    for k in range(1, len(levels) + 1):
        truncated = solve_hqp(levels[:k], n, settings)
        assert level_cost(levels[k - 1], full.x) == pytest.approx(
            level_cost(levels[k - 1], truncated.x), rel=1e-5, abs=1e-6
        )


def test_equality_only_levels_match_nullspace_projection():
    rng = np.random.default_rng(7)
    n = 6
    A1, b1 = rng.normal(size=(2, n)), rng.normal(size=2)
    A2, b2 = rng.normal(size=(3, n)), rng.normal(size=3)
    A3, b3 = np.eye(n), np.zeros(n)
    levels = [
        Level("a", [EqualityTask("a", A1, b1)]),
        Level("b", [EqualityTask("b", A2, b2)]),
        Level("c", [EqualityTask("c", A3, b3)]),
    ]
    # Classic recursive null-space projection (Siciliano and Slotine), exact for full-rank rows.
    x1 = np.linalg.pinv(A1) @ b1
    N1 = np.eye(n) - np.linalg.pinv(A1) @ A1
    x2 = x1 + np.linalg.pinv(A2 @ N1, rcond=1e-9) @ (b2 - A2 @ x1)
    N2 = N1 - np.linalg.pinv(A2 @ N1, rcond=1e-9) @ (A2 @ N1)
    x3 = x2 + np.linalg.pinv(A3 @ N2, rcond=1e-9) @ (b3 - A3 @ x2)
    np.testing.assert_allclose(solve_hqp(levels, n).x, x3, atol=1e-6)


def test_redundant_rows_do_not_break_the_solver(settings):
    n = 4
    A = np.array([[1.0, 0, 0, 0], [2.0, 0, 0, 0], [0, 1.0, 0, 0]])
    levels = [
        Level("dup", [EqualityTask("dup", A, np.array([1.0, 2.0, 3.0]))]),
        Level("reg", [EqualityTask("reg", np.eye(n), np.ones(n) * 5)]),
    ]
    x = solve_hqp(levels, n, settings).x
    np.testing.assert_allclose(x, [1.0, 3.0, 5.0, 5.0], atol=1e-6)


def test_infeasible_hard_constraints_raise_qp_infeasible(settings):
    n = 2
    G = np.array([[1.0, 0.0], [-1.0, 0.0]])
    h = np.array([-1.0, -1.0])  # x0 <= -1 and x0 >= 1
    levels = [Level("bad", [EqualityTask("e", np.eye(n), np.zeros(n))], [InequalityTask("box", G, h)])]
    with pytest.raises(QpInfeasible):
        solve_hqp(levels, n, settings)
    with pytest.raises(QpInfeasible):
        solve_weighted(levels, n, [1.0], settings)


def test_soft_inequality_conflict_resolved_by_priority(settings):
    # Level 0 wants x <= -1 (soft), level 1 wants x = 3: strict keeps x = -1, weighted compromises.
    levels = [
        Level("limit", [], [InequalityTask("x<=-1", np.array([[1.0]]), np.array([-1.0]), hard=False)]),
        Level("target", [EqualityTask("x=3", np.array([[1.0]]), np.array([3.0]))]),
    ]
    assert solve_hqp(levels, 1, settings).x[0] == pytest.approx(-1.0, abs=1e-6)
    weighted = solve_weighted(levels, 1, [1.0, 1.0], settings).x[0]
    assert weighted == pytest.approx(1.0, abs=1e-6)  # argmin (x+1)^2 + (x-3)^2
    assert solve_weighted(levels, 1, [1e4, 1.0], settings).x[0] == pytest.approx(-1.0 + 4.0 / 1.0001e4, abs=1e-6)


@pytest.mark.parametrize("seed", range(4))
def test_weighted_mode_matches_brute_force_weighted_qp(seed, settings):
    rng = np.random.default_rng(200 + seed)
    n = 12
    # A last identity level makes the weighted optimum unique, so solutions can be compared.
    levels = random_levels(rng, n, 3) + [Level("reg", [EqualityTask("reg", np.eye(n), np.zeros(n))])]
    weights = [100.0, 10.0, 1.0, 0.01]
    solution = solve_weighted(levels, n, weights, settings)
    prog = MathematicalProgram()
    x = prog.NewContinuousVariables(n, "x")
    for level, weight in zip(levels, weights, strict=True):
        for t in level.equalities:
            prog.AddQuadraticCost(
                2 * weight * t.weight * t.A.T @ t.A, -2 * weight * t.weight * t.A.T @ t.b, x, is_convex=True
            )
        for t in level.inequalities:
            if t.hard:
                prog.AddLinearConstraint(t.G, np.full(len(t.h), -np.inf), t.h, x)
            else:
                w = prog.NewContinuousVariables(len(t.h))
                prog.AddLinearConstraint(
                    np.hstack([t.G, -np.eye(len(t.h))]), np.full(len(t.h), -np.inf), t.h, np.concatenate([x, w])
                )
                prog.AddQuadraticCost(2 * weight * t.weight * np.eye(len(t.h)), np.zeros(len(t.h)), w)
    result = ClarabelSolver().Solve(prog)
    assert result.is_success()
    np.testing.assert_allclose(solution.x, result.GetSolution(x), atol=1e-4)


@pytest.mark.parametrize("target, expected", [(0.5, 0.5), (2.0, 1.0)])
@pytest.mark.parametrize("rows", ["square", "tall"])
def test_an_unconstrained_optimum_is_kept_only_when_it_meets_the_constraints(target, expected, rows, settings):
    # x0 <= 1 (hard) above a target x = (target, 0): inside the bound the least-squares step is the
    # answer (taken without the QP), beyond it the QP stops x0 at the bound. "tall" repeats a row,
    # the shape of the controller's regularisation level (solved by its normal equations).
    A = np.eye(2) if rows == "square" else np.array([[1.0, 0.0], [0.0, 1.0], [1.0, 0.0]])
    b = A @ np.array([target, 0.0])
    levels = [
        Level("bound", [], [InequalityTask("x0<=1", np.array([[1.0, 0.0]]), np.array([1.0]))]),
        Level("target", [EqualityTask("target", A, b)]),
    ]
    np.testing.assert_allclose(solve_hqp(levels, 2, settings).x, [expected, 0.0], atol=1e-6)
