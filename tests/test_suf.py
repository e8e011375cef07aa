"""SUF analysis: the five methods on an analytic case, their ordering on the Go1, the exact
polytope against the feasibility LP, and clear errors for bad problems."""

import math

import numpy as np
import pytest
from scipy.optimize import linprog

from pedi_drake.exceptions import SufError
from pedi_drake.friction import friction_pyramid_rows
from pedi_drake.suf.methods import METHODS, fibonacci_sphere, smallest_unrejectable_force
from pedi_drake.suf.problem import RejectableForceProblem
from pedi_drake.suf.ray_program import RfpLinearProgram
from pedi_drake.suf.stances import (
    Go1Stance,
    prong_manipulation_stance,
    stance_problem,
    teleoperation_stance,
    with_prongs_at_height,
)

MASS, G, MU = 2.0, 9.81, 0.5


def point_mass_on_one_contact() -> RejectableForceProblem:
    """A point mass on one frictional contact, pushed by F: lambda + F = (0, 0, m g).

    With the paper's inscribed pyramid (slope s = mu sqrt(2)/2) its RFP is the inverted pyramid
    F_z <= m g, |F_x|, |F_y| <= s (m g - F_z), so the SUF is the distance from the origin to a
    side face, s m g / sqrt(1 + s^2), the worst force sideways and up; along +x alone the largest
    force is s m g.
    """
    weight = np.array([0.0, 0.0, MASS * G])
    pyramid = friction_pyramid_rows(MU)
    return RejectableForceProblem(
        contact_names=("contact",),
        end_effector="mass",
        mu=MU,
        A_eq=np.hstack([np.eye(3), np.eye(3)]),
        b_eq=weight,
        A_in=np.hstack([np.zeros((5, 3)), pyramid]),
        b_in=np.zeros(5),
        W=np.eye(3),
        Je_T=np.eye(3),
        b=weight,
        G_y=pyramid,
        g_y=np.zeros(5),
        p_WE=np.zeros(3),
        torque_limits=np.zeros(0),
    )


SLOPE = MU * math.sqrt(2.0) / 2.0  # the inscribed pyramid's |lambda_x| / lambda_z (paper Eqs. 3-4)
POINT_MASS_SUF = SLOPE * MASS * G / math.sqrt(1.0 + SLOPE**2)


@pytest.mark.parametrize("method", ["exact", "fibonacci", "affine", "quadratic"])
def test_each_method_finds_the_point_mass_pyramid_suf(method):
    result = smallest_unrejectable_force(point_mass_on_one_contact(), method)
    tolerance = 0.02 if method == "fibonacci" else 1e-3
    assert result.value == pytest.approx(POINT_MASS_SUF, rel=tolerance)
    assert result.value <= POINT_MASS_SUF * (1 + 1e-4)  # conservative
    # The worst force pushes sideways and lifts (a side face's outward normal).
    assert result.direction[2] == pytest.approx(SLOPE / math.sqrt(1 + SLOPE**2), abs=0.05)


def test_single_direction_is_the_ray_length_and_overestimates():
    result = smallest_unrejectable_force(point_mass_on_one_contact(), "single", direction=(1.0, 0.0, 0.0))
    assert result.value == pytest.approx(SLOPE * MASS * G, rel=1e-6)
    assert result.value > POINT_MASS_SUF and not result.conservative


def test_fibonacci_directions_are_unit_and_spread():
    d = fibonacci_sphere(1024)
    np.testing.assert_allclose(np.linalg.norm(d, axis=1), 1.0)
    assert np.all(np.abs(d.mean(axis=0)) < 0.01)


@pytest.fixture(scope="module", params=["teleoperation", "prong_manipulation"])
def go1_results(request):
    stance = teleoperation_stance() if request.param == "teleoperation" else prong_manipulation_stance()
    problem = stance_problem(stance)
    return problem, {m: smallest_unrejectable_force(problem, m) for m in METHODS}


def test_approximations_never_exceed_exact(go1_results):
    _, results = go1_results
    exact = results["exact"].value
    assert exact > 1.0
    for method in ("fibonacci", "affine", "quadratic"):
        assert results[method].value <= exact + 1e-3, method
    assert results["affine"].value <= results["quadratic"].value + 1e-3
    assert results["single"].value >= exact - 1e-3


def test_fibonacci_and_quadratic_are_within_2_percent_of_exact(go1_results):
    _, results = go1_results
    exact = results["exact"].value
    assert results["fibonacci"].value >= 0.98 * exact
    assert results["quadratic"].value >= 0.98 * exact
    assert results["affine"].value >= 0.90 * exact


def test_exact_polytope_separates_rejectable_from_unrejectable_forces(go1_results, rng):
    problem, results = go1_results
    polytope = results["exact"].polytope
    lp = RfpLinearProgram(problem)
    for _ in range(10):
        # Inside: a random convex combination of vertices, pulled 1% towards the origin.
        weights = rng.dirichlet(np.ones(len(polytope.vertices)))
        inside = 0.99 * weights @ polytope.vertices
        assert lp.feasible(inside), inside
        # Outside: 1% beyond the polytope's boundary along a random direction.
        d = rng.normal(size=3)
        d /= np.linalg.norm(d)
        reach = min(b / (a @ d) for a, b in zip(polytope.A, polytope.b, strict=True) if a @ d > 1e-12)
        assert lp.feasible(0.99 * reach * d)
        assert not lp.feasible(1.01 * reach * d)


def test_the_worst_force_lies_on_the_exact_boundary(go1_results):
    problem, results = go1_results
    exact = results["exact"]
    lp = RfpLinearProgram(problem)
    assert lp.ray(exact.direction) == pytest.approx(exact.value, rel=1e-3)


def test_a_problem_without_contacts_is_refused():
    with pytest.raises(SufError, match="at least one contact"):
        stance_problem(Go1Stance(0.27, contacts=()))


def test_a_singular_configuration_is_named():
    # One stance foot cannot produce every generalised force: W has rank below 18.
    problem = stance_problem(Go1Stance(0.27, contacts=("RL",), end_effector="FR"))
    with pytest.raises(SufError, match="singular configuration"):
        smallest_unrejectable_force(problem, "affine")


def test_an_infeasible_nominal_acceleration_is_named():
    stance = teleoperation_stance()
    problem = stance_problem(stance, qdd_desired=np.r_[np.zeros(3), [0.0, 0.0, 200.0], np.zeros(12)])
    with pytest.raises(SufError, match="nominal motion is not feasible"):
        smallest_unrejectable_force(problem, "single")


def test_unknown_method_lists_the_methods():
    with pytest.raises(SufError, match="exact"):
        smallest_unrejectable_force(point_mass_on_one_contact(), "bogus")


def test_unreachable_stance_is_named():
    with pytest.raises(SufError, match="out of reach"):
        stance_problem(teleoperation_stance(trunk_height=0.6))


def one_affine_law_meets(problem: RejectableForceProblem, forces: np.ndarray) -> bool:
    """Whether some affine law y(F) = y0 + Y F, y = [tau; lambda], meets the dynamics for every F
    (W y0 = b, W Y = -J_e^T) and the torque and friction rows G_y y <= g_y at each of `forces`.

    Written from scratch in (y0, Y), without the null-space reparametrisation, and solved by
    HiGHS: a relaxation of the affine SOCP (finitely many forces instead of the whole ball).
    """
    W, G, g = problem.W, problem.G_y, problem.g_y
    nv, ny = W.shape
    A_eq = np.zeros((4 * nv, 4 * ny))  # variables: y0, then the columns of Y
    for k in range(4):
        A_eq[k * nv : (k + 1) * nv, k * ny : (k + 1) * ny] = W
    b_eq = np.concatenate([problem.b, -problem.Je_T.T.ravel()])
    A_ub = np.vstack([np.hstack([G, F[0] * G, F[1] * G, F[2] * G]) for F in forces])
    b_ub = np.tile(g, len(forces))
    result = linprog(np.zeros(4 * ny), A_ub=A_ub, b_ub=b_ub, A_eq=A_eq, b_eq=b_eq, bounds=(None, None), method="highs")
    assert result.status in (0, 2), result.message
    return result.status == 0


def test_the_affine_gap_in_a_prong_stance_is_a_property_of_affine_laws():
    """Paper Fig. 4: affine laws "slightly underapproximate". In a friction-limited prong stance
    (both prongs and rear feet down, FR foot reaching forward and out) the affine SUF is ~7 %
    below exact, and that is the best any affine law can do, not a weak solve: no single affine
    law handles 200 forces on a sphere 2 % larger than the affine SUF, though each of those forces
    is rejectable on its own (the exact SUF is larger still); 1 % smaller, one law handles them all.
    """
    stance = Go1Stance(0.18, 0.19, 0.155, ("RR", "RL", "prong0", "prong1"), "FR", (0.30, -0.185, -0.21))
    problem = stance_problem(with_prongs_at_height(stance))
    exact = smallest_unrejectable_force(problem, "exact").value
    affine = smallest_unrejectable_force(problem, "affine").value
    quadratic = smallest_unrejectable_force(problem, "quadratic").value
    assert affine < 0.95 * exact  # a real gap in this stance ...
    assert quadratic >= 0.98 * exact  # ... that the same constraint rows, with a richer law, close
    sphere = fibonacci_sphere(200)
    assert one_affine_law_meets(problem, 0.99 * affine * sphere)
    above = 1.02 * affine * sphere
    assert all(RfpLinearProgram(problem).feasible(F) for F in above)
    assert not one_affine_law_meets(problem, above)
