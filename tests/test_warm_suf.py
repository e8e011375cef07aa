"""The warm-started exact SUF equals the cold exact SUF (Drake's CLP and qhull) within 0.1 %, along
a teleoperated path and on random nearby stances; the live SUF builds the same rows from the
state estimate; a spent LP budget falls back to the single-direction SUF and says so."""

import copy
import dataclasses
import math

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from pedi_drake import robot
from pedi_drake.benchmarks.live_suf import teleoperated_path
from pedi_drake.benchmarks.suf import random_stance
from pedi_drake.exceptions import SufError
from pedi_drake.suf import warm_projection as wp
from pedi_drake.suf.live import LiveSuf, LiveSufReading, idle_vector, rfp_rows, without_timing
from pedi_drake.suf.methods import suf_exact, suf_single
from pedi_drake.suf.problem import ContactPoint, build_problem
from pedi_drake.suf.stances import stance_problem, teleoperation_stance

RELATIVE_TOLERANCE = 1e-3  # the floor: equal to the cold exact SUF within 0.1 %


@pytest.fixture(scope="module")
def compiled():
    wp.warm_up()


def _path_problems(steps: int):
    return [stance_problem(stance) for stance in teleoperated_path(steps)]


def test_warm_started_along_a_teleoperated_path_equals_cold_exact(compiled):
    warm, warm_lps, cold_lps = None, [], []
    for problem in _path_problems(40):
        cold = suf_exact(problem)
        result, warm = wp.suf_exact_warm(problem, warm)
        assert result.value == pytest.approx(cold.value, rel=RELATIVE_TOLERANCE)
        assert result.direction @ cold.direction > 0.99 or result.value == pytest.approx(cold.value, rel=1e-6)
        warm_lps.append(result.num_programs)
        cold_lps.append(wp.suf_exact_warm(problem)[0].num_programs)
    # Warm, most configurations need no LP beyond the cheap checks; cold, every one needs twenty.
    assert np.median(warm_lps) < 0.25 * np.median(cold_lps)


def test_the_warm_polytope_is_the_cold_one(compiled):
    problem = stance_problem(teleoperation_stance())
    cold = suf_exact(problem)
    result, _ = wp.suf_exact_warm(problem)
    # Every vertex of one lies on or inside the other (to the certification tolerance).
    for vertices, other in ((result.polytope.vertices, cold.polytope), (cold.polytope.vertices, result.polytope)):
        assert np.all(vertices @ other.A.T <= other.b + 2e-3)


@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(
    seed=st.integers(0, 2**31 - 1),
    scenario=st.sampled_from(["teleoperation", "prong_manipulation"]),
    step_mm=st.floats(0.5, 20.0),
)
def test_warm_started_from_a_random_nearby_stance_equals_cold_exact(compiled, seed, scenario, step_mm):
    rng = np.random.default_rng(seed)
    stance = random_stance(scenario, rng)
    # The same stance with the end-effector foot moved by `step_mm` and the trunk by half of that.
    offset = rng.normal(size=3)
    offset *= step_mm * 1e-3 / np.linalg.norm(offset)
    moved = dataclasses.replace(
        stance,
        end_effector_B=tuple(np.asarray(stance.end_effector_B) + offset),
        trunk_height=stance.trunk_height + 0.5 * offset[2],
    )
    try:
        first, second = stance_problem(stance), stance_problem(moved)
        cold = suf_exact(second)
        _, warm = wp.suf_exact_warm(first)
    except SufError:
        return  # a stance out of reach or unable to stand: nothing to compare
    result, _ = wp.suf_exact_warm(second, warm)
    assert result.value == pytest.approx(cold.value, rel=RELATIVE_TOLERANCE, abs=2e-3)


def test_a_spent_budget_is_reported_not_returned(compiled):
    problem = stance_problem(teleoperation_stance())
    with pytest.raises(SufError, match="did not converge within 5 LPs"):
        wp.suf_exact_warm(problem, max_lps=5)


def test_the_compiled_projection_matches_its_interpreted_reference(compiled):
    problem = stance_problem(teleoperation_stance(trunk_height=0.25))
    G, h, N_F, F0, _ = wp.problem_rows(problem)
    results = []
    for project_within in (wp.project_within, wp.project_within.py_func):
        hull, meta = wp.new_projection_arrays(G.shape[1])
        none = (np.zeros((1, 3)), np.zeros((1, G.shape[1]), np.int64), np.zeros(1, np.int64))
        progress = wp.new_progress()
        status, _ = project_within(G, h, N_F, F0, *none, 0, wp.TOLERANCE, 5000, hull, meta, progress, math.inf)
        assert status == wp.EXACT
        results.append((wp.polytope_of(hull), wp.progress_lps(progress)))
    (compiled_polytope, compiled_lps), (reference_polytope, reference_lps) = results
    assert compiled_lps == reference_lps
    np.testing.assert_allclose(compiled_polytope.b, reference_polytope.b, atol=1e-9)


def _project_in_calls(rows, warm, budget: float, max_lps: int = 5000):
    """(status, LPs, polytope, the work of every call) of a projection done in calls of `budget`."""
    G, h, N_F, F0, _ = rows
    hull, meta = wp.new_projection_arrays(G.shape[1])
    if warm is None:
        directions, active, num_active = np.zeros((1, 3)), np.zeros((1, G.shape[1]), np.int64), np.zeros(1, np.int64)
    else:
        directions, active, num_active = warm.directions, warm.active, warm.num_active
    num_warm = 0 if warm is None else len(warm.directions)
    progress = wp.new_progress()
    works = []
    while True:
        status, work = wp.project_within(
            G, h, N_F, F0, directions, active, num_active, num_warm, wp.TOLERANCE, max_lps, hull, meta, progress, budget
        )
        works.append(work)
        if status != wp.PENDING:
            return status, wp.progress_lps(progress), wp.polytope_of(hull), works


# The most one step is charged: a facet's check, its LP and the point it finds joined to the hull.
LARGEST_STEP = wp.CHECK_WORK + wp.LP_WORK + wp.INSERT_WORK


@pytest.mark.parametrize("budget", [1e-9, 0.5, 3.0])
@pytest.mark.parametrize("start", ["cold", "warm", "out of LPs"])
def test_a_projection_done_in_calls_ends_as_the_one_done_in_one_call(compiled, budget, start):
    stances = teleoperated_path(40)
    rows = wp.problem_rows(stance_problem(stances[12]))
    warm = wp.suf_exact_warm(stance_problem(stances[10]))[1] if start == "warm" else None
    max_lps = 8 if start == "out of LPs" else 5000
    status, lps, polytope, works = _project_in_calls(rows, warm, math.inf, max_lps)
    assert status == (wp.INCOMPLETE if start == "out of LPs" else wp.EXACT) and len(works) == 1
    sliced_status, sliced_lps, sliced, works = _project_in_calls(rows, warm, budget, max_lps)
    assert (sliced_status, sliced_lps) == (status, lps) and len(works) > 1
    np.testing.assert_array_equal(sliced.A, polytope.A)
    np.testing.assert_array_equal(sliced.b, polytope.b)
    np.testing.assert_array_equal(sliced.vertices, polytope.vertices)
    # A call stops at its budget, past it by at most the one step it had started.
    assert max(works) <= budget + LARGEST_STEP + 1e-12


def test_a_finished_projection_does_nothing_more(compiled):
    G, h, N_F, F0, _ = rows = wp.problem_rows(stance_problem(teleoperation_stance()))
    status, lps, _, _ = _project_in_calls(rows, None, math.inf)
    hull, meta = wp.new_projection_arrays(G.shape[1])
    none = (np.zeros((1, 3)), np.zeros((1, G.shape[1]), np.int64), np.zeros(1, np.int64))
    progress = wp.new_progress()
    wp.project_within(G, h, N_F, F0, *none, 0, wp.TOLERANCE, 5000, hull, meta, progress, math.inf)
    again = wp.project_within(G, h, N_F, F0, *none, 0, wp.TOLERANCE, 5000, hull, meta, progress, math.inf)
    assert again == (status, 0.0) and wp.progress_lps(progress) == lps


# The live SUF ---------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def live():
    return LiveSuf(mu=0.6)


def _stance_state(stance):
    base = np.array([1.0, 0.0, 0.0, 0.0, *stance.trunk_xy, stance.trunk_height, *np.zeros(6)])
    return base, stance.joint_angles()


def test_the_live_rows_are_the_problems_rows(live, go1_plant):
    plant, plant_map = go1_plant
    stance = teleoperation_stance()
    base, q = _stance_state(stance)
    # The live contacts in the controller's order (FL, RR, RL), FR the end effector.
    contacts = [ContactPoint(leg, f"{leg}_foot", np.zeros(3)) for leg in ("FL", "RR", "RL")]
    q_plant = plant_map.full_positions(base[0:4], base[4:7], q, plant.num_positions())
    problem = build_problem(plant, q_plant, contacts, ContactPoint("FR", "FR_foot", np.zeros(3)), mu=0.6)
    dynamics = live._dynamics
    out = dynamics.compute(base, q, np.zeros(12))
    rows = rfp_rows(
        out,
        np.array([0.0, 1.0, 1.0, 1.0]),
        0,
        live._pyramid,
        live._limits,
        live._v_actuated,
        live._base_v,
    )
    for mine, theirs in zip(rows, (problem.A_eq, problem.b_eq, problem.A_in, problem.b_in), strict=True):
        np.testing.assert_allclose(mine, theirs, atol=1e-9, rtol=1e-9)


def test_the_live_suf_is_the_exact_suf_of_the_stance_and_its_reach_the_single_direction_one(live, go1_plant):
    stance = teleoperation_stance()
    base, q = _stance_state(stance)
    problem = stance_problem(stance)
    push = np.array([-1.0, 0.0, 0.0])
    vector, warm = live.update(None, idle_vector(), base, q, np.array([0.0, 1.0, 1.0, 1.0]), 0, push)
    reading = LiveSufReading.from_vector(vector)
    assert reading.exact and reading.leg == 0 and warm is not None
    assert reading.value == pytest.approx(suf_exact(problem).value, rel=RELATIVE_TOLERANCE)
    assert reading.reach == pytest.approx(suf_single(problem, push).value, rel=RELATIVE_TOLERANCE)
    # The next update of the same stance, warm: every vertex whose active set determines it (nz
    # rows) is checked without an LP; only a degenerate one (fewer rows) is solved again.
    degenerate = int(np.sum(warm.num_active < warm.nz))
    vector, _ = live.update(warm, vector, base, q, np.array([0.0, 1.0, 1.0, 1.0]), 0, push)
    assert LiveSufReading.from_vector(vector).lps == degenerate and vector[12] == 2
    assert LiveSufReading.from_vector(vector).value == pytest.approx(reading.value, rel=1e-9)


def test_an_update_out_of_budget_uses_the_single_direction_suf_and_counts_it(go1_plant):
    stance = teleoperation_stance()
    base, q = _stance_state(stance)
    problem = stance_problem(stance)
    exact_vector, _ = LiveSuf(mu=0.6).update(None, idle_vector(), base, q, np.array([0, 1, 1, 1.0]), 0, np.zeros(3))
    worst = LiveSufReading.from_vector(exact_vector).direction
    tight = LiveSuf(mu=0.6, max_lps=3)
    push = np.array([0.0, 0.0, 1.0])
    vector, _ = tight.update(None, exact_vector, base, q, np.array([0, 1, 1, 1.0]), 0, push)
    reading = LiveSufReading.from_vector(vector)
    assert reading.status == wp.INCOMPLETE and reading.fallbacks == 1 and reading.updates == 2
    assert reading.reach == pytest.approx(suf_single(problem, push).value, rel=1e-6)
    # The SUF value of that update: the single-direction SUF along the last worst direction.
    assert reading.value == pytest.approx(suf_single(problem, worst).value, rel=1e-6)
    assert reading.value >= LiveSufReading.from_vector(exact_vector).value - 1e-6


def test_a_warm_start_from_another_contact_set_does_not_change_the_suf(live):
    # Three contacts either way, so the warm start's rows have the same shape but other meanings
    # (another foot's pyramid): the projection checks every warm vertex, so the SUF is the cold one.
    stance = teleoperation_stance()
    base, q = _stance_state(stance)
    first, warm = live.update(None, idle_vector(), base, q, np.array([0, 1, 1, 1.0]), 0, np.zeros(3))
    rl = robot.LEG_NAMES.index("RL")
    warm_other, _ = live.update(warm, first, base, q, np.array([1, 1, 1, 0.0]), rl, np.zeros(3))
    cold_other, _ = live.update(None, first, base, q, np.array([1, 1, 1, 0.0]), rl, np.zeros(3))
    warm_reading, cold_reading = LiveSufReading.from_vector(warm_other), LiveSufReading.from_vector(cold_other)
    assert warm_reading.leg == rl and warm_reading.status == cold_reading.status
    assert warm_reading.value == pytest.approx(cold_reading.value, rel=RELATIVE_TOLERANCE, abs=1e-3)


def _live_in_calls(live, work, previous, base, q, contacts, effector, push, budget):
    """The work charged by every call of a live update done in `work` in calls of `budget`."""
    live.start(work, previous, base, q, contacts, effector, push)
    works = [live.advance(work, budget)]
    while work.under_way:
        works.append(live.advance(work, budget))
    return works


@pytest.mark.parametrize("budget", [1e-9, 1.0, 3.0])
def test_live_updates_done_in_calls_give_the_vectors_and_warm_starts_of_one_call(live, budget):
    push, loaded = np.array([-1.0, 0.0, 0.0]), np.array([0.0, 1.0, 1.0, 1.0])
    tight = LiveSuf(mu=0.6, max_lps=8)  # runs out: the single-direction SUF
    work = live.new_workspace()  # its warm start: the last sliced update's
    warm, vector, sliced_vector = None, idle_vector(), idle_vector()
    for k, stance in enumerate(teleoperated_path(40)[:12]):
        base, q = _stance_state(stance)
        solver = tight if k == 6 else live
        if k == 6:
            warm = None  # cold: more LPs than `tight` has
            work.set_warm_start(None)
        vector, warm = solver.update(warm, vector, base, q, loaded, 0, push)
        calls = _live_in_calls(solver, work, sliced_vector, base, q, loaded, 0, push, budget)
        assert not work.under_way and LiveSufReading.from_vector(work.result).slices == len(calls)
        np.testing.assert_array_equal(without_timing(work.result), without_timing(vector))
        sliced_warm = work.warm_start()
        assert (sliced_warm is None) == (warm is None)
        if warm is not None:
            np.testing.assert_array_equal(sliced_warm.directions, warm.directions)
            np.testing.assert_array_equal(sliced_warm.active, warm.active)
        sliced_vector = work.result.copy()
    assert LiveSufReading.from_vector(vector).fallbacks == 1


def test_a_copied_workspace_goes_on_alone(live):
    base, q = _stance_state(teleoperation_stance())
    work = live.new_workspace()
    live.start(work, idle_vector(), base, q, np.array([0.0, 1.0, 1.0, 1.0]), 0, np.zeros(3))
    live.advance(work, 2.0)
    copied = copy.deepcopy(work)
    while work.under_way:
        live.advance(work, 2.0)
    assert copied.under_way and not np.array_equal(copied.progress, work.progress)
    while copied.under_way:
        live.advance(copied, 5.0)
    np.testing.assert_array_equal(without_timing(copied.result), without_timing(work.result))
