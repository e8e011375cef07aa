"""A mission's optimal lift as its phases run it (no simulation: the phase runners on hand-made
views): trunk-frame targets that stay fixed in the world are reached at the same world point
whatever posture the optimiser picks, and a lift with no feasible posture falls back to the fixed
posture in a mission but fails (the target is refused) in the semi-autonomous mode."""

import dataclasses
from pathlib import Path

import numpy as np
import pytest
from pydrake.math import RigidTransform, RollPitchYaw

from pedi_drake import robot
from pedi_drake.estimation.base_state import BaseState
from pedi_drake.estimation.leg_odometry import foot_kinematics_B
from pedi_drake.exceptions import UnreachableTarget
from pedi_drake.mission.phases import (
    LegToPedipulationRunner,
    MissionEnvironment,
    PedipulationLift,
    ReachRunner,
    posture_request,
    target_anchor,
)
from pedi_drake.mission.posture_planner import PLAN_LATENCY, PLAN_WAIT_LIMIT, solve_request
from pedi_drake.mission.progress import (
    FAILED,
    LEG_MODE_JOINTS,
    RUNNING,
    LegTrajectory,
    MissionProgress,
    PhaseRecord,
    References,
)
from pedi_drake.mission.robot_view import RobotView
from pedi_drake.mission.semi_autonomous import target_sequence
from pedi_drake.mission.spec import SemiAutonomousMode, load_mission
from pedi_drake.suf.posture import leg_angles
from pedi_drake.trajectory import PiecewiseQuintic

# give_paw's offer: the trunk pitched nose-up before the lift, the paw's target in the trunk frame [m].
PITCH = -0.12  # [rad]
OFFER_B = (0.35, -0.13, -0.03)
APPROACH = (-0.04, 0.0, 0.0)
HEIGHT = 0.28  # [m]


def _paw_mission(tmp_path: Path, trunk_targets: str):
    path = tmp_path / "paw.yaml"
    path.write_text(
        "phases:\n"
        "  - {kind: stand_up}\n"
        f"  - {{kind: body_rotate, rpy: [0.0, {PITCH}, 0.0]}}\n"
        f"  - {{kind: leg_to_pedipulation, leg: FR, posture: optimal, trunk_targets: {trunk_targets}, timeout: 8.0}}\n"
        f"  - {{kind: reach, name: offer, leg: FR, target: {list(OFFER_B)}, frame: trunk, "
        f"approach_offset: {list(APPROACH)}}}\n"
        "  - {kind: leg_to_support, leg: FR}\n"
    )
    return load_mission(str(path))


def _feet_on_the_ground() -> np.ndarray:
    """(4, 3) the feet where the standing pose puts them, on the ground, world [m]."""
    feet_B, _ = foot_kinematics_B(robot.STANDING_Q)
    return feet_B + np.array([0.0, 0.0, robot.FOOT_RADIUS - float(feet_B[:, 2].mean())])


def _view(X_WB: RigidTransform, feet_W: np.ndarray, lifted_B: dict[str, np.ndarray] | None = None) -> RobotView:
    """The robot with its trunk at X_WB and its feet at `feet_W` (world) or, for the legs in
    `lifted_B`, at those trunk-frame points: joint angles by the closed-form IK."""
    X_BW = X_WB.inverse()
    q = robot.STANDING_Q.copy()
    for k, leg in enumerate(robot.LEG_NAMES):
        p_B = (lifted_B or {}).get(leg, X_BW @ feet_W[k])
        angles = leg_angles(leg, np.asarray(p_B, float), 0.0)
        assert angles is not None, f"{leg} cannot stand at {p_B}"
        q[robot.leg_slice(leg)] = angles
    base = BaseState(X_WB.rotation().ToQuaternion().wxyz(), X_WB.translation(), np.zeros(3), np.zeros(3))
    zeros = np.zeros(12)
    return RobotView(0.0, base, q, zeros, zeros, np.full(4, 30.0))


@pytest.fixture(scope="module")
def paw_plan(tmp_path_factory):
    """The optimal lift of a give_paw-like mission planned from a pitched standing pose: the
    mission, its request, the optimiser's answer and the anchor of its trunk-frame targets."""
    mission = _paw_mission(tmp_path_factory.mktemp("paw"), "world")
    lift = mission.phases[2]
    X_WB = RigidTransform(RollPitchYaw(0.0, PITCH, 0.0), [0.0, 0.0, HEIGHT])
    feet_W = _feet_on_the_ground()
    view = _view(X_WB, feet_W)
    # The fixed posture: the trunk over the centroid of the other feet (the CoM about there).
    p_fixed = np.array([*feet_W[1:, :2].mean(axis=0), HEIGHT])
    request = posture_request(lift, view, MissionEnvironment(None), np.ones(4), p_fixed, X_WB.rotation())
    return mission, request, solve_request(request), target_anchor(lift, request.start)


def test_trunk_frame_targets_go_to_the_optimiser_as_their_world_points_at_the_fixed_posture(paw_plan):
    _, request, _, anchor = paw_plan
    X_fixed = request.start.pose()
    assert anchor is not None and np.allclose(anchor.GetAsMatrix4(), X_fixed.GetAsMatrix4())
    assert request.case.frame == "world"
    np.testing.assert_allclose(request.case.targets[0], X_fixed @ np.array(OFFER_B), atol=1e-12)
    np.testing.assert_allclose(request.case.reach_only[0], X_fixed @ (np.add(OFFER_B, APPROACH)), atol=1e-12)


def test_the_reach_after_an_optimal_posture_aims_at_the_world_point_of_the_fixed_posture(paw_plan):
    mission, request, result, anchor = paw_plan
    optimal = result.best.posture
    X_opt = optimal.pose()
    print(f"\nfixed {result.start.suf:.2f} N at {request.start}\noptimal {result.best.suf:.2f} N at {optimal}")
    assert result.best.feasible and result.best.suf > result.start.suf
    p_W = anchor @ np.array(OFFER_B)
    # What the bug did: the trunk-frame target taken at the optimal posture is elsewhere.
    assert np.linalg.norm(X_opt @ np.array(OFFER_B) - p_W) > 0.01
    # The reach with the trunk at the optimal posture (the foot lifted to the working position).
    stance = _feet_on_the_ground()
    view = _view(X_opt, stance, {"FR": np.array([0.19, -0.13, -0.12])})
    t = 0.0
    references = References.holding(X_opt.translation(), X_opt.rotation(), t, 0)
    hold = PiecewiseQuintic.through(np.array([view.leg_q("FR")] * 2), t, [1e-3])
    references.legs["FR"] = LegTrajectory(LEG_MODE_JOINTS, hold)
    progress = MissionProgress(references=references, target_anchors={"FR": anchor})
    reach = mission.phases[3]
    ReachRunner().start(reach, progress, view, MissionEnvironment(None))
    np.testing.assert_allclose(progress.memo["target_W"], p_W, atol=1e-12)
    approach_B, target_B = progress.ik.targets_B["FR"]
    np.testing.assert_allclose(X_opt @ target_B, p_W, atol=1e-12)
    np.testing.assert_allclose(X_opt @ approach_B, anchor @ np.add(OFFER_B, APPROACH), atol=1e-12)
    # The optimiser's answer reaches that very point inside its margins.
    assert leg_angles("FR", target_B, request.limits.joint_margin) is not None


def test_targets_on_the_trunk_move_with_the_posture(tmp_path):
    mission = _paw_mission(tmp_path, "trunk")
    lift = mission.phases[2]
    X_WB = RigidTransform(RollPitchYaw(0.0, PITCH, 0.0), [0.0, 0.0, HEIGHT])
    view = _view(X_WB, _feet_on_the_ground())
    request = posture_request(lift, view, MissionEnvironment(None), np.ones(4), X_WB.translation(), X_WB.rotation())
    assert target_anchor(lift, request.start) is None
    assert request.case.frame == "trunk" and request.case.targets == (OFFER_B,)


class _InfeasiblePlanner:
    """Answers every request with the optimiser's verdict on a target no posture reaches."""

    def __init__(self, request):
        far = dataclasses.replace(request.case, targets=((0.9, -0.13, 0.2),), reach_only=())
        self.result = solve_request(dataclasses.replace(request, case=far, fixed=("z", "roll", "pitch", "yaw")))

    def answer(self, request, *, wait):
        return self.result


def _planning_lift(lift, request, planner):
    """A lift phase in its planning stage, the trunk held at the start posture's attitude."""
    X_WB = RigidTransform(RollPitchYaw(0.0, PITCH, 0.0), [0.0, 0.0, HEIGHT])
    view = _view(X_WB, _feet_on_the_ground())
    progress = MissionProgress(references=References.holding(X_WB.translation(), X_WB.rotation(), 0.0, 0))
    progress.records.append(_record(lift.name))
    progress.memo["lift"] = PedipulationLift("plan", 0.0, request=request)
    env = MissionEnvironment(None, planner=planner)
    return progress, view, env


def _record(name: str) -> PhaseRecord:
    return PhaseRecord(name=name, kind="leg_to_pedipulation", status=RUNNING, t_start=0.0)


def test_a_mission_lift_with_no_feasible_posture_takes_the_fixed_one(paw_plan):
    mission, request, _, _ = paw_plan
    lift = mission.phases[2]
    planner = _InfeasiblePlanner(request)
    assert not planner.result.best.feasible
    progress, view, env = _planning_lift(lift, request, planner)
    assert LegToPedipulationRunner().step(lift, progress, view, env) == RUNNING
    posture = progress.records[-1].metrics["posture"]
    assert posture["taken"] == "fixed" and "the fixed posture is taken" in posture["fallback"]
    assert progress.memo["lift"].stage == "shift"
    # The trunk goes to the fixed posture's position; no anchor: the reach uses the trunk as it is.
    end = progress.references.body_position.sample(10.0).position
    np.testing.assert_allclose(end, request.start.p_WB, atol=1e-12)
    assert "FR" not in progress.target_anchors and "FR" not in progress.pre_posture


def test_a_semi_autonomous_lift_with_no_feasible_posture_fails_before_anything_moves(paw_plan):
    _, request, _, _ = paw_plan
    block = SemiAutonomousMode(leg="FR")
    lift = target_sequence(block, np.array([0.9, -0.13, 0.2]), 1)[0]
    progress, view, env = _planning_lift(lift, request, _InfeasiblePlanner(request))
    with pytest.raises(UnreachableTarget, match="no posture within the limits"):
        LegToPedipulationRunner().step(lift, progress, view, env)
    assert progress.records[-1].metrics["posture"]["taken"] == "none"
    np.testing.assert_allclose(progress.references.body_position.sample(10.0).position, [0.0, 0.0, HEIGHT])


class _LatePlanner:
    """Answers a real-time poll (wait=False) only from its `answers_from`-th call on."""

    def __init__(self, request, answers_from: int):
        self.result, self.calls, self.answers_from = solve_request(request), 0, answers_from

    def answer(self, request, *, wait):
        assert not wait  # a real-time run polls
        self.calls += 1
        return self.result if self.calls >= self.answers_from else None


def _polling_lift(paw_plan, planner):
    mission, request, _, _ = paw_plan
    lift = mission.phases[2]
    progress, view, env = _planning_lift(lift, request, planner)
    env.wait_for_plans = False
    return lift, progress, view, env


def _at(view, t: float):
    return dataclasses.replace(view, time=t)


def test_a_late_posture_plan_is_waited_for_without_counting_against_the_timeout(paw_plan):
    lift, progress, view, env = _polling_lift(paw_plan, _LatePlanner(paw_plan[1], answers_from=3))
    runner = LegToPedipulationRunner()
    progress.phase_start = -PLAN_LATENCY  # asked at -2 s, due at 0 s
    assert runner.step(lift, progress, _at(view, 4.0), env) == RUNNING
    assert progress.plan_wait == 4.0 and progress.memo["lift"].stage == "plan"
    assert runner.step(lift, progress, _at(view, 9.0), env) == RUNNING
    # 11 s since the phase started, of which 9 s waiting: the timeout sees the 2 s of PLAN_LATENCY.
    assert progress.plan_wait == 9.0 and progress.phase_time(9.0) == PLAN_LATENCY
    assert runner.step(lift, progress, _at(view, 9.5), env) == RUNNING
    assert progress.memo["lift"].stage == "shift"
    assert progress.plan_wait == 9.5 and progress.records[-1].metrics["posture"]["plan_wait_s"] == 9.5


def test_a_posture_plan_that_never_comes_ends_the_lift_with_the_reason(paw_plan):
    lift, progress, view, env = _polling_lift(paw_plan, _LatePlanner(paw_plan[1], answers_from=10**9))
    runner = LegToPedipulationRunner()
    assert runner.step(lift, progress, _at(view, PLAN_WAIT_LIMIT), env) == RUNNING
    assert runner.step(lift, progress, _at(view, PLAN_WAIT_LIMIT + 0.01), env) == FAILED
    assert progress.reason == f"{lift.name}: no posture plan {PLAN_WAIT_LIMIT:.0f} s after it was due"
