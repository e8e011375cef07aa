"""LegIkSystem: world-frame targets in a small diagram, solving only when the target changes."""

import numpy as np
import pytest
from pydrake.common.eigen_geometry import Quaternion
from pydrake.common.value import AbstractValue
from pydrake.math import RigidTransform, RollPitchYaw, RotationMatrix
from pydrake.systems.analysis import Simulator
from pydrake.systems.framework import DiagramBuilder
from pydrake.systems.primitives import ConstantValueSource, ConstantVectorSource

from pedi_drake import robot
from pedi_drake.exceptions import PediError
from pedi_drake.ik import LegIkSystem
from pedi_drake.ik.leg_ik_system import RETARGET_TOLERANCE, _retarget
from pedi_drake.leg_kinematics import foot_position_B

X_WB = RigidTransform(RollPitchYaw(0.05, -0.1, 0.7), [0.4, -0.2, 0.3])


def pose_vector(X: RigidTransform) -> np.ndarray:
    return np.concatenate([X.rotation().ToQuaternion().wxyz(), X.translation()])


def test_goal_places_the_foot_on_the_world_target_in_a_diagram():
    q_true = np.array([-0.2, 0.7, -1.4])
    p_WF = X_WB.multiply(foot_position_B("RR", q_true))
    builder = DiagramBuilder()
    ik = builder.AddSystem(LegIkSystem())
    for name, source in (
        ("foot_target_W", ConstantVectorSource(p_WF)),
        ("X_WB", ConstantVectorSource(pose_vector(X_WB))),
        ("leg", ConstantValueSource(AbstractValue.Make("RR"))),
        ("q_measured", ConstantVectorSource(robot.STANDING_Q)),
    ):
        builder.Connect(builder.AddSystem(source).get_output_port(), ik.GetInputPort(name))
    simulator = Simulator(builder.Build())
    simulator.AdvanceTo(0.05)
    context = ik.GetMyContextFromRoot(simulator.get_context())
    q_goal = ik.GetOutputPort("leg_q_goal").Eval(context)
    assert ik.GetOutputPort("solved").Eval(context)[0] == 1.0
    assert np.linalg.norm(X_WB.multiply(foot_position_B("RR", q_goal)) - p_WF) <= 1e-3
    assert ik.GetOutputPort("ik_error").Eval(context)[0] <= 1e-3
    assert ik.solve_count(context) == 1  # 25 periodic updates, one target


def _standalone(leg: str, p_WF: np.ndarray, X: RigidTransform = X_WB):
    ik = LegIkSystem(period=0.01)
    simulator = Simulator(ik)
    context = simulator.get_mutable_context()
    ik.GetInputPort("foot_target_W").FixValue(context, p_WF)
    ik.GetInputPort("X_WB").FixValue(context, pose_vector(X))
    ik.GetInputPort("leg").FixValue(context, AbstractValue.Make(leg))
    ik.GetInputPort("q_measured").FixValue(context, robot.STANDING_Q)
    return ik, simulator, context


def test_solves_only_when_the_target_changes():
    p_WF = X_WB.multiply(foot_position_B("FL", np.array([0.1, 0.8, -1.6])))
    ik, simulator, context = _standalone("FL", p_WF)
    simulator.AdvanceTo(0.1)
    assert ik.solve_count(context) == 1
    ik.GetInputPort("foot_target_W").FixValue(context, p_WF + [0.0, 0.0, 2e-5])  # below retarget_tolerance
    simulator.AdvanceTo(0.2)
    assert ik.solve_count(context) == 1
    ik.GetInputPort("foot_target_W").FixValue(context, p_WF + [0.02, 0.0, 0.0])
    simulator.AdvanceTo(0.3)
    assert ik.solve_count(context) == 2


def test_trunk_motion_and_leg_change_trigger_a_solve():
    p_WF = X_WB.multiply(foot_position_B("FL", np.array([0.1, 0.8, -1.6])))
    ik, simulator, context = _standalone("FL", p_WF)
    simulator.AdvanceTo(0.05)
    moved = RigidTransform(X_WB.rotation(), X_WB.translation() + [0.0, 0.0, 0.01])
    ik.GetInputPort("X_WB").FixValue(context, pose_vector(moved))
    simulator.AdvanceTo(0.1)
    assert ik.solve_count(context) == 2
    ik.GetInputPort("leg").FixValue(context, AbstractValue.Make("FR"))
    simulator.AdvanceTo(0.15)
    assert ik.solve_count(context) == 3


def test_unreachable_target_reports_failure_within_limits():
    ik, simulator, context = _standalone("RL", X_WB.multiply([0.0, 0.0, -1.0]))
    simulator.AdvanceTo(0.05)
    assert ik.GetOutputPort("solved").Eval(context)[0] == 0.0
    q_goal = ik.GetOutputPort("leg_q_goal").Eval(context)
    assert np.all(q_goal >= robot.Q_LOWER[9:12]) and np.all(q_goal <= robot.Q_UPPER[9:12])


def test_nan_target_reports_failure_and_holds_the_measured_angles():
    ik, simulator, context = _standalone("FR", np.array([np.nan, 0.0, 0.0]))
    simulator.AdvanceTo(0.05)
    assert ik.GetOutputPort("solved").Eval(context)[0] == 0.0
    np.testing.assert_array_equal(ik.GetOutputPort("leg_q_goal").Eval(context), robot.STANDING_Q[0:3])
    assert ik.solve_count(context) == 1  # a persisting NaN target is not re-solved every tick


def test_unnormalized_quaternion_is_normalized():
    p_WF = X_WB.multiply(foot_position_B("FR", np.array([0.0, 0.9, -1.8])))
    ik, simulator, context = _standalone("FR", p_WF)
    pose = pose_vector(X_WB)
    pose[0:4] *= 3.0
    ik.GetInputPort("X_WB").FixValue(context, pose)
    simulator.AdvanceTo(0.02)
    assert ik.GetOutputPort("solved").Eval(context)[0] == 1.0


def test_unknown_leg_raises():
    ik, simulator, context = _standalone("XX", np.zeros(3))
    with pytest.raises(PediError):
        simulator.Initialize()


def test_solved_target_B_echoes_the_trunk_frame_target_of_the_last_solve():
    p_B = foot_position_B("FL", np.array([0.1, 0.8, -1.6]))
    ik, simulator, context = _standalone("FL", X_WB.multiply(p_B))
    assert np.all(np.isnan(ik.GetOutputPort("solved_target_B").Eval(context)))
    simulator.AdvanceTo(0.05)
    np.testing.assert_allclose(ik.GetOutputPort("solved_target_B").Eval(context), p_B, atol=1e-12)


def test_the_retarget_check_equals_its_python_source_and_drakes_frames():
    rng = np.random.default_rng(20261203)
    for k in range(2000):
        quaternion = rng.normal(size=4) * rng.uniform(0.5, 2.0)
        pose = np.concatenate([quaternion, rng.normal(0, 0.3, 3)])
        p_WF = rng.normal(0, 0.4, 3)
        if k % 7 == 0:
            p_WF[rng.integers(0, 3)] = np.nan  # nothing asked
        R_WB = RotationMatrix(Quaternion(quaternion / np.linalg.norm(quaternion)))
        expected = np.full(3, np.nan) if k % 7 == 0 else R_WB.inverse().multiply(p_WF - pose[4:7])
        state = np.zeros(10)
        state[0:3] = expected + rng.choice([0.0, 0.5 * RETARGET_TOLERANCE, 3 * RETARGET_TOLERANCE], size=3)
        if k % 11 == 0:
            state[0:3] = np.nan
        state[3] = rng.integers(-1, 4)
        leg_index = int(rng.integers(0, 4))
        compiled, interpreted = np.empty(3), np.empty(3)
        due = _retarget(p_WF, pose, state, leg_index, RETARGET_TOLERANCE, compiled)
        assert due == _retarget.py_func(p_WF, pose, state, leg_index, RETARGET_TOLERANCE, interpreted)
        np.testing.assert_allclose(compiled, interpreted, rtol=0, atol=1e-15)
        np.testing.assert_allclose(compiled, expected, rtol=0, atol=1e-13)
        moved = np.abs(expected - state[0:3])
        both_unset = np.isnan(expected).any() and np.isnan(state[0:3]).any()
        same = both_unset or bool(np.all(moved <= RETARGET_TOLERANCE))
        assert due == (int(state[3]) != leg_index or not same)
