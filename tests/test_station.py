"""The simulated station: port parity with docs/conventions.md, standing, sensors."""

import numpy as np
import pytest
from pydrake.lcm import DrakeLcm
from pydrake.systems.analysis import Simulator

from pedi_drake import robot
from pedi_drake.diagram import MakePedipulationDiagram
from pedi_drake.go1_command import COMMAND_SIZE, pack_command
from pedi_drake.go1_driver.config import Go1DriverConfig
from pedi_drake.go1_driver.hardware_station import MakeHardwareStation
from pedi_drake.go1_driver.link import DrakeLcmTransport, Go1Link
from pedi_drake.scenario import Scenario, load_scenario
from pedi_drake.station.motor_model import Go1MotorModel, _guard_kernel, guarded_command, motor_torque
from pedi_drake.station_interface import STATION_PORTS, MakeStation

STAND_HOLD_START = 2.0  # [s] the stand blend (1.5 s) is over and the trunk has settled.
STAND_END = 5.0  # [s] 3 s of holding.


def _go1_ports(system):
    ports = {}
    for i in range(system.num_input_ports()):
        port = system.get_input_port(i)
        ports[port.get_name()] = ("input", port.size())
    for i in range(system.num_output_ports()):
        port = system.get_output_port(i)
        ports[port.get_name()] = ("output", port.size())
    return {name: value for name, value in ports.items() if name.startswith("go1.")}


def test_station_exports_exactly_the_documented_go1_ports():
    station = MakeStation(Scenario())
    assert _go1_ports(station) == STATION_PORTS


def test_hardware_station_exports_the_same_ports():
    config = Go1DriverConfig()
    station = MakeHardwareStation(config, Go1Link(DrakeLcmTransport(DrakeLcm("memq://")), config, threaded=False))
    assert _go1_ports(station) == STATION_PORTS


def test_motor_model_clamps_to_effort_limits_and_zeroes_non_finite_commands():
    q = np.zeros(12)
    huge = motor_torque(pack_command(np.full(12, 10.0), 0, 1000.0, 0, 0), q, q)
    np.testing.assert_array_equal(huge, robot.EFFORT_LIMIT)
    command = pack_command(0, 0, 0, 0, np.full(12, 1.0))
    command[48] = np.nan
    tau = motor_torque(command, q, q)
    assert tau[0] == 0.0 and np.all(tau[1:] == 1.0)


def test_the_motor_model_system_applies_the_motor_law_in_plant_order():
    plant, plant_map = robot.make_go1_plant()
    motors = Go1MotorModel(plant_map, plant.num_positions(), plant.num_velocities(), plant.num_actuators())
    context = motors.CreateDefaultContext()
    rng = np.random.default_rng(3)
    state = rng.normal(size=plant.num_positions() + plant.num_velocities())
    q = plant_map.joint_positions(state[: plant.num_positions()])
    qd = plant_map.joint_velocities(state[plant.num_positions() :])
    command = pack_command(rng.normal(size=12), rng.normal(size=12), 40.0, 1.5, 5.0 * rng.normal(size=12))
    command[40] = np.inf  # motor 4's kd: that motor gets no torque
    motors.GetInputPort("command").FixValue(context, command)
    motors.GetInputPort("plant_state").FixValue(context, state)
    expected = motor_torque(command, q, qd)
    assert expected[4] == 0.0 and np.count_nonzero(expected) == 11
    np.testing.assert_allclose(motors.GetOutputPort("torque").Eval(context), expected, rtol=1e-14)
    np.testing.assert_allclose(
        motors.GetOutputPort("actuation").Eval(context),
        plant_map.actuation(expected, plant.num_actuators()),
        rtol=1e-14,
    )


def test_the_command_guard_kernel_equals_guarded_command():
    """MotorCommandGuard's compiled kernel against the reference, exactly, on commands with
    non-finite, huge and ordinary entries (the kernel runs once per controller tick)."""
    rng = np.random.default_rng(4)
    for trial in range(200):
        command = rng.normal(scale=10.0 ** rng.integers(0, 8), size=COMMAND_SIZE)
        for k in rng.integers(0, COMMAND_SIZE, size=rng.integers(0, 4)):
            command[k] = rng.choice([np.nan, np.inf, -np.inf, 1e300, -1e300])
        out = np.full(COMMAND_SIZE, np.nan)
        _guard_kernel(command, out)
        np.testing.assert_array_equal(out, guarded_command(command), err_msg=f"trial {trial}")


@pytest.fixture(scope="module")
def standing_run():
    scenario = load_scenario(scenario_name="stand", scenario_text=f"{{simulation_duration: {STAND_END}}}")
    built = MakePedipulationDiagram(scenario)
    simulator = Simulator(built.diagram)
    simulator.AdvanceTo(STAND_END)
    context = simulator.get_context()
    log = built.logs(context)["sim.plant_state"]
    plant = built.diagram.GetSubsystemByName("station").GetSubsystemByName("plant")
    return plant, log.times, log.data, built, context


def test_standing_holds_trunk_height_within_1cm_of_commanded_pose(standing_run):
    plant, t, x, _, _ = standing_run
    plant_map = robot.Go1PlantMap.from_plant(plant)
    target = robot.trunk_height_for(0.9, -1.8)
    hold = t >= STAND_HOLD_START
    height = x[plant_map.base_q_start + 6, hold]
    assert np.max(np.abs(height - target)) < 0.01, f"height {height.min():.4f}..{height.max():.4f}, target {target:.4f}"


def test_standing_feet_stay_within_5mm_of_where_they_landed(standing_run):
    plant, t, x, _, _ = standing_run
    context = plant.CreateDefaultContext()
    hold = np.nonzero(t >= STAND_HOLD_START)[0]
    feet = []
    for k in hold:
        plant.SetPositionsAndVelocities(context, x[:, k])
        feet.append([plant.GetBodyByName(f).EvalPoseInWorld(context).translation() for f in robot.FOOT_BODY_NAMES])
    feet = np.array(feet)
    assert np.max(np.linalg.norm(feet - feet[0], axis=2)) < 0.005


def test_standing_sensors_report_weight_on_feet_and_gravity_on_accelerometer(standing_run):
    _, _, _, built, context = standing_run
    diagram = built.diagram
    station = diagram.GetSubsystemByName("station")
    station_context = station.GetMyContextFromRoot(context)
    forces = station.GetOutputPort("go1.foot_contact").Eval(station_context)
    assert np.sum(forces) == pytest.approx(robot.TOTAL_MASS * 9.81, rel=0.03)
    imu = station.GetOutputPort("go1.imu").Eval(station_context)
    assert np.linalg.norm(imu[:4]) == pytest.approx(1.0)
    np.testing.assert_allclose(imu[7:10], [0, 0, 9.81], atol=0.3)
    np.testing.assert_allclose(imu[4:7], 0.0, atol=0.05)


def test_sensor_noise_is_seeded_and_reproducible():
    def measure(seed):
        scenario = load_scenario(
            scenario_name="stand", scenario_text=f"{{random_seed: {seed}, sensor_noise: {{enabled: true}}}}"
        )
        station = MakeStation(scenario)
        context = station.CreateDefaultContext()
        station.GetInputPort("go1.command").FixValue(context, pack_command(robot.LYING_Q, 0, 20, 1, 0))
        Simulator(station, context).AdvanceTo(0.05)
        return station.GetOutputPort("go1.position_measured").Eval(context).copy()

    a, b, c = measure(1), measure(1), measure(2)
    np.testing.assert_array_equal(a, b)
    assert not np.array_equal(a, c)


@pytest.mark.parametrize("robot_text", ["{}", "{prongs: {}}"], ids=["plain", "prongs"])
def test_lying_start_rests_on_the_ground_without_penetration(robot_text):
    """The lying robot (on its prongs, if it has them) starts out of the floor and is not thrown up.

    A pose that starts with a prong inside the floor gets the trunk ejected by the contact forces.
    (Without prongs the folded legs settle by about 2 cm under these gains: it may sink, not rise.)
    """
    from pedi_drake.station.initial_state import initial_joint_positions

    scenario = load_scenario(scenario_text=f"{{robot: {robot_text}}}")
    station = MakeStation(scenario)
    context = station.CreateDefaultContext()
    q0 = initial_joint_positions(scenario.robot)
    station.GetInputPort("go1.command").FixValue(context, pack_command(q0, 0, 60, 2, 0))
    query = station.GetOutputPort("sim.query_object").Eval(context)
    deepest = max((pair.depth for pair in query.ComputePointPairPenetration()), default=0.0)
    assert deepest < 1e-4, f"{deepest * 1000:.1f} mm penetration at the start"
    p_start = station.GetOutputPort("sim.plant_state").Eval(context)[4:7].copy()
    Simulator(station, context).AdvanceTo(0.3)
    p_end = station.GetOutputPort("sim.plant_state").Eval(context)[4:7]
    assert p_end[2] - p_start[2] < 0.002, (p_start, p_end)
    assert np.linalg.norm(p_end[:2] - p_start[:2]) < 0.005, (p_start, p_end)


def test_logged_sensors_start_at_their_initial_values():
    """Sensor logs go through a LogHold: the t = 0 sample is the initial reading, not the hold's zeros."""
    scenario = load_scenario(scenario_name="stand", scenario_text="{estimator: kalman, simulation_duration: 0.1}")
    built = MakePedipulationDiagram(scenario)
    simulator = Simulator(built.diagram)
    context = simulator.get_mutable_context()
    imu_0 = built.diagram.GetOutputPort("go1.imu").Eval(context).copy()
    simulator.AdvanceTo(0.1)
    log = built.logs(context)["go1.imu"]
    assert log.times[0] == 0.0
    np.testing.assert_allclose(log.data[:, 0], imu_0)
    assert abs(np.linalg.norm(log.data[0:4, -1]) - 1.0) < 1e-9  # a unit quaternion every sample
