"""The station's one-callback plant readings against the reference sensors, bit for bit.

`PlantReadings` computes the IMU, foot sensors, torque estimate and contact ground truth with
one compiled kernel; `sensors.imu_reading`, `sensors.foot_normal_forces`,
`sensors.foot_contact_forces_W` and `scene_contact.scene_contact_forces` are the same maths in
numpy on the plant's objects. They must agree exactly (not to a tolerance), with and without
noise, on random contacts and on the contacts of a simulated mission.
"""

import numpy as np
import pytest
from pydrake.geometry import PenetrationAsPointPair
from pydrake.multibody.plant import PointPairContactInfo
from pydrake.multibody.tree import BodyIndex
from pydrake.systems.analysis import Simulator

from pedi_drake import robot
from pedi_drake.diagram import MakePedipulationDiagram, apply_mission
from pedi_drake.mission.spec import load_mission
from pedi_drake.scenario import load_scenario
from pedi_drake.station.plant_readings import (
    FOOT_CHANNEL,
    IMU_CHANNEL,
    TORQUE_CHANNEL,
    _readings_kernel,
    readings_sizes,
)
from pedi_drake.station.scene_contact import ROBOT_CONTACT_SOURCES, scene_contact_forces
from pedi_drake.station.sensors import foot_contact_forces_W, foot_index_of_body, foot_normal_forces, imu_reading
from pedi_drake.station.sim_station import MakeSimulationStation

MISSION = "hit_target_front"  # a mission with a scene object


def _scenario(noise: bool, seed: int = 7, with_scene: bool = True):
    """The mission's scenario; `with_scene`: with its scene objects (as MakePedipulationDiagram
    applies them)."""
    scenario = load_scenario(
        scenario_text=f"{{mission: {MISSION}, random_seed: {seed}, sensor_noise: {{enabled: {str(noise).lower()}}}}}"
    )
    return apply_mission(scenario, load_mission(scenario.mission)) if with_scene else scenario


class _Contacts:
    """Duck-typed ContactResults over a list of PointPairContactInfo (pydrake cannot fill one)."""

    def __init__(self, infos):
        self._infos = infos

    def num_point_pair_contacts(self) -> int:
        return len(self._infos)

    def point_pair_contact_info(self, i: int) -> PointPairContactInfo:
        return self._infos[i]


class _Reference:
    """The reference sensors' inputs for the station's plant: body maps as the old systems made them."""

    def __init__(self, station, scenario):
        plant = station.GetSubsystemByName("plant")
        self.plant = plant
        self.map = robot.Go1PlantMap.from_plant(plant)
        model = self.map.model
        feet = [plant.GetBodyByName(name, model).index() for name in robot.FOOT_BODY_NAMES]
        self.foot_of_body = foot_index_of_body(feet)
        self.source_of_body = {
            int(body): self.foot_of_body.get(int(body), len(feet)) for body in plant.GetBodyIndices(model)
        }
        self.scene_names = [obj.instance_name for obj in scenario.scene]
        self.object_of_body = {
            int(body): k
            for k, name in enumerate(self.scene_names)
            for body in plant.GetBodyIndices(plant.GetModelInstanceByName(name))
        }
        trunk = plant.GetBodyByName(robot.TRUNK_BODY_NAME, model)
        imu = plant.GetBodyByName(robot.IMU_BODY_NAME, model)
        nq = plant.num_positions()
        a0 = trunk.floating_velocities_start_in_v()
        self.starts = (trunk.floating_positions_start(), nq + a0, a0, a0 + 3)
        context = plant.CreateDefaultContext()
        self.p_BI = plant.CalcRelativeTransform(context, trunk.body_frame(), imu.body_frame()).translation()
        self.gravity_W = plant.gravity_field().gravity_vector()
        self.noise, self.seed = scenario.sensor_noise, scenario.random_seed

    def readings(self, x, vdot, torque, contacts, sample) -> dict[str, np.ndarray]:
        """{station port: value} as the reference functions compute them."""
        noise = self.noise if self.noise.enabled else None

        def rng(channel):
            return np.random.default_rng((self.seed, sample, channel)) if noise else None

        tau = torque.copy()
        feet = foot_normal_forces(contacts, self.foot_of_body)
        if noise:
            tau = tau + rng(TORQUE_CHANNEL).normal(0.0, noise.joint_torque, 12)
        imu = imu_reading(x, vdot, self.starts, self.p_BI, self.gravity_W, rng(IMU_CHANNEL), noise)
        if noise:
            feet = np.maximum(feet + rng(FOOT_CHANNEL).normal(0.0, noise.foot_force, 4), 0.0)
        return {
            "go1.imu": imu,
            "go1.foot_contact": feet,
            "go1.torque_estimated": tau,
            "sim.foot_contact_forces": foot_contact_forces_W(contacts, self.foot_of_body).ravel(),
            "sim.scene_contact_forces": scene_contact_forces(
                contacts, self.source_of_body, self.object_of_body, len(self.scene_names)
            ),
        }


def _split(readings: np.ndarray, num_objects: int) -> dict[str, np.ndarray]:
    out, start = {}, 0
    for name, size in readings_sizes(num_objects).items():
        out[name] = readings[start : start + size]
        start += size
    return out


def _random_contacts(rng, reference: _Reference, n: int) -> _Contacts:
    """n contacts between random bodies: feet, other robot bodies, scene objects, the world."""
    bodies = [0, *reference.source_of_body, *reference.object_of_body]
    infos = []
    for _ in range(n):
        a, b = rng.choice(bodies, 2)
        pair = PenetrationAsPointPair()
        normal = rng.normal(size=3)
        pair.nhat_BA_W = normal / np.linalg.norm(normal)
        force = rng.normal(scale=50.0, size=3)
        infos.append(PointPairContactInfo(BodyIndex(int(a)), BodyIndex(int(b)), force, np.zeros(3), 0.0, 0.0, pair))
    return _Contacts(infos)


@pytest.mark.parametrize("noise", [False, True], ids=["exact", "noisy"])
def test_readings_equal_the_reference_sensors_on_random_contacts(noise):
    scenario = _scenario(noise)
    assert scenario.scene, "the test needs a scene object"
    station = MakeSimulationStation(scenario)
    readings = station.GetSubsystemByName("readings")
    reference = _Reference(station, scenario)
    plant = reference.plant
    rng = np.random.default_rng(11)
    out = np.zeros(sum(readings.sizes.values()))
    for trial in range(60):
        x = rng.normal(size=plant.num_positions() + plant.num_velocities())
        vdot = rng.normal(scale=5.0, size=plant.num_velocities())
        torque = rng.normal(scale=10.0, size=12)
        # 40 contacts in some trials: more than the readings' buffers hold at first.
        contacts = _random_contacts(rng, reference, int(rng.integers(0, 40 if trial % 10 == 0 else 12)))
        sample = int(rng.integers(0, 10_000))
        readings.read(x, vdot, torque, contacts, sample, out)
        expected = reference.readings(x, vdot, torque, contacts, sample)
        for name, value in _split(out, len(reference.scene_names)).items():
            np.testing.assert_array_equal(value, expected[name], err_msg=f"{name}, trial {trial}")


@pytest.mark.parametrize("noise", [False, True], ids=["exact", "noisy"])
def test_station_ports_equal_the_reference_sensors_in_a_simulated_mission(noise):
    """The closed loop's own contacts and state, at several instants of the mission's start."""
    scenario = _scenario(noise)
    built = MakePedipulationDiagram(_scenario(noise, with_scene=False))
    station = built.diagram.GetSubsystemByName("station")
    reference = _Reference(station, scenario)
    plant = reference.plant
    simulator = Simulator(built.diagram)
    context = simulator.get_mutable_context()
    station_context = station.GetMyContextFromRoot(context)
    plant_context = plant.GetMyContextFromRoot(context)
    period = plant.time_step()
    contacts_seen = 0
    for t in np.arange(0.0, 2.0, 0.25):
        simulator.AdvanceTo(t)
        x = station.GetOutputPort("sim.plant_state").Eval(station_context).copy()
        vdot = plant.get_generalized_acceleration_output_port().Eval(plant_context).copy()
        torque = station.GetOutputPort("sim.motor_torque").Eval(station_context).copy()
        contacts = station.GetOutputPort("sim.contact_results").Eval(station_context)
        contacts_seen += contacts.num_point_pair_contacts()
        sample = int(round(context.get_time() / period))
        expected = reference.readings(x, vdot, torque, contacts, sample)
        for name, value in expected.items():
            np.testing.assert_array_equal(station.GetOutputPort(name).Eval(station_context), value, err_msg=name)
    assert contacts_seen > 0


def test_readings_kernel_equals_its_interpreted_code():
    """The compiled kernel against `.py_func` on random inputs (a model without Drake objects)."""
    rng = np.random.default_rng(5)
    num_bodies, num_objects = 9, 2
    body_maps = np.full((3, num_bodies), -1, dtype=np.int64)
    body_maps[0, 1:5] = np.arange(4)
    body_maps[1, 1:7] = [0, 1, 2, 3, 4, 4]
    body_maps[2, 7:9] = [0, 1]
    starts = np.array([0, 7, 0, 3, len(ROBOT_CONTACT_SOURCES)])
    size = sum(readings_sizes(num_objects).values())
    for _ in range(30):
        n = int(rng.integers(0, 20))
        x, vdot, torque = rng.normal(size=13), rng.normal(size=6), rng.normal(size=12)
        bodies = rng.integers(0, num_bodies, size=(n, 2))
        forces, normals = rng.normal(size=(n, 3)), rng.normal(size=(n, 3))
        constants = rng.normal(size=6)
        outputs = []
        for function in (_readings_kernel, _readings_kernel.py_func):
            out, R_WB = np.full(size, np.nan), np.zeros((3, 3))
            function(x, vdot, torque, bodies, forces, normals, n, body_maps, starts, constants, out, R_WB)
            outputs.append((out[4:], R_WB))
        np.testing.assert_allclose(outputs[0][0], outputs[1][0], rtol=1e-12, atol=1e-12)
        np.testing.assert_allclose(outputs[0][1], outputs[1][1], rtol=1e-12, atol=1e-12)
