"""Closed-form Go1 leg IK: the oracle of the FABRIK tests, checked against the Drake plant."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from pedi_drake import robot
from pedi_drake.exceptions import UnreachableTarget
from pedi_drake.ik.analytic import leg_chain, leg_ik_solutions, solve_leg_ik_analytic
from pedi_drake.leg_kinematics import foot_position_B

LIMITS = {leg: (np.array(leg_chain(leg).q_lower), np.array(leg_chain(leg).q_upper)) for leg in robot.LEG_NAMES}


def plant_foot_B(go1_plant, leg: str, q_leg: np.ndarray) -> np.ndarray:
    """Foot centre in the trunk frame [m] from the Drake plant (trunk at the world origin)."""
    plant, plant_map = go1_plant
    context = plant.CreateDefaultContext()
    q12 = robot.STANDING_Q.copy()
    q12[robot.leg_slice(leg)] = q_leg
    plant.SetPositions(context, plant_map.full_positions([1, 0, 0, 0], np.zeros(3), q12, plant.num_positions()))
    foot = plant.GetBodyByName(f"{leg}_foot", plant_map.model).body_frame()
    trunk = plant.GetBodyByName(robot.TRUNK_BODY_NAME, plant_map.model).body_frame()
    return plant.CalcPointsPositions(context, foot, np.zeros(3), trunk).ravel()


unit = st.floats(0.0, 1.0)


@settings(max_examples=300, derandomize=True, deadline=None)
@given(leg=st.sampled_from(robot.LEG_NAMES), u=st.tuples(unit, unit, unit))
def test_solutions_include_the_sampled_angles(leg, u):
    lo, hi = LIMITS[leg]
    q = lo + np.array(u) * (hi - lo)
    solutions = leg_ik_solutions(leg, foot_position_B(leg, q))
    assert min(np.max(np.abs(s - q)) for s in solutions) < 1e-8


def test_every_solution_reaches_the_target_per_drake_plant_fk(go1_plant, rng):
    for leg in robot.LEG_NAMES:
        lo, hi = LIMITS[leg]
        for q in rng.uniform(lo, hi, size=(40, 3)):
            p = plant_foot_B(go1_plant, leg, q)
            solutions = leg_ik_solutions(leg, p)
            assert solutions
            for s in solutions:
                assert np.linalg.norm(plant_foot_B(go1_plant, leg, s) - p) < 1e-9


def test_solutions_are_within_limits_for_random_targets(rng):
    for leg in robot.LEG_NAMES:
        lo, hi = LIMITS[leg]
        hip = np.array(leg_chain(leg).p_BH)
        for p in hip + rng.uniform(-0.5, 0.5, size=(500, 3)):
            for s in leg_ik_solutions(leg, p):
                assert np.all(s >= lo) and np.all(s <= hi)


def test_target_beyond_the_leg_is_unreachable():
    p = np.array(leg_chain("FR").p_BH) + np.array([0.0, -0.08, -0.5])  # leg length is 0.426 m
    assert leg_ik_solutions("FR", p) == []
    assert leg_ik_solutions("FR", p, respect_limits=False) == []


def test_target_on_the_hip_axis_is_unreachable():
    # Inside the circle of the 0.08 m lateral offset: no leg plane passes through it.
    p = np.array(leg_chain("FL").p_BH) + np.array([0.2, 0.0, 0.0])
    assert leg_ik_solutions("FL", p, respect_limits=False) == []


def test_target_needing_a_straighter_knee_than_the_calf_limit_is_unreachable_within_limits():
    q = np.array([0.0, 0.15, -0.3])  # calf upper limit is -0.888
    p = foot_position_B("RR", q)
    assert leg_ik_solutions("RR", p) == []
    assert leg_ik_solutions("RR", p, respect_limits=False)


def test_non_finite_target_raises():
    with pytest.raises(UnreachableTarget):
        leg_ik_solutions("FR", np.array([np.nan, 0.0, -0.2]))


def test_nearest_solution_is_selected():
    q = np.array([0.2, 0.8, -1.6])
    p = foot_position_B("FL", q)
    np.testing.assert_allclose(solve_leg_ik_analytic("FL", p, q_near=q + 0.01), q, atol=1e-9)


def test_unreachable_raises_in_the_single_solution_form():
    with pytest.raises(UnreachableTarget):
        solve_leg_ik_analytic("RL", np.array([0.0, 0.0, -2.0]))
