"""The posture optimiser (pedi_drake.suf.posture) against a brute-force grid, its margins, and
its planner in a worker process."""

import dataclasses
import time

import numpy as np
import pytest

from pedi_drake import robot
from pedi_drake.estimation.leg_odometry import foot_kinematics_B
from pedi_drake.exceptions import SufError
from pedi_drake.leg_kinematics import foot_position_B, working_position_B
from pedi_drake.mission.posture_planner import PosturePlanner, PostureRequest, solve_request
from pedi_drake.suf.posture import (
    Posture,
    PostureCase,
    PostureLimits,
    evaluate_posture,
    grid_posture,
    leg_angles,
    optimise_posture,
    polygon_margin,
    posture_box,
)

# The optimiser's SUF may fall below the best point of the grid by at most this fraction [-]:
# the grid's spacing (1.5 cm) is coarser than the search's last step (1.25 mm), so a search that
# finds the grid's best region ends within rounding of it or above it.
GRID_TOLERANCE = 0.01
TARGET_FRONT = (0.447, -0.13, 0.20)  # hit_target_front's target, world [m]
# remove_object_from_back's targets, on the trunk's back (trunk frame) [m], and its roll [rad].
BACK_TARGETS_B = ((0.16, 0.065, 0.10), (-0.14, 0.065, 0.10))
BACK_ROLL = 0.25
ATTITUDE_AND_HEIGHT = ("z", "roll", "pitch", "yaw")


def standing_case(targets=(TARGET_FRONT,), leg="FR", reach_only=()) -> tuple[PostureCase, Posture]:
    """The case of a lift from the standing pose (feet where STANDING_Q puts them, trunk at the
    origin) and the fixed posture: the trunk over the other feet's centroid."""
    feet_B, _ = foot_kinematics_B(robot.STANDING_Q)
    height = robot.FOOT_RADIUS - float(feet_B[:, 2].mean())
    feet_W = feet_B + np.array([0.0, 0.0, height])
    stance = tuple((name, tuple(feet_W[k])) for k, name in enumerate(robot.LEG_NAMES) if name != leg)
    centroid = np.mean([p[:2] for _, p in stance], axis=0)
    case = PostureCase(stance, leg, tuple(targets), reach_only=tuple(reach_only))
    return case, Posture((float(centroid[0]), float(centroid[1]), height), (0.0, 0.0, 0.0))


@pytest.fixture(scope="module")
def small_case():
    """The trunk's x and y only: a 9 x 9 grid over the optimiser's whole box, and the optimiser."""
    case, start = standing_case()
    lower, upper = posture_box(start, PostureLimits())
    grid = grid_posture(case, start, {"x": np.linspace(lower[0], upper[0], 9), "y": np.linspace(lower[1], upper[1], 9)})
    result = optimise_posture(case, start, fixed=ATTITUDE_AND_HEIGHT)
    return case, start, grid, result


def test_the_optimiser_is_never_below_a_feasible_grid_point_by_more_than_the_tolerance(small_case):
    _, _, grid, result = small_case
    feasible = [e for e in grid if e.feasible]
    best = max(feasible, key=lambda e: e.suf)
    print(f"\ngrid best {best.suf:.3f} N ({len(feasible)} of {len(grid)} feasible) at {best.posture}")
    print(f"optimiser {result.best.suf:.3f} N at {result.best.posture} after {result.evaluations} postures")
    assert len(feasible) >= 5  # the case has a feasible region to compare on
    assert result.best.feasible
    assert result.best.suf >= best.suf * (1.0 - GRID_TOLERANCE)


def test_the_optimiser_keeps_the_coordinates_it_is_told_to_and_its_box(small_case):
    _, start, _, result = small_case
    lower, upper = posture_box(start, PostureLimits())
    v = result.best.posture.vector()
    assert np.all(v >= lower - 1e-12) and np.all(v <= upper + 1e-12)
    assert np.array_equal(v[2:], start.vector()[2:])


def test_the_optimal_posture_reaches_every_point_inside_the_margins():
    case, start = standing_case(reach_only=((0.447, -0.13, 0.25),))
    limits = PostureLimits()
    result = optimise_posture(case, start, limits)
    posture = result.best.posture
    X_BW = posture.pose().inverse()
    print(f"\nfixed {result.start.suf:.3f} N, optimal {result.best.suf:.3f} N at {posture}")
    assert result.best.feasible and result.best.suf > result.start.suf
    for leg, p_W in case.stance_W + tuple((case.leg, p) for p in case.targets + case.reach_only):
        p_B = X_BW @ np.asarray(p_W)
        q = leg_angles(leg, p_B, limits.joint_margin)
        assert q is not None
        assert np.all(q >= robot.Q_LOWER[0:3] + limits.joint_margin - 1e-9)
        assert np.all(q <= robot.Q_UPPER[0:3] - limits.joint_margin + 1e-9)
        assert np.linalg.norm(foot_position_B(leg, q) - p_B) < 1e-6
    assert result.best.com_margin >= limits.com_margin


def test_the_lift_keeps_its_working_position_off_the_floor():
    """A low trunk pitched nose-down puts the lift's working position (15 cm below the hip) into
    the ground, where the foot can never arrive: such a posture is refused, and the optimiser,
    free in all six coordinates, keeps it at least lift_height up."""
    case, start = standing_case()
    lifted = dataclasses.replace(case, lift_B=tuple(working_position_B("FR", 0.15)))
    low_pitched = Posture((*start.p_WB[:2], 0.22), (0.0, 0.2, 0.0))
    assert "floor" in evaluate_posture(lifted, low_pitched).reason
    limits = PostureLimits()
    result = optimise_posture(lifted, start, limits)
    height = (result.best.posture.pose() @ np.asarray(lifted.lift_B))[2]
    print(f"\nworking position {1000 * height:.1f} mm up at {result.best.posture}, {result.best.suf:.3f} N")
    assert result.best.feasible and result.best.suf > result.start.suf
    assert height >= limits.lift_height


def test_a_trunk_frame_target_near_a_joint_limit_leaves_the_postures_to_their_own_margins():
    """remove_object_from_back's first target folds FL's calf to within a milliradian of its stop
    whatever the posture (the target rides with the trunk): the rolled fixed posture is feasible,
    and the optimiser finds a better one. The same point as a world target, whose joint angles
    the posture sets, keeps the joint margin: the fixed posture breaks it."""
    limits = PostureLimits()
    first = np.array(BACK_TARGETS_B[0])
    q = leg_angles("FL", first, 0.0)
    fold = q[2] - robot.Q_LOWER[2]  # the calf's distance from its folded stop [rad]
    print(f"\nFL at {first.tolist()} (trunk frame): calf {1000 * fold:.2f} mrad from its stop")
    assert 0.0 <= fold < 1e-3 and leg_angles("FL", first, limits.joint_margin) is None
    case, start = standing_case(targets=BACK_TARGETS_B, leg="FL")
    case = dataclasses.replace(case, frame="trunk", lift_B=tuple(working_position_B("FL", 0.15)))
    rolled = Posture(start.p_WB, (BACK_ROLL, 0.0, 0.0))
    result = optimise_posture(case, rolled, limits, fixed=("roll", "pitch", "yaw"))
    print(f"\nfixed {result.start.suf:.2f} N, optimal {result.best.suf:.2f} N at {result.best.posture}")
    assert result.start.feasible
    assert result.best.feasible and result.best.suf > result.start.suf
    assert result.best.com_margin >= limits.com_margin
    world = dataclasses.replace(
        case, frame="world", targets=tuple(tuple(rolled.pose() @ np.array(p)) for p in BACK_TARGETS_B)
    )
    assert "point 0 out of reach" in evaluate_posture(world, rolled, limits).reason


def test_a_target_out_of_reach_has_no_feasible_posture():
    case, start = standing_case(targets=((0.9, -0.13, 0.20),))
    result = optimise_posture(case, start, fixed=ATTITUDE_AND_HEIGHT)
    assert not result.best.feasible
    assert "out of reach" in result.best.reason


def test_a_bad_case_is_refused():
    case, start = standing_case()
    with pytest.raises(SufError, match="targets"):
        optimise_posture(dataclasses.replace(case, targets=((np.nan, 0.0, 0.2),)), start)
    with pytest.raises(SufError, match="stance_W"):
        optimise_posture(dataclasses.replace(case, leg="FL"), start)
    with pytest.raises(SufError, match="fixed"):
        optimise_posture(case, start, fixed=("height",))


def test_the_polygon_margin_is_the_distance_to_the_nearest_edge():
    square = np.array([[1.0, 1.0], [-1.0, 1.0], [-1.0, -1.0], [1.0, -1.0]])
    assert polygon_margin(square, np.array([0.0, 0.0])) == pytest.approx(1.0)
    assert polygon_margin(square, np.array([0.5, 0.0])) == pytest.approx(0.5)
    assert polygon_margin(square, np.array([1.5, 0.0])) == pytest.approx(-0.5)


def test_the_planner_answers_as_the_optimiser_does_without_blocking_the_caller():
    case, start = standing_case()
    request = PostureRequest(case, start, fixed=ATTITUDE_AND_HEIGHT)
    planner = PosturePlanner()
    try:
        planner.ask(request)
        started = time.perf_counter()
        early = planner.answer(request, wait=False)  # the solve takes hundreds of milliseconds
        polled = time.perf_counter() - started
        answer = planner.answer(request, wait=True)
    finally:
        planner.close()
    direct = solve_request(request)
    assert early is None and polled < 0.01
    assert answer.best == direct.best
    assert evaluate_posture(case, answer.best.posture).suf == pytest.approx(answer.best.suf)


def test_every_coordinate_does_at_least_as_well_as_the_trunk_shift_alone(small_case):
    case, start, _, planar = small_case
    full = optimise_posture(case, start)
    print(f"\nx, y only {planar.best.suf:.3f} N; all six {full.best.suf:.3f} N at {full.best.posture}")
    assert full.best.feasible
    assert full.best.suf >= planar.best.suf
