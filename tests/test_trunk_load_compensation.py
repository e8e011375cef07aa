"""The trunk's integral action: what it learns, when, its bounds, and a stand-up under a load
the controllers' model does not know."""

import numpy as np
import pytest
from pydrake.math import RotationMatrix

from pedi_drake import robot
from pedi_drake.control import references
from pedi_drake.control.trunk_load_compensation import (
    ANGULAR,
    CARRIED_HEIGHT,
    LINEAR,
    TrunkLoadCompensationConfig,
    TrunkLoadCompensator,
)
from pedi_drake.exceptions import ScenarioError
from pedi_drake.run import run
from pedi_drake.run_logs import read_run_logs
from pedi_drake.scenario import load_scenario

PERIOD = 0.002  # [s]
STANDING = np.array([0.0, 0.0, 0.28])  # [m]


MASS = 13.1  # [kg]
INERTIA = np.diag([0.13, 0.40, 0.43])  # [kg m^2]


def _compensator(config: TrunkLoadCompensationConfig | None = None, num_contacts: int = 6):
    system = TrunkLoadCompensator(
        config or TrunkLoadCompensationConfig(enabled=True), PERIOD, num_contacts, MASS, INERTIA
    )
    context = system.CreateDefaultContext()
    return system, context


def _fix(system, context, p_ref, p, R=None, contact_set=None, lifted_mode=references.LEG_MODE_JOINTS):
    R = R or RotationMatrix()
    nc = system.contact_set_port.size()
    contact_set = np.ones(nc) if contact_set is None else np.asarray(contact_set, float)
    lifted = {
        leg: (lifted_mode, np.zeros(3), np.zeros(3), np.zeros(3))
        for k, leg in enumerate(robot.LEG_NAMES)
        if contact_set[k] < 0.5
    }
    system.leg_reference_port.FixValue(context, references.leg_reference_vector(lifted))
    system.body_reference_port.FixValue(context, references.body_reference_vector(np.asarray(p_ref), RotationMatrix()))
    system.base_state_port.FixValue(context, np.concatenate([R.ToQuaternion().wxyz(), p, np.zeros(6)]))
    system.contact_set_port.FixValue(context, contact_set)


def _tick(system, context, n: int = 1) -> np.ndarray:
    for _ in range(n):
        state = system.AllocateDiscreteVariables()
        system.CalcForcedDiscreteVariableUpdate(context, state)
        context.SetDiscreteState(state)
    return context.get_discrete_state(system.learnt_state).value().copy()


def test_a_sagging_trunk_learns_the_missing_lift_at_the_integral_gain():
    system, context = _compensator()
    sag = 0.02  # [m]
    _fix(system, context, STANDING, STANDING - [0.0, 0.0, sag], contact_set=[1, 1, 1, 1, 0, 0])
    learnt = _tick(system, context, 10)
    expected = 10 * TrunkLoadCompensationConfig().position_gain * PERIOD * sag
    np.testing.assert_allclose(learnt[LINEAR], [0.0, 0.0, expected], atol=1e-12)
    np.testing.assert_allclose(learnt[ANGULAR], 0.0, atol=1e-12)
    # ... and hands it to the controller as the load's weight: a downward force on the trunk.
    wrench = system.wrench_port.Eval(context)
    np.testing.assert_allclose(wrench, [0.0, 0.0, 0.0, 0.0, 0.0, -MASS * expected], atol=1e-12)


def test_a_tilted_trunk_learns_the_missing_moment_about_the_tilt():
    system, context = _compensator()
    tilt = RotationMatrix.MakeYRotation(-0.01)  # nose up: the reference is level
    _fix(system, context, STANDING, STANDING, R=tilt, contact_set=[1, 1, 1, 1, 0, 0])
    learnt = _tick(system, context, 5)
    assert learnt[ANGULAR][1] == pytest.approx(5 * TrunkLoadCompensationConfig().orientation_gain * PERIOD * 0.01)
    assert abs(learnt[ANGULAR][0]) < 1e-12 and abs(learnt[ANGULAR][2]) < 1e-12
    # The moment that tilted it, through the model's inertia in the trunk's own attitude.
    R = tilt.matrix()
    np.testing.assert_allclose(system.wrench_port.Eval(context)[:3], -(R @ INERTIA @ R.T) @ learnt[ANGULAR], atol=1e-12)


def test_what_it_learns_is_bounded_per_axis():
    config = TrunkLoadCompensationConfig(enabled=True)
    system, context = _compensator(config)
    _fix(
        system,
        context,
        STANDING,
        STANDING + [0.3, -0.3, -0.1],
        R=RotationMatrix.MakeXRotation(0.5),
        contact_set=[1, 1, 1, 1, 0, 0],
    )
    learnt = _tick(system, context, 2000)
    np.testing.assert_allclose(np.abs(learnt[LINEAR]), config.max_linear)
    assert abs(learnt[ANGULAR][0]) == pytest.approx(config.max_angular)


def test_a_trunk_on_its_belly_learns_nothing_and_keeps_what_it_knew():
    system, context = _compensator()
    _fix(system, context, STANDING, STANDING - [0.0, 0.0, 0.01], contact_set=[1, 1, 1, 1, 0, 0])
    before = _tick(system, context, 20)
    low = np.array([0.0, 0.0, CARRIED_HEIGHT - 0.01])
    _fix(system, context, low - [0.0, 0.0, 0.03], low, R=RotationMatrix.MakeYRotation(0.1))
    np.testing.assert_array_equal(_tick(system, context, 50), before)


def test_on_loaded_prongs_it_learns_the_attitude_but_not_the_position():
    system, context = _compensator()
    _fix(
        system,
        context,
        STANDING - [0.0, 0.0, 0.05],
        STANDING,
        R=RotationMatrix.MakeYRotation(0.02),
        contact_set=[1, 1, 1, 1, 1, 0],
    )
    learnt = _tick(system, context, 10)
    np.testing.assert_array_equal(learnt[LINEAR], 0.0)
    assert learnt[ANGULAR][1] < 0.0


def test_on_three_feet_it_learns_while_the_lifted_leg_moves_freely():
    system, context = _compensator()
    sagging = STANDING - [0.0, 0.0, 0.02]
    _fix(system, context, STANDING, sagging, contact_set=[1, 1, 1, 1, 0, 0])
    four = _tick(system, context, 10)
    assert four[LINEAR][2] > 0.0
    # FR lifted on a joint reference (a reach): the stance legs carry a different share, learnt.
    _fix(system, context, STANDING, sagging, contact_set=[0, 1, 1, 1, 0, 0])
    three = _tick(system, context, 10)
    assert three[LINEAR][2] > four[LINEAR][2]
    tilted = RotationMatrix.MakeYRotation(0.02)
    # FR on a foot task (it may push on a wall): held, whatever the trunk's error.
    for mode in (references.LEG_MODE_FOOT, references.LEG_MODE_FOOT_POSE):
        _fix(system, context, STANDING, sagging, R=tilted, contact_set=[0, 1, 1, 1, 0, 0], lifted_mode=mode)
        np.testing.assert_array_equal(_tick(system, context, 10), three)
    # FR and FL lifted (on the prongs' tips and the hind feet): held.
    _fix(system, context, STANDING, sagging, R=tilted, contact_set=[0, 0, 1, 1, 1, 1])
    np.testing.assert_array_equal(_tick(system, context, 10), three)


def test_disabled_it_learns_no_load():
    system, context = _compensator(TrunkLoadCompensationConfig(enabled=False))
    _fix(system, context, STANDING, STANDING - [0.0, 0.0, 0.05], contact_set=[1, 1, 1, 1, 0, 0])
    np.testing.assert_array_equal(_tick(system, context, 10), 0.0)
    np.testing.assert_array_equal(system.wrench_port.Eval(context), 0.0)


@pytest.mark.parametrize(
    "text, field",
    [
        ("{position_gain: -1.0}", "trunk_load_compensation.position_gain"),
        ("{orientation_gain: .nan}", "trunk_load_compensation.orientation_gain"),
        ("{max_linear: [1.0, 1.0]}", "trunk_load_compensation.max_linear"),
        ("{max_linear: [1.0, -1.0, 1.0]}", "trunk_load_compensation.max_linear"),
        ("{max_angular: -2.0}", "trunk_load_compensation.max_angular"),
    ],
)
def test_bad_settings_name_their_field(text, field):
    with pytest.raises(ScenarioError, match=field.replace(".", r"\.")):
        load_scenario(scenario_text=f"{{trunk_load_compensation: {text}}}")


STAND_MISSION = """
description: Stand up.
phases:
  - {kind: stand_up, height: 0.28, duration: 2.0, timeout: 6.0}
"""
# A Go1 carrying 2.5 kg off its centre on motors at 60-70 % of their rating: the controllers'
# PD alone leaves the trunk about 4 cm low.
HEAVY_WEAK = (
    "{model_error: {payload_mass: 2.5, payload_offset: [0.03, 0.02, 0.0], motor_strength: [0.6, 0.7, 0.6, 0.7]},"
    " trunk_load_compensation: {enabled: %s}}"
)


@pytest.mark.parametrize("enabled", [True, False])
def test_a_heavy_go1_on_weak_motors_stands_to_its_height_only_with_the_integral(tmp_path, enabled):
    mission = tmp_path / "mission.yaml"
    mission.write_text(STAND_MISSION)
    scenario = load_scenario(scenario_text=HEAVY_WEAK % str(enabled).lower())
    scenario.mission, scenario.controller = str(mission), "whole_body"
    result = run(scenario=scenario, name="heavy", out_dir=tmp_path / "out", quiet=True, replay=False)
    logs = read_run_logs(tmp_path / "out" / "logs.npz")
    true_height = logs["sim.plant_state"].data[6, -1]  # the plant's truth [m]
    if enabled:
        assert result["success"], result["reason"]
        assert abs(true_height - 0.28) < 0.01
    else:
        assert not result["success"]
        assert true_height < 0.28 - 0.02
