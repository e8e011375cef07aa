"""The teleoperated foot's bounds (workspace, speed, force), the operator watchdog (silence ->
hold -> return to support) and the operator's E-stop (damping)."""

import numpy as np
import pytest
from pydrake.math import RigidTransform, RotationMatrix
from pydrake.systems.analysis import Simulator

from pedi_drake import robot
from pedi_drake.estimation.base_state import BaseState
from pedi_drake.go1_command import split_command
from pedi_drake.go1_driver.config import Go1SafetyConfig
from pedi_drake.ik.analytic import leg_ik_solutions
from pedi_drake.ik.fabrik import solve_leg_ik
from pedi_drake.leg_kinematics import leg_geometry
from pedi_drake.mission import spec
from pedi_drake.mission.phases import MissionEnvironment
from pedi_drake.mission.progress import (
    FAILED,
    LEG_MODE_FOOT,
    RUNNING,
    LegTrajectory,
    MissionProgress,
    PhaseRecord,
    References,
)
from pedi_drake.mission.robot_view import RobotView
from pedi_drake.mission.teleop_bounds import (
    bound_force,
    bound_speed,
    slide_in_workspace,
    step_into_workspace,
    workspace_margin,
)
from pedi_drake.mission.teleop_foot import TeleopFootRunner
from pedi_drake.operator.command import MODE_TELEOP, OperatorCommand
from pedi_drake.operator.estop_gate import OperatorEstopGate
from pedi_drake.trajectory import QuinticSegment

X_WB = RigidTransform([0.0, 0.0, 0.28])
JOINT_MARGIN, MIN_HEIGHT = 0.05, 0.04


def _margin(p_B):
    return workspace_margin("FR", p_B, X_WB, JOINT_MARGIN, MIN_HEIGHT)


def _working_position_B() -> np.ndarray:
    geometry = leg_geometry("FR")
    return geometry.p_BH + geometry.p_HT - np.array([0.0, 0.0, 0.15])


def test_a_command_out_of_reach_slides_along_the_boundary_and_stays_reachable():
    p = _working_position_B()
    push = np.array([0.004, 0.0, 0.0])  # forward, 0.4 m/s for 10 ms: far beyond the leg's reach
    sideways = np.array([0.0, 0.0, 0.001])
    clipped = 0
    for _ in range(150):
        p, was_clipped = slide_in_workspace(_margin, p, p + push + sideways)
        clipped += was_clipped
        # IK-checked: both solvers put the foot there within the limits.
        assert leg_ik_solutions("FR", p), p
        assert solve_leg_ik("FR", p, tol=1e-4).success, p
        assert _margin(p) >= 0.0
    assert clipped > 0
    start = _working_position_B()
    # Blocked forward, the target kept moving along the boundary (upward, the command's other part).
    assert p[0] - start[0] < 150 * push[0] - 0.1
    assert p[2] - start[2] > 0.05


def test_the_workspace_keeps_the_foot_above_the_ground():
    p = _working_position_B()
    for _ in range(100):
        p, _ = slide_in_workspace(_margin, p, p + [0.0, 0.0, -0.005])
    assert (X_WB @ p)[2] == pytest.approx(MIN_HEIGHT, abs=1e-4)


def test_a_target_the_workspace_moved_away_from_steps_back_in_by_a_hair():
    at_floor = _working_position_B()
    at_floor[2] = MIN_HEIGHT - X_WB.translation()[2]  # the lowest the foot may go
    assert _margin(at_floor) == pytest.approx(0.0, abs=1e-9)
    outside = at_floor - [0.0, 0.0, 0.0003]  # the trunk sank 0.3 mm with it
    inside = step_into_workspace(_margin, outside, max_step=0.001)
    assert _margin(inside) >= 0.0
    assert 0.0003 <= np.linalg.norm(inside - outside) < 0.0003 + 0.001 / 2**7  # straight up, no farther
    np.testing.assert_allclose((inside - outside)[0:2], 0.0, atol=1e-6)
    assert step_into_workspace(_margin, outside - [0.0, 0.0, 0.002], max_step=0.001) is None  # too far


def test_the_speed_bound_scales_the_velocity_to_the_limit():
    velocity, clipped = bound_speed(np.array([0.3, 0.4, 0.0]), 0.1)
    assert clipped and np.linalg.norm(velocity) == pytest.approx(0.1)
    np.testing.assert_allclose(velocity / 0.1, [0.6, 0.8, 0.0])
    assert bound_speed(np.array([0.05, 0.0, 0.0]), 0.1) == (pytest.approx([0.05, 0.0, 0.0]), False)


def test_a_huge_or_overflowed_velocity_is_bounded_and_never_nan():
    # Finite, but its square overflows: still a direction, scaled to the bound.
    velocity, clipped = bound_speed(np.array([1e300, -1e300, 0.0]), 0.1)
    assert clipped and np.linalg.norm(velocity) == pytest.approx(0.1)
    # A position 1e308 away, divided by a tick, is inf: no motion.
    velocity, clipped = bound_speed(np.array([np.inf, 0.0, -np.inf]), 0.1)
    assert clipped and np.array_equal(velocity, np.zeros(3))


def test_the_force_bound_slows_motion_into_the_contact_stops_it_and_backs_out_but_not_away():
    def wall(force):  # a wall in front pushes back with `force` [N]
        return np.array([-force, 0.0, 0.0])

    towards = np.array([0.1, 0.05, 0.0])
    velocity, limited = bound_force(towards, wall(10.0), 15.0, 0.1)
    assert not limited and np.array_equal(velocity, towards)  # far below the bound
    velocity, limited = bound_force(towards, wall(14.0), 15.0, 0.1)
    assert limited and 0.0 < velocity[0] < 0.05  # near it: slowed
    np.testing.assert_allclose(velocity[1], 0.05)  # along the wall: untouched
    velocity, limited = bound_force(towards, wall(15.0), 15.0, 0.1)
    assert limited and velocity[0] == pytest.approx(0.0, abs=1e-12)  # at it: stopped
    velocity, limited = bound_force(towards, wall(20.0), 15.0, 0.1)
    assert limited and -0.1 <= velocity[0] < 0.0  # beyond it: backing out, within the speed bound
    velocity, _ = bound_force(np.array([-0.1, 0.0, 0.0]), wall(20.0), 15.0, 0.1)
    assert velocity[0] <= -0.1  # away from the wall: never slowed
    assert not bound_force(towards, np.zeros(3), 15.0, 0.1)[1]


def _view(t: float, operator: OperatorCommand, q: np.ndarray) -> RobotView:
    base = BaseState(np.array([1.0, 0.0, 0.0, 0.0]), X_WB.translation(), np.zeros(3), np.zeros(3))
    return RobotView(t, base, q, np.zeros(12), np.zeros(12), np.zeros(4), operator=operator)


def test_operator_silence_holds_the_foot_then_returns_the_leg_to_support():
    phase = spec.TeleopFoot(name="teleop", leg="FR", hold_after=0.2, return_after=1.0)
    q = robot.STANDING_Q.copy()
    q[0:3] = leg_ik_solutions("FR", _working_position_B())[0]
    progress = MissionProgress(phase_start=0.0)
    progress.references = References.holding(X_WB.translation(), RotationMatrix(), 0.0, 0)
    p_foot_W = X_WB @ _working_position_B()
    progress.references.legs["FR"] = LegTrajectory(LEG_MODE_FOOT, QuinticSegment(p_foot_W, p_foot_W, 0.0, 1e-3))
    progress.records.append(PhaseRecord("teleop", "teleop_foot", RUNNING, 0.0))
    runner, env = TeleopFootRunner(), MissionEnvironment(None)

    def command(age: float) -> OperatorCommand:
        return OperatorCommand(mode_request=MODE_TELEOP, value=np.array([0.05, 0.0, 0.0]), age=age)

    runner.start(phase, progress, _view(0.0, command(0.0), q), env)
    t, outcome = 0.0, RUNNING
    # Silence counts from the phase start at the latest: the operator talks for longer than the timeouts.
    for _ in range(120):  # 1.2 s of a talking operator: the foot moves at 0.05 m/s
        t += 0.01
        outcome = runner.step(phase, progress, _view(t, command(0.0), q), env)
    assert outcome == RUNNING
    moved = progress.memo["p_ref_W"] - p_foot_W
    np.testing.assert_allclose(moved, [0.06, 0.0, 0.0], atol=1e-9)
    held = progress.memo["p_ref_W"].copy()
    for age in (0.3, 0.5, 0.9):  # silent beyond hold_after: the foot holds
        t += 0.01
        assert runner.step(phase, progress, _view(t, command(age), q), env) == RUNNING
        np.testing.assert_array_equal(progress.memo["p_ref_W"], held)
    assert progress.records[-1].metrics["bound_activations"]["silence_hold"] == 1
    t += 0.01
    assert runner.step(phase, progress, _view(t, command(1.1), q), env) == FAILED  # beyond return_after
    assert "returns to support" in progress.reason
    assert progress.records[-1].metrics["ended_by"] == "operator_silence"


def test_the_operator_estop_puts_the_motors_in_damping():
    gate = OperatorEstopGate(Go1SafetyConfig(), period=0.002)
    context = gate.CreateDefaultContext()
    command = np.concatenate([robot.STANDING_Q, np.zeros(12), np.full(12, 50.0), np.ones(12), np.ones(12)])
    gate.GetInputPort("command").FixValue(context, command)
    gate.GetInputPort("position_measured").FixValue(context, robot.STANDING_Q)
    gate.GetInputPort("velocity_measured").FixValue(context, np.full(12, 0.5))
    operator = gate.GetInputPort("operator_command")
    operator.FixValue(context, OperatorCommand(age=0.0).to_vector())

    simulator = Simulator(gate, context)
    simulator.AdvanceTo(0.01)
    np.testing.assert_array_equal(gate.GetOutputPort("command").Eval(context), command)
    operator.FixValue(context, OperatorCommand(estop=True, age=0.0).to_vector())
    simulator.AdvanceTo(0.02)
    operator.FixValue(context, OperatorCommand(estop=False, age=0.0).to_vector())  # latched: stays
    simulator.AdvanceTo(0.03)
    _, qd_des, kp, kd, tau_ff = split_command(gate.GetOutputPort("command").Eval(context))
    assert np.all(kp == 0.0) and np.all(kd > 0.0) and np.all(tau_ff == 0.0) and np.all(qd_des == 0.0)
    assert gate.GetOutputPort("latched").Eval(context)[0] == 1.0
