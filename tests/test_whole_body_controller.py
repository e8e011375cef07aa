"""WholeBodyController: standalone ticks (defaults, failures) and the demo missions as short simulations."""

import dataclasses

import numpy as np
import pytest
import reference_tasks
from reference_stacks import ResolvedInputs, StackBuilder
from standing_context import standing_context, tick

from pedi_drake import robot
from pedi_drake.benchmarks.demos import demo_scenario, run_demo
from pedi_drake.control import references
from pedi_drake.control.config import WholeBodyControllerConfig
from pedi_drake.control.tick_steps import STATUS_BAD_INPUT, STATUS_CONTACTS_RELAXED, STATUS_OK, STATUS_QP_FAILED
from pedi_drake.control.whole_body_controller import WholeBodyController
from pedi_drake.prongs import ProngDesign
from pedi_drake.scenario import RobotConfig
from pedi_drake.station.initial_state import initial_trunk_pose
from pedi_drake.vector3 import orientation_error_W


def standing_controller(config: WholeBodyControllerConfig | None = None):
    controller = WholeBodyController(config or WholeBodyControllerConfig())
    context = standing_context(controller)
    return controller, context


def test_unconnected_references_stand_in_place():
    controller, context = standing_controller(WholeBodyControllerConfig())
    command, diag = tick(controller, context, 3)
    layout = controller.diag
    assert diag[layout["status"]][0] == STATUS_OK
    forces = diag[layout["contact_forces"]].reshape(-1, 3)
    # Static standing: the feet carry the weight, evenly enough, and the torques are small.
    assert np.sum(forces[:, 2]) == pytest.approx(controller.model.total_mass * 9.81, rel=0.02)
    assert np.all(forces[:, 2] > 20.0)
    np.testing.assert_allclose(command[24:36], controller.config.joint_kp)
    assert np.all(np.abs(command[48:60]) < 0.5 * robot.EFFORT_LIMIT)


def test_infeasible_qp_holds_last_good_command_and_recovers():
    # 200 N minimum per loaded foot cannot be produced within the knee torque limits.
    config = WholeBodyControllerConfig(min_normal_force=200.0, contact_ramp_time=0.02)
    controller, context = standing_controller(config)
    controller.contact_set_port.FixValue(context, np.zeros(4))
    good, diag = tick(controller, context, 2)
    assert diag[controller.diag["status"]][0] == STATUS_OK
    controller.contact_set_port.FixValue(context, np.ones(4))
    for _ in range(15):
        command, diag = tick(controller, context, 1)
        if diag[controller.diag["status"]][0] == STATUS_OK:
            good = command
    assert diag[controller.diag["status"]][0] == STATUS_QP_FAILED
    assert diag[controller.diag["total_failures"]][0] > 0
    assert np.all(np.isfinite(command))
    np.testing.assert_allclose(command[0:12], good[0:12])  # last good position target
    np.testing.assert_allclose(command[48:60], good[48:60])  # last good feed-forward
    np.testing.assert_allclose(command[12:24], 0.0)  # velocity target: stop
    assert np.all(command[36:48] >= config.failure_kd)  # damped
    controller.contact_set_port.FixValue(context, np.zeros(4))
    _, diag = tick(controller, context, 15)
    assert diag[controller.diag["status"]][0] == STATUS_OK


def test_non_finite_reference_is_rejected_without_nan():
    controller, context = standing_controller()
    good, _ = tick(controller, context, 2)
    body = references.body_reference_vector(np.array([0.0, 0.0, np.nan]), initial_trunk_pose(RobotConfig()).rotation())
    controller.body_reference_port.FixValue(context, body)
    command, diag = tick(controller, context, 1)
    assert diag[controller.diag["status"]][0] == STATUS_BAD_INPUT
    assert np.all(np.isfinite(command))
    np.testing.assert_allclose(command[48:60], good[48:60])


def test_contact_removal_ramps_the_force_down():
    config = WholeBodyControllerConfig(contact_ramp_time=0.3)
    controller, context = standing_controller(config)
    tick(controller, context, 3)
    controller.contact_set_port.FixValue(context, references.contact_set_vector(("FL", "RR", "RL")))
    fr = []
    for _ in range(int(0.3 / config.period) + 5):
        _, diag = tick(controller, context, 1)
        fr.append(diag[controller.diag["contact_forces"]][2])
    steps = np.abs(np.diff(fr))
    bound_step = config.max_normal_force * config.period / config.contact_ramp_time
    assert fr[-1] == pytest.approx(0.0, abs=1e-6)
    assert np.max(steps) <= bound_step + 0.5


@pytest.fixture(scope="module")
def three_leg():
    return run_demo("three_leg_hold", demo_scenario("three_leg_hold"))


def test_three_leg_hold_meets_floors(three_leg):
    r = three_leg
    assert r.mission_succeeded and not r.fell
    assert r.qp_failures == 0
    assert max(r.foot_errors) < 0.005
    assert r.trunk_drift < 0.01
    assert r.stance_slip < 0.002
    assert r.max_torque_ratio <= 1.0


def test_three_leg_contact_switch_has_no_force_jump(three_leg):
    # The FR force ramps out over 0.3 s: about 1.7 N a tick at most; the other feet follow smoothly.
    assert three_leg.max_force_jump < 5.0


def test_stand_on_four_legs_at_1khz_in_weighted_mode():
    scenario = demo_scenario("stand")
    scenario.whole_body = dataclasses.replace(scenario.whole_body, period=0.001, hqp_mode="weighted")
    r = run_demo("stand", scenario)
    assert r.mission_succeeded and not r.fell and r.qp_failures == 0
    assert r.stance_slip_whole_run < 0.002
    assert r.max_torque_ratio < 0.5


def test_five_targets_reached():
    r = run_demo("five_targets")
    assert r.mission_succeeded and not r.fell and r.qp_failures == 0
    assert len(r.foot_errors) == 5
    assert max(r.foot_errors) < 0.005
    assert r.max_torque_ratio <= 1.0


def test_prongs_carry_the_trunk_with_both_front_feet_lifted():
    r = run_demo("prongs", demo_scenario("prongs"))
    assert r.mission_succeeded and not r.fell and r.qp_failures == 0
    assert r.prong_load > 20.0
    assert max(r.foot_errors) < 0.005
    assert r.max_torque_ratio <= 1.0


def test_sliding_prongs_that_friction_cannot_stop_brake_at_the_limit_instead_of_failing():
    # Trunk and loaded prong tips slide at 1.5 m/s (a push): stopping the tips, which are fixed to
    # the trunk, at the no-motion task's rate needs more horizontal force than friction allows, so
    # the strict stack is infeasible. The controller then demotes contact no-motion below the
    # force limits rather than fail: the contacts brake at the friction limit.
    controller = WholeBodyController(WholeBodyControllerConfig(), ProngDesign())
    context = controller.CreateDefaultContext()
    X = initial_trunk_pose(RobotConfig(initial_pose="standing"))
    sliding = np.concatenate([X.rotation().ToQuaternion().wxyz(), X.translation(), np.zeros(3), [1.5, 0.0, 0.0]])
    controller.base_state_port.FixValue(context, sliding)
    controller.position_port.FixValue(context, robot.STANDING_Q)
    controller.velocity_port.FixValue(context, np.zeros(12))
    controller.contact_set_port.FixValue(context, references.contact_set_vector(num_prongs=2, prongs=True))
    command, diag = tick(controller, context, 1)
    assert diag[controller.diag["status"]][0] == STATUS_CONTACTS_RELAXED
    assert diag[controller.diag["total_failures"]][0] == 0
    assert np.all(np.isfinite(command)) and np.all(np.abs(command[48:60]) <= robot.EFFORT_LIMIT)
    forces = diag[controller.diag["contact_forces"]].reshape(-1, 3)
    mu = controller.config.friction / np.sqrt(2.0)
    assert np.all(np.abs(forces[:, 0]) <= mu * forces[:, 2] + 1e-6)
    assert np.sum(forces[:, 0]) < -0.9 * mu * np.sum(forces[:, 2])  # braking, at the friction limit


@pytest.mark.parametrize(
    ("mode", "calf_rows"), [(references.LEG_MODE_FOOT_POSE, 2), (references.LEG_MODE_SHANK_POSE, 3)]
)
def test_hqp_takes_the_optional_5d_foot_task_and_the_6d_shank_task(mode, calf_rows):
    controller, context = standing_controller()
    tick(controller, context, 2)
    controller.contact_set_port.FixValue(context, references.contact_set_vector(("FL", "RR", "RL")))
    p_WF = controller.model.update(controller.base_state_port.Eval(context), robot.STANDING_Q, np.zeros(12)).p_contacts[
        0
    ]
    R_WC, _, _ = controller.model.calf_orientation(0)
    rotation = orientation_error_W(R_WC, np.eye(3)) + np.array([0.05, -0.05, 0.0])
    legs = references.leg_reference_vector({"FR": (mode, p_WF, np.zeros(3), rotation)})
    controller.leg_reference_port.FixValue(context, legs)
    _, diag = tick(controller, context, 1)
    assert diag[controller.diag["status"]][0] in (STATUS_OK, STATUS_CONTACTS_RELAXED)
    snapshot = controller.model.update(controller.base_state_port.Eval(context), robot.STANDING_Q, np.zeros(12))
    snapshot.calf_orientations[0] = controller.model.calf_orientation(0)
    inputs = ResolvedInputs(
        body=references.parse_body_reference(
            references.body_reference_vector(
                snapshot.p_WB, initial_trunk_pose(RobotConfig(initial_pose="standing")).rotation()
            )
        ),
        legs=references.parse_leg_reference(legs),
        ramp=np.array([0.0, 1.0, 1.0, 1.0]),
        no_motion=np.array([False, True, True, True]),
        polygon_N=np.zeros((0, 2)),
        polygon_d=np.zeros(0),
        friction=0.6,
        ground_height=0.0,
    )
    layout = reference_tasks.VariableLayout(
        controller.model.nv, controller.num_contacts, controller.model.plant_map.v_index
    )
    builder = StackBuilder(controller.config, layout, controller.model.total_mass)
    names = [task.name for task in builder.leg_tasks(snapshot, inputs)]
    assert names == ["foot_FR", "calf_FR"]
    calf = builder.leg_tasks(snapshot, inputs)[1]
    assert calf.A.shape[0] == calf_rows  # the 5-D task leaves the yaw free, the 6-D holds it


def test_a_safety_polygon_with_two_vertices_is_rejected_as_bad_input():
    controller, context = standing_controller()
    polygon = references.safety_polygon_vector(np.array([[0.1, 0.0], [0.0, 0.1], [-0.1, 0.0]]))
    controller.safety_polygon_port.FixValue(context, polygon)
    _, diag = tick(controller, context, 2)
    assert diag[controller.diag["status"]][0] == STATUS_OK
    polygon[0] = 2.0  # a count the layout does not allow
    controller.safety_polygon_port.FixValue(context, polygon)
    _, diag = tick(controller, context, 1)
    assert diag[controller.diag["status"]][0] == STATUS_BAD_INPUT
