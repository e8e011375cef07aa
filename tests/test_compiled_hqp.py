"""The compiled hierarchical QP (compiled_hqp) against the Python one (hqp) on the same levels.

The levels are shaped like the whole-body stack's: a top level of equalities alone (the
dynamics and the stance feet), a level of hard and soft inequalities with sparse rows (limits
on one or two variables, torque-like rows on a dozen), then equalities on a few rows and a
regularisation of more rows than the null space left has columns.
"""

from pathlib import Path

import numpy as np
import pytest
from reference_hqp import EqualityTask, HqpSettings, InequalityTask, Level, row_table, solve_hqp

from pedi_drake.control import compiled_hqp
from pedi_drake.exceptions import QpInfeasible

N = 30
SETTINGS = HqpSettings()


def sparse_rows(rng: np.random.Generator, rows: int, nonzeros: int) -> np.ndarray:
    """(rows, N) with `nonzeros` random entries a row, the rest exactly zero."""
    M = np.zeros((rows, N))
    for i in range(rows):
        M[i, rng.choice(N, nonzeros, replace=False)] = rng.normal(size=nonzeros)
    return M


def stack_like_levels(rng: np.random.Generator, tight: float, redundant: int = 0) -> list[Level]:
    """Four levels as the whole-body stack builds them, feasible at a random point; `tight`
    (0 to 1) moves the hard bounds onto that point, so more of them bind. `redundant` top-level
    rows are combinations of the others, as a stance on the prongs gives (two contacts on the
    trunk fix one rotation twice): the top level is then rank-deficient."""
    x_feasible = rng.normal(size=N)
    physics = rng.normal(size=(15, N))
    if redundant:
        physics = np.vstack([physics, rng.normal(size=(redundant, 15)) @ physics])
    limits = np.vstack([sparse_rows(rng, 24, 1), sparse_rows(rng, 24, 2), sparse_rows(rng, 12, 12)])
    limits = np.vstack([limits, -limits[-12:]])
    slack = rng.uniform(0.0, 1.0, len(limits)) * (1.0 - tight)
    soft = rng.normal(size=(3, N))
    return [
        Level("physics", [EqualityTask("dynamics", physics, physics @ x_feasible)], []),
        Level(
            "feasibility",
            [],
            [
                InequalityTask("limits", limits, limits @ x_feasible + slack, hard=True),
                InequalityTask("capture point", soft, soft @ x_feasible - rng.uniform(0.0, 1.0, 3), hard=False),
            ],
        ),
        Level("pose", [EqualityTask("pose", rng.normal(size=(9, N)), rng.normal(size=9) * 3)], []),
        Level("regularisation", [EqualityTask("small", sparse_rows(rng, 36, 1), np.zeros(36), weight=1e-3)], []),
    ]


@pytest.mark.parametrize("seed", range(20))
@pytest.mark.parametrize("tight", [0.0, 0.9])
@pytest.mark.parametrize("redundant", [0, 2])
def test_strict_solve_equals_the_python_reference(seed, tight, redundant):
    levels = stack_like_levels(np.random.default_rng(seed), tight, redundant)
    expected = solve_hqp(levels, N, SETTINGS)
    status, x, residuals = compiled_hqp.solve_table_strict(row_table(levels, N), SETTINGS)
    assert status == compiled_hqp.STATUS_OK
    np.testing.assert_allclose(x, expected.x, rtol=0, atol=1e-8 * max(1.0, np.abs(expected.x).max()))
    np.testing.assert_allclose(residuals, expected.equality_residuals, rtol=1e-8, atol=1e-9)


def test_random_dense_levels_equal_the_python_reference():
    rng = np.random.default_rng(7)
    for _ in range(20):
        n = int(rng.integers(4, 16))
        levels = []
        for k in range(4):
            m = int(rng.integers(0, n + 3))
            A = rng.normal(size=(m, n))
            inequalities = []
            if k == 1:
                G = rng.normal(size=(5, n))
                inequalities.append(InequalityTask("hard", G, G @ rng.normal(size=n) + 0.5, hard=True))
            levels.append(Level(f"L{k}", [EqualityTask(f"eq{k}", A, rng.normal(size=m))], inequalities))
        try:
            expected = solve_hqp(levels, n, SETTINGS)
        except QpInfeasible:
            continue
        status, x, _ = compiled_hqp.solve_table_strict(row_table(levels, n), SETTINGS)
        assert status == compiled_hqp.STATUS_OK
        np.testing.assert_allclose(x, expected.x, rtol=0, atol=1e-8 * max(1.0, np.abs(expected.x).max()))


def test_infeasible_hard_rows_are_reported():
    G = np.zeros((2, N))
    G[0, 3], G[1, 3] = 1.0, -1.0
    levels = [
        Level("physics", [EqualityTask("pin", np.eye(N)[:2], np.ones(2))], []),
        Level("limits", [], [InequalityTask("contradiction", G, np.array([-1.0, -1.0]), hard=True)]),
        Level("pose", [EqualityTask("pose", np.eye(N)[4:6], np.ones(2))], []),
    ]
    with pytest.raises(QpInfeasible):
        solve_hqp(levels, N, SETTINGS)
    status, _, _ = compiled_hqp.solve_table_strict(row_table(levels, N), SETTINGS)
    assert status == compiled_hqp.STATUS_INFEASIBLE


def test_the_split_finds_the_rank_the_null_space_and_the_least_norm_step():
    rng = np.random.default_rng(11)
    for m, deficiency in ((6, 0), (18, 0), (6, 1), (18, 1), (21, 3), (24, 24), (40, 12)):
        A = rng.normal(size=(m - deficiency, N))
        A = np.vstack([A, rng.normal(size=(deficiency, m - deficiency)) @ A]) if m > deficiency else np.zeros((m, N))
        rank, kind, Y, Nb, R, order, U, sigma = compiled_hqp._row_space_split(A, 1e-9)
        assert rank == np.linalg.matrix_rank(A) == min(m, N) - max(0, deficiency - max(0, m - N))
        if m > N:
            assert kind == compiled_hqp.SPLIT_SVD
        else:
            assert kind == (compiled_hqp.SPLIT_FULL_RANK if deficiency == 0 else compiled_hqp.SPLIT_PIVOTED)
        scale = max(1.0, np.abs(A).max())
        np.testing.assert_allclose(A @ Nb, 0.0, atol=1e-12 * scale)
        basis = np.hstack([Y, Nb])
        np.testing.assert_allclose(basis.T @ basis, np.eye(N), atol=1e-12)
        # The least-norm least-squares step, against numpy's (an SVD).
        r = rng.normal(size=m)
        z = np.empty(N)
        compiled_hqp._min_norm_least_squares(r, rank, kind, Y, R, order, U, sigma, z)
        np.testing.assert_allclose(z, np.linalg.lstsq(A, r, rcond=None)[0], atol=1e-9)


def test_a_level_the_levels_above_already_fix_takes_no_step():
    """A level whose rows lie in the span of the levels above (here, a combination of the top
    level's rows asking for another value) has rank 0 in their null space: both solvers leave x
    where the levels above put it, rather than solving for the rows' rounding noise."""
    rng = np.random.default_rng(12)
    top = rng.normal(size=(15, N))
    combination = rng.normal(size=(3, 15)) @ top
    levels = [
        Level("physics", [EqualityTask("dynamics", top, rng.normal(size=15))], []),
        Level("repeat", [EqualityTask("conflicting", combination, rng.normal(size=3))], []),
        Level("pose", [EqualityTask("pose", rng.normal(size=(6, N)), rng.normal(size=6))], []),
    ]
    without = [levels[0], levels[2]]
    expected = solve_hqp(without, N, SETTINGS)
    for solution in (
        solve_hqp(levels, N, SETTINGS).x,
        compiled_hqp.solve_table_strict(row_table(levels, N), SETTINGS)[1],
    ):
        np.testing.assert_allclose(solution, expected.x, rtol=0, atol=1e-9)


def test_redundant_contact_rows_are_found_rank_deficient_as_the_svd_finds_them():
    # The paper003 stack of a real tick with six loaded contacts (four feet, two prongs at the
    # trunk's ends) as the FR foot starts to unload: its first level's 24 rows have rank 23 (a
    # singular value of 3e-17), yet an unpivoted QR leaves 1.9e-8 on its diagonal. Taken as full
    # rank, the minimum-norm step was 8e6 long and the next level's QP infeasible.
    recorded = np.load(Path(__file__).parent / "fixtures" / "hqp_redundant_prong_contacts.npz")
    n = int(recorded["n"])
    A = recorded["eq_A"][: recorded["eq_start"][1]]
    rank, *_ = compiled_hqp._row_space_split(A, float(recorded["rank_tolerance"]))
    singular = np.linalg.svd(A, compute_uv=False)
    assert rank == np.sum(singular > float(recorded["rank_tolerance"]) * singular[0]) == 23
    table = compiled_hqp.RowTable(
        n,
        *(recorded[f] for f in ("eq_A", "eq_b", "eq_start", "hard_G", "hard_h", "hard_start")),
        *(recorded[f] for f in ("soft_G", "soft_h", "soft_w", "soft_start")),
    )
    settings = HqpSettings(
        proximal_weight=float(recorded["proximal_weight"]),
        rank_tolerance=float(recorded["rank_tolerance"]),
        fix_tolerance=float(recorded["fix_tolerance"]),
    )
    status, x, _ = compiled_hqp.solve_table_strict(table, settings)
    assert status == compiled_hqp.STATUS_OK
    np.testing.assert_allclose(x, recorded["x"], atol=1e-8)  # the Python reference's solution
