"""Model error as scenario data: validation, and each field's effect on the simulated station only."""

import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from pydrake.geometry import Sphere
from pydrake.systems.analysis import Simulator

from pedi_drake import robot
from pedi_drake.exceptions import ScenarioError
from pedi_drake.go1_command import pack_command
from pedi_drake.model_error_config import ModelErrorConfig
from pedi_drake.scenario import Scenario, load_scenario
from pedi_drake.station.model_error import FRICTION_VELOCITY_BAND, PAYLOAD_BODY_NAME, joint_loss_torque
from pedi_drake.station.motor_model import Go1MotorModel, motor_torque
from pedi_drake.station_interface import MakeStation

REPO = Path(__file__).resolve().parents[1]
# The soft foot of the reality-gap study: the standing robot sinks about 17 mm into it.
SOFT_FOOT_STIFFNESS = 1880.0  # [N/m]
# The weight on the feet of the standing Go1 [N].
WEIGHT = robot.TOTAL_MASS * 9.81


def _station(model_error: str, robot_text: str = "{initial_pose: standing}"):
    scenario = load_scenario(scenario_text=f"{{robot: {robot_text}, model_error: {model_error}}}")
    station = MakeStation(scenario)
    return scenario, station, station.GetSubsystemByName("plant")


def _motors(error: ModelErrorConfig, time_step: float = 0.001):
    plant, plant_map = robot.make_go1_plant()
    motors = Go1MotorModel(
        plant_map,
        plant.num_positions(),
        plant.num_velocities(),
        plant.num_actuators(),
        error=error,
        time_step=time_step,
    )
    return plant, plant_map, motors


@pytest.mark.parametrize(
    "text, field",
    [
        ("{payload_mass: -1}", "model_error.payload_mass"),
        ("{payload_mass: .nan}", "model_error.payload_mass"),
        ("{payload_offset: [0.0, 0.1]}", "model_error.payload_offset"),
        ("{motor_strength: [1.0, 1.0, 0.0, 1.0]}", "model_error.motor_strength[RR]"),
        ("{motor_strength: [1.0, 1.6, 1.0, 1.0]}", "model_error.motor_strength[FL]"),
        ("{motor_strength: [1.0, 1.0, 1.0]}", "model_error.motor_strength"),
        ("{command_latency: -0.001}", "model_error.command_latency"),
        ("{command_latency: 0.2}", "model_error.command_latency"),
        ("{foot_contact_stiffness: 0.0}", "model_error.foot_contact_stiffness"),
        ("{foot_contact_dissipation: -1.0}", "model_error.foot_contact_dissipation"),
        ("{foot_contact_relaxation_time: -0.1}", "model_error.foot_contact_relaxation_time"),
        ("{joint_damping: -0.1}", "model_error.joint_damping"),
        ("{joint_friction: 5.0}", "model_error.joint_friction"),
        ("{foot_radius: 0.005}", "model_error.foot_radius"),
        ("{foot_radius: 0.05}", "model_error.foot_radius"),
        ("{payload_mas: 1.0}", "model_error.payload_mas"),
    ],
)
def test_a_bad_model_error_value_raises_naming_the_field(text, field):
    with pytest.raises(ScenarioError, match=re.escape(f"{field}:")):
        load_scenario(scenario_text=f"{{model_error: {text}}}")


def test_hunt_crossley_dissipation_under_sap_is_refused_not_ignored():
    with pytest.raises(ScenarioError, match="model_error.foot_contact_dissipation: SAP"):
        load_scenario(scenario_text="{model_error: {foot_contact_dissipation: 0.5}}")
    text = "{plant_config: {discrete_contact_approximation: similar}, model_error: {foot_contact_dissipation: 0.5}}"
    station = MakeStation(load_scenario(scenario_text=text))
    plant, inspector = station.GetSubsystemByName("plant"), station.GetSubsystemByName("scene_graph").model_inspector()
    for name in robot.FOOT_BODY_NAMES:
        (geometry,) = plant.GetCollisionGeometriesForBody(plant.GetBodyByName(name))
        assert inspector.GetProximityProperties(geometry).GetProperty("material", "hunt_crossley_dissipation") == 0.5


def test_a_bad_model_error_on_the_command_line_exits_2_naming_the_field(tmp_path):
    out = tmp_path / "run"
    done = subprocess.run(
        [sys.executable, "run_sim.py", "--scenario_text", "{model_error: {payload_mass: -1}}", "--out", str(out)],
        cwd=REPO,
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert done.returncode == 2, done.stderr
    assert "model_error.payload_mass" in done.stderr and "Traceback" not in done.stderr
    assert not out.exists()


def test_the_default_scenario_has_no_model_error_and_the_station_is_the_rated_robot():
    assert Scenario().model_error == ModelErrorConfig()
    _, station, plant = _station("{}")
    assert not plant.HasBodyNamed(PAYLOAD_BODY_NAME)
    motors = station.GetSubsystemByName("motors")
    names = {motors.GetSystems()[k].get_name() for k in range(len(motors.GetSystems()))}
    assert names == {"command_guard", "joint_state", "law_inputs", "motor_law", "unitree_torque"}
    inspector = station.GetSubsystemByName("scene_graph").model_inspector()
    for name in robot.FOOT_BODY_NAMES:
        (geometry,) = plant.GetCollisionGeometriesForBody(plant.GetBodyByName(name))
        assert inspector.GetShape(geometry).radius() == robot.FOOT_RADIUS
        assert not inspector.GetProximityProperties(geometry).HasProperty("material", "point_contact_stiffness")


def test_the_payload_adds_its_mass_at_its_offset_from_the_trunk_centre():
    mass, p_BP = 2.5, np.array([0.03, -0.02, 0.04])
    _, _, rated = _station("{}")
    _, _, loaded = _station(f"{{payload_mass: {mass}, payload_offset: {p_BP.tolist()}}}")

    def mass_and_com_in_trunk(plant):
        context = plant.CreateDefaultContext()
        go1 = plant.GetModelInstanceByName(robot.MODEL_INSTANCE_NAME)
        X_WB = plant.GetBodyByName(robot.TRUNK_BODY_NAME).EvalPoseInWorld(context)
        return plant.CalcTotalMass(context, [go1]), X_WB.inverse() @ plant.CalcCenterOfMassPositionInWorld(
            context, [go1]
        )

    m0, c0 = mass_and_com_in_trunk(rated)
    m1, c1 = mass_and_com_in_trunk(loaded)
    assert m0 == pytest.approx(robot.TOTAL_MASS, abs=1e-9)
    assert m1 == pytest.approx(m0 + mass, abs=1e-12)
    np.testing.assert_allclose(c1, (m0 * c0 + mass * p_BP) / (m0 + mass), atol=1e-12)


def test_motor_strength_scales_the_applied_torque_and_the_effort_limit(rng):
    strength = [0.6, 1.0, 0.8, 1.3]
    error = ModelErrorConfig(motor_strength=strength)
    plant, plant_map, motors = _motors(error)
    context = motors.CreateDefaultContext()
    state = rng.normal(size=plant.num_positions() + plant.num_velocities())
    q = plant_map.joint_positions(state[: plant.num_positions()])
    qd = plant_map.joint_velocities(state[plant.num_positions() :])
    command = pack_command(rng.normal(size=12), rng.normal(size=12), 20.0, 1.0, rng.normal(size=12))
    motors.GetInputPort("plant_state").FixValue(context, state)
    motors.GetInputPort("command").FixValue(context, command)
    scale = np.repeat(strength, 3)
    torque = motors.GetOutputPort("torque").Eval(context)
    np.testing.assert_allclose(torque, scale * motor_torque(command, q, qd), rtol=1e-14)
    np.testing.assert_allclose(
        motors.GetOutputPort("actuation").Eval(context), plant_map.actuation(torque, plant.num_actuators()), rtol=1e-14
    )
    saturating = pack_command(q + 10.0, 0, 1000.0, 0, 0)
    motors.GetInputPort("command").FixValue(context, saturating)
    np.testing.assert_allclose(motors.GetOutputPort("torque").Eval(context), scale * robot.EFFORT_LIMIT, rtol=1e-14)


@pytest.mark.parametrize("latency, steps", [(0.0, 0), (0.001, 1), (0.003, 3), (0.0074, 7), (0.0075, 8)])
def test_command_latency_delays_the_command_by_whole_plant_steps(latency, steps):
    scenario, station, _ = _station(f"{{command_latency: {latency}}}", robot_text="{initial_pose: lying}")
    dt = scenario.plant_config.time_step
    assert scenario.model_error.latency_steps(dt) == steps
    context = station.CreateDefaultContext()
    simulator = Simulator(station, context)
    sent = 1.0 + 0.1 * np.arange(steps + 4)
    applied = []
    for k, tau in enumerate(sent):
        # Pure feed-forward torque, a new value every plant step: what the motors apply does not
        # depend on the state, and tells which step's command it is.
        station.GetInputPort("go1.command").FixValue(context, pack_command(0, 0, 0, 0, np.full(12, tau)))
        applied.append(station.GetOutputPort("sim.motor_torque").Eval(context)[0])  # for the step from k dt
        simulator.AdvanceTo((k + 1) * dt)
    np.testing.assert_array_equal(applied[steps:], sent[: len(sent) - steps])
    if steps >= 2:
        assert applied[:steps] == [0.0] * steps  # nothing has come through yet


def test_joint_damping_and_friction_oppose_the_motion_and_the_motors_report_their_own_torque(rng):
    error = ModelErrorConfig(joint_damping=0.2, joint_friction=0.3)
    plant, plant_map, motors = _motors(error)
    context = motors.CreateDefaultContext()
    qd = np.concatenate([rng.uniform(-3.0, 3.0, 10), [0.5 * FRICTION_VELOCITY_BAND, -0.02]])
    v = plant_map.full_velocities(np.zeros(3), np.zeros(3), qd, plant.num_velocities())
    q = plant_map.full_positions([1.0, 0.0, 0.0, 0.0], np.zeros(3), robot.STANDING_Q, plant.num_positions())
    motors.GetInputPort("plant_state").FixValue(context, np.concatenate([q, v]))
    motors.GetInputPort("command").FixValue(context, pack_command(0, 0, 0, 0, 0))  # motors apply nothing
    net = motors.GetOutputPort("actuation").Eval(context)[plant_map.u_index]
    assert np.all(net * qd < 0.0)
    np.testing.assert_allclose(net, -joint_loss_torque(qd, 0.2, 0.3), rtol=1e-14)
    assert abs(net[-2]) == pytest.approx(0.2 * qd[-2] + 0.3 * 0.5)  # inside the band: half the friction
    np.testing.assert_array_equal(motors.GetOutputPort("torque").Eval(context), 0.0)


def _standing_sink(model_error: str, hold: float = 1.0) -> tuple[float, float]:
    """(mean foot sink into the ground [m], total foot force [N]) after a PD hold of the standing pose."""
    scenario, station, plant = _station(model_error)
    context = station.CreateDefaultContext()
    station.GetInputPort("go1.command").FixValue(context, pack_command(robot.STANDING_Q, 0, 60.0, 2.0, 0))
    Simulator(station, context).AdvanceTo(hold)
    plant_context = plant.GetMyContextFromRoot(context)
    z = [plant.GetBodyByName(name).EvalPoseInWorld(plant_context).translation()[2] for name in robot.FOOT_BODY_NAMES]
    force = station.GetOutputPort("go1.foot_contact").Eval(context).sum()
    return scenario.model_error.foot_radius - float(np.mean(z)), float(force)


def test_a_soft_foot_sinks_about_17_mm_under_the_standing_robot():
    rigid, rigid_force = _standing_sink("{}")
    soft, soft_force = _standing_sink(f"{{foot_contact_stiffness: {SOFT_FOOT_STIFFNESS}}}")
    assert rigid < 0.001, f"{1000 * rigid:.2f} mm"
    assert soft == pytest.approx(0.017, abs=0.001), f"{1000 * soft:.2f} mm"
    for force in (rigid_force, soft_force):
        assert force == pytest.approx(WEIGHT, rel=0.03)


def test_foot_contact_properties_reach_the_foot_geometry():
    text = "{foot_contact_stiffness: 5000.0, foot_contact_relaxation_time: 0.02}"
    _, station, plant = _station(text)
    inspector = station.GetSubsystemByName("scene_graph").model_inspector()
    for name in robot.FOOT_BODY_NAMES:
        (geometry,) = plant.GetCollisionGeometriesForBody(plant.GetBodyByName(name))
        properties = inspector.GetProximityProperties(geometry)
        assert properties.GetProperty("material", "point_contact_stiffness") == 5000.0
        assert properties.GetProperty("material", "relaxation_time") == 0.02
        assert properties.HasProperty("material", "coulomb_friction")  # the foot's own friction stays


def test_the_foot_radius_changes_the_plant_feet_and_their_start_height_only():
    radius = 0.023
    _, station, plant = _station(f"{{foot_radius: {radius}}}")
    inspector = station.GetSubsystemByName("scene_graph").model_inspector()
    for name in robot.FOOT_BODY_NAMES:
        body = plant.GetBodyByName(name)
        for geometry in plant.GetCollisionGeometriesForBody(body) + plant.GetVisualGeometriesForBody(body):
            shape = inspector.GetShape(geometry)
            assert isinstance(shape, Sphere) and shape.radius() == radius
    context = station.CreateDefaultContext()
    query = station.GetOutputPort("sim.query_object").Eval(context)
    assert max((pair.depth for pair in query.ComputePointPairPenetration()), default=0.0) < 1e-4
    plant_context = plant.GetMyContextFromRoot(context)
    z = plant.GetBodyByName(robot.FOOT_BODY_NAMES[0]).EvalPoseInWorld(plant_context).translation()[2]
    assert z == pytest.approx(radius, abs=0.001)
    # The controllers' model keeps its own foot.
    assert robot.FOOT_RADIUS == 0.02
