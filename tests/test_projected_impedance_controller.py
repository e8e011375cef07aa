"""ProjectedImpedanceController: standalone ticks (defaults, failures, ramps) on both paths (the
compiled tick and the Python reference), the scenario's settings, and short simulations of the
foot impedance and the force estimate."""

import numpy as np
import pytest
from standing_context import standing_context, tick

from pedi_drake import robot
from pedi_drake.benchmarks.demos import demo_scenario, simulate_demo
from pedi_drake.control import references
from pedi_drake.control.config import ProjectedImpedanceConfig
from pedi_drake.control.projected_impedance_controller import ProjectedImpedanceController
from pedi_drake.control.tick_steps import STATUS_BAD_INPUT, STATUS_CONTACTS_RELAXED, STATUS_OK, STATUS_QP_FAILED
from pedi_drake.diagram import apply_mission
from pedi_drake.evaluation import paper002 as evaluation
from pedi_drake.evaluation.controller_metrics import controller_metrics
from pedi_drake.exceptions import ScenarioError
from pedi_drake.scenario import RobotConfig, load_scenario
from pedi_drake.station.initial_state import initial_trunk_pose


def standing_controller(config: ProjectedImpedanceConfig | None = None):
    controller = ProjectedImpedanceController(config or ProjectedImpedanceConfig())
    context = standing_context(controller)
    return controller, context


def test_unconnected_references_stand_in_place_on_four_feet():
    controller, context = standing_controller()
    command, diag = tick(controller, context, 3)
    layout = controller.diag
    assert diag[layout["status"]][0] == STATUS_OK
    forces = diag[layout["contact_forces"]].reshape(-1, 3)
    assert np.sum(forces[:, 2]) == pytest.approx(controller.model.total_mass * 9.81, rel=0.02)
    assert np.all(forces[:, 2] > 20.0)
    assert diag[layout["constraint_rank"]][0] == 12
    assert np.all(np.abs(command[48:60]) < 0.5 * robot.EFFORT_LIMIT)


def test_diagnostics_keep_the_whole_body_controller_layout_first():
    from pedi_drake.control.whole_body_controller import diagnostics_layout

    controller, _ = standing_controller()
    for name, where in diagnostics_layout(controller.num_contacts).items():
        assert controller.diag[name] == where


def test_a_balance_the_limits_cannot_hold_is_relaxed_not_dropped():
    # 200 N minimum per loaded foot: no forces balance the standing robot's weight, but some lie
    # within the limits; the tick takes the nearest balance they give and says so.
    config = ProjectedImpedanceConfig(min_normal_force=200.0, contact_ramp_time=0.02)
    controller, context = standing_controller(config)
    command, diag = tick(controller, context, 3)
    assert diag[controller.diag["status"]][0] == STATUS_CONTACTS_RELAXED
    assert np.all(np.isfinite(command))
    forces = diag[controller.diag["contact_forces"]].reshape(-1, 3)
    assert np.all(forces[:, 2] >= 200.0 - 1e-6)
    assert np.all(np.abs(command[48:60]) <= config.torque_limit_scale * robot.EFFORT_LIMIT + 1e-6)


def test_infeasible_qp_holds_and_damps_the_last_good_command_and_recovers():
    # 200 N minimum per loaded foot: four feet cannot balance a 13 kg robot, and a tenth of the
    # effort limits cannot press them that hard (no relaxed balance either).
    config = ProjectedImpedanceConfig(min_normal_force=200.0, torque_limit_scale=0.1, contact_ramp_time=0.02)
    controller, context = standing_controller(config)
    controller.contact_set_port.FixValue(context, np.zeros(4))
    good, diag = tick(controller, context, 2)
    assert diag[controller.diag["status"]][0] == STATUS_OK
    controller.contact_set_port.FixValue(context, np.ones(4))
    for _ in range(15):
        command, diag = tick(controller, context, 1)
        if diag[controller.diag["status"]][0] in (STATUS_OK, STATUS_CONTACTS_RELAXED):
            good = command  # a relaxed balance (while the feet's load ramps in) is a command too
    assert diag[controller.diag["status"]][0] == STATUS_QP_FAILED
    assert diag[controller.diag["total_failures"]][0] > 0
    assert np.all(np.isfinite(command))
    np.testing.assert_allclose(command[48:60], good[48:60])  # last good feed-forward held
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


def test_contact_removal_ramps_the_force_bound_down():
    # Standing with the centre of mass on the FL-RR diagonal, FR's force can only shrink so far
    # before balance needs it: the ramp bounds the force at every tick it solves.
    config = ProjectedImpedanceConfig(contact_ramp_time=0.3)
    controller, context = standing_controller(config)
    tick(controller, context, 3)
    controller.contact_set_port.FixValue(context, references.contact_set_vector(("FL", "RR", "RL")))
    ramps, forces = [], []
    for _ in range(int(0.3 / config.period) + 5):
        _, diag = tick(controller, context, 1)
        ramps.append(diag[controller.diag["contact_ramp"]][0])
        if diag[controller.diag["status"]][0] == STATUS_OK:
            forces.append((ramps[-1], diag[controller.diag["contact_forces"]][2]))
    step = config.period / config.contact_ramp_time
    np.testing.assert_allclose(np.diff(ramps)[: int(0.25 / config.period)], -step, atol=1e-9)
    assert ramps[-1] == 0.0
    assert len(forces) > 50
    for ramp, fz in forces:
        assert ramp * config.min_normal_force - 1e-6 <= fz <= ramp * config.max_normal_force + 1e-6
    steps = np.abs(np.diff([fz for _, fz in forces]))
    assert np.max(steps) <= config.max_normal_force * step + 0.5


def test_bad_controller_name_is_a_scenario_error_naming_the_field():
    with pytest.raises(ScenarioError, match=r"controller: .*got 'projected'"):
        load_scenario(scenario_text="{controller: projected}")


@pytest.mark.parametrize("value", ["[600.0, 0.0, 600.0]", "[600.0, -5.0, 600.0]", "[600.0, 600.0]"])
def test_foot_stiffness_that_is_not_positive_is_a_scenario_error_naming_the_field(value):
    with pytest.raises(ScenarioError, match=r"projected_impedance\.foot_stiffness"):
        load_scenario(
            scenario_text=f"{{controller: projected_impedance, projected_impedance: {{foot_stiffness: {value}}}}}"
        )


def test_projected_impedance_is_selectable_in_the_scenario():
    scenario = load_scenario(
        scenario_text="{controller: projected_impedance, projected_impedance: {foot_stiffness: [800.0, 800.0, 500.0]}}"
    )
    assert scenario.controller == "projected_impedance"
    assert scenario.projected_impedance.foot_stiffness == [800.0, 800.0, 500.0]


@pytest.fixture(scope="module")
def foot_push():
    scenario = demo_scenario("push_foot")
    scenario.controller = "projected_impedance"
    record, judged = simulate_demo("push_foot", scenario)
    plant = record.built.diagram.GetSubsystemByName("station").GetSubsystemByName("plant")
    push = apply_mission(record.scenario, record.built.mission).pushes[0]
    response = evaluation.foot_push_response(plant, record.logs, push)
    return controller_metrics(record, judged), response, scenario


def test_pushed_foot_yields_with_the_commanded_stiffness(foot_push):
    metrics, response, scenario = foot_push
    assert not metrics.fell and metrics.qp_failures == 0
    commanded = scenario.projected_impedance.foot_stiffness[0]  # the push is along world x
    assert response.stiffness_n_per_m == pytest.approx(commanded, rel=0.10)


def test_force_estimate_matches_the_force_applied_to_the_foot(foot_push):
    _, response, _ = foot_push
    assert response.force_estimate_rms_n < 2.0


def test_three_leg_hold_holds_the_trunk_still(foot_push):
    metrics, _, _ = foot_push
    assert metrics.mission_succeeded
    assert metrics.trunk_drift < 0.01
    assert metrics.stance_slip < 0.002
    assert metrics.max_torque_ratio <= 1.0
