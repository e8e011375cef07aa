"""Constrained FABRIK: against the closed-form oracle and the Drake plant's forward kinematics."""

import statistics
import time

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from test_ik_analytic import LIMITS, plant_foot_B

from pedi_drake import robot
from pedi_drake.exceptions import PediError
from pedi_drake.ik import LegIkResult, extended_leg_q, leg_ik_solutions, solve_leg_ik
from pedi_drake.ik.analytic import leg_chain
from pedi_drake.leg_kinematics import foot_position_B

unit = st.floats(0.0, 1.0)


@settings(max_examples=400, derandomize=True, deadline=None)
@given(leg=st.sampled_from(robot.LEG_NAMES), u=st.tuples(unit, unit, unit), start=st.sampled_from(["ext", "stand"]))
def test_reaches_every_reachable_target_within_1mm(leg, u, start):
    lo, hi = LIMITS[leg]
    p = foot_position_B(leg, lo + np.array(u) * (hi - lo))
    assert leg_ik_solutions(leg, p)  # reachable by construction, as the oracle confirms
    q_init = extended_leg_q(leg) if start == "ext" else robot.STANDING_Q[robot.leg_slice(leg)]
    result = solve_leg_ik(leg, p, q_init, tol=1e-3)
    assert result.success
    assert result.error <= 1e-3


@settings(max_examples=400, derandomize=True, deadline=None)
@given(leg=st.sampled_from(robot.LEG_NAMES), u=st.tuples(unit, unit, unit), v=st.tuples(unit, unit, unit))
def test_reaches_every_reachable_target_from_any_start_within_limits(leg, u, v):
    lo, hi = LIMITS[leg]
    p = foot_position_B(leg, lo + np.array(u) * (hi - lo))
    result = solve_leg_ik(leg, p, lo + np.array(v) * (hi - lo), tol=1e-3)
    assert result.success


def test_stalled_hip_escapes_by_switching_tangent_or_restarting():
    # Found by fuzzing: the target is 0.5 mm outside the thigh joint's circle about the hip axis
    # and the start has the leg pointing backwards; the compensation phase first holds the hip
    # in a local minimum (hip -0.80 rad, thigh and calf saturated, error 0.138 m).
    p = foot_position_B("FR", np.array([0.412, -0.673, -1.858]))
    result = solve_leg_ik("FR", p, np.array([0.3, 1.595, -1.626]))
    assert result.success


def test_reported_error_matches_drake_plant_fk(go1_plant, rng):
    for leg in robot.LEG_NAMES:
        lo, hi = LIMITS[leg]
        hip = np.array(leg_chain(leg).p_BH)
        for p in hip + rng.uniform(-0.35, 0.35, size=(25, 3)):
            result = solve_leg_ik(leg, p)
            assert abs(np.linalg.norm(plant_foot_B(go1_plant, leg, result.q) - p) - result.error) < 1e-9


def test_solution_agrees_with_the_oracle_in_task_space(rng):
    # The angles may be a different branch; the foot must land where the oracle's does.
    for leg in robot.LEG_NAMES:
        lo, hi = LIMITS[leg]
        for q in rng.uniform(lo, hi, size=(100, 3)):
            p = foot_position_B(leg, q)
            result = solve_leg_ik(leg, p, tol=1e-4)
            oracle = leg_ik_solutions(leg, p)
            assert np.linalg.norm(foot_position_B(leg, result.q) - foot_position_B(leg, oracle[0])) < 1e-4


def test_limits_never_violated_over_thousands_of_random_targets(rng):
    count = 0
    for leg in robot.LEG_NAMES:
        lo, hi = LIMITS[leg]
        hip = np.array(leg_chain(leg).p_BH)
        targets = hip + rng.uniform(-0.7, 0.7, size=(1000, 3))  # most are unreachable
        starts = rng.uniform(lo - 1.0, hi + 1.0, size=(1000, 3))  # starts outside limits get clipped
        for p, q_init in zip(targets, starts, strict=True):
            result = solve_leg_ik(leg, p, q_init)
            assert np.all(result.q >= lo) and np.all(result.q <= hi), (leg, p, q_init, result)
            assert result.success == (result.error <= 1e-3)
            count += 1
    assert count == 4000


def test_unreachable_target_fails_with_the_closest_distance():
    p_HF = np.array([0.0, -0.08, -0.6])
    result = solve_leg_ik("FR", np.array(leg_chain("FR").p_BH) + p_HF)
    assert not result.success
    # The straightest leg within the calf limit ends 2 * 0.213 * cos(0.444) from the thigh joint,
    # so its feet cover a sphere of radius sqrt(0.08^2 + that^2) about the hip: the nearest point
    # to a target straight out from the hip is on that sphere.
    reach = np.hypot(0.08, 2 * 0.213 * np.cos(0.888 / 2))
    assert result.error == pytest.approx(np.linalg.norm(p_HF) - reach, abs=1e-4)


def test_hip_saturates_at_its_limit_for_a_target_beyond_it():
    q = np.array([1.2, 0.9, -1.8])  # hip limit 0.863
    p = foot_position_B("FL", q)
    assert leg_ik_solutions("FL", p) == []
    result = solve_leg_ik("FL", p)
    assert not result.success
    assert result.q[0] == pytest.approx(leg_chain("FL").q_upper[0], abs=1e-12)


def test_target_at_the_calf_limit_is_reached_on_the_limit():
    q = np.array([0.1, 0.3, leg_chain("RR").q_upper[2]])
    result = solve_leg_ik("RR", foot_position_B("RR", q), tol=1e-4)
    assert result.success
    assert result.q[2] <= leg_chain("RR").q_upper[2]


@pytest.mark.parametrize("bad", [np.nan, np.inf, -np.inf])
def test_non_finite_target_gives_success_false(bad):
    q_init = np.array([0.1, 0.8, -1.5])
    result = solve_leg_ik("RL", np.array([0.0, bad, -0.2]), q_init)
    assert isinstance(result, LegIkResult)
    assert not result.success
    assert result.error == np.inf
    assert result.iterations == 0
    np.testing.assert_array_equal(result.q, q_init)


def test_bad_inputs_raise_pedi_error():
    with pytest.raises(PediError):
        solve_leg_ik("XX", np.zeros(3))
    with pytest.raises(PediError):
        solve_leg_ik("FR", np.zeros(2))
    with pytest.raises(PediError):
        solve_leg_ik("FR", np.zeros(3), np.array([0.0, np.nan, -1.0]))


def test_start_already_on_target_takes_no_iterations():
    q = np.array([0.0, 0.9, -1.8])
    result = solve_leg_ik("FR", foot_position_B("FR", q), q)
    assert result.success and result.iterations == 0 and result.error < 1e-12


def test_iteration_budget_is_respected():
    p = np.array(leg_chain("FR").p_BH) + np.array([0.15, -0.08, -0.3])
    result = solve_leg_ik("FR", p, extended_leg_q("FR"), tol=1e-12, max_iterations=1)
    assert result.iterations == 1


def test_extended_start_is_within_limits_and_straightest():
    for leg in robot.LEG_NAMES:
        lo, hi = LIMITS[leg]
        q = extended_leg_q(leg)
        assert np.all(q >= lo) and np.all(q <= hi)
        assert q[2] == hi[2]


def test_median_solve_time_is_below_100_us(rng):
    lo, hi = LIMITS["FR"]
    targets = [foot_position_B("FR", q) for q in rng.uniform(lo, hi, size=(300, 3))]
    times = []
    for p in targets:
        t0 = time.perf_counter()
        solve_leg_ik("FR", p)
        times.append(time.perf_counter() - t0)
    assert statistics.median(times) < 100e-6
