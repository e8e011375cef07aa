"""PlantReadings: what the simulated station reads off the plant at an instant, in one callback.

The Go1's IMU, foot force sensors and torque estimate (`go1.imu`, `go1.foot_contact`,
`go1.torque_estimated`) and the simulation's ground truth of contact (`sim.foot_contact_forces`,
`sim.scene_contact_forces`) are functions of the same plant outputs at the same instant, read
together every control tick (by the estimator, the mission manager and the log's hold). One
output port, `readings` (layout `readings_sizes`), computes them all: one pass over the contact
results (the pybind calls that cost most), one compiled kernel for the maths, then the sensor
noise; a C++ Demultiplexer (see `MakeSimulationStation`) splits it into the station's ports.
Five Python output ports of their own would pay three passes over the contact results and a
callback with its Evals per port, every control tick.

The kernel is the reference functions of `pedi_drake.station.sensors` and
`pedi_drake.station.scene_contact` operation by operation (the same sums in the same order,
`np.dot` where they use numpy's), so the readings are bit-identical to theirs; the tests compare
them on simulated and random contacts. The noise is drawn as the sensors always drew it: a
generator seeded by (scenario seed, sample index, channel) per signal, so the same seed gives the
same numbers and the readings keep no hidden state.
"""

import numpy as np
from pydrake.common.value import AbstractValue
from pydrake.math import RotationMatrix
from pydrake.multibody.plant import ContactResults, MultibodyPlant
from pydrake.systems.framework import BasicVector, Context

from pedi_drake import robot
from pedi_drake.leaf_system import LeafSystemWithoutWitnesses
from pedi_drake.runtime.jit import kernel
from pedi_drake.scenario import SensorNoiseConfig
from pedi_drake.station.scene_contact import ROBOT_CONTACT_SOURCES
from pedi_drake.vector3 import axis_angle_matrix, rotation_matrix_kernel

IMU_SIZE = 10  # quaternion w, x, y, z; gyro (3); accelerometer (3)
NUM_FEET = 4
# Noise channels of the sensors' generators (seeded by scenario seed, sample, channel): the
# joint encoders draw channels 0 (positions) and 1 (velocities), see JointEncoders.
TORQUE_CHANNEL, IMU_CHANNEL, FOOT_CHANNEL = 2, 3, 4


def readings_sizes(num_objects: int) -> dict[str, int]:
    """{signal: size} of `readings` in order: the station's port names, `num_objects` scene objects."""
    return {
        "go1.imu": IMU_SIZE,
        "go1.foot_contact": NUM_FEET,
        "go1.torque_estimated": 12,
        "sim.foot_contact_forces": 3 * NUM_FEET,
        "sim.scene_contact_forces": num_objects * len(ROBOT_CONTACT_SOURCES),
    }


# Offsets of the blocks in `readings` (the scene block, last, has the scene's size).
_FOOT_AT = IMU_SIZE
_TORQUE_AT = _FOOT_AT + NUM_FEET
_FEET_W_AT = _TORQUE_AT + 12
_SCENE_AT = _FEET_W_AT + 3 * NUM_FEET


@kernel
def _readings_kernel(x, vdot, torque, bodies, forces, normals, num_contacts, body_maps, starts, constants, out, R_WB):
    """Fills `out` (readings without the quaternion, out[0:4]) and R_WB (the trunk's rotation).

    starts: quaternion in x, w_WB in x, alpha_WB in vdot, a_WB in vdot, number of contact
    sources per object; constants: p_BI (3), gravity_W (3); body_maps rows: foot number,
    contact source, scene object of each body index (-1: none); bodies (n, 2): the contacts'
    body A and B; forces (n, 3): contact force on B, world [N]; normals (n, 3): nhat_BA_W.
    """
    # The IMU (sensors.imu_reading).
    q0 = starts[0]
    R_WB[:, :] = rotation_matrix_kernel(x[q0 : q0 + 4])
    w_W, alpha_W, p_BI = np.empty(3), np.empty(3), np.empty(3)
    for k in range(3):
        w_W[k] = x[starts[1] + k]
        alpha_W[k] = vdot[starts[2] + k]
        p_BI[k] = constants[k]
    p = np.dot(R_WB, p_BI)
    # cross3(alpha_W, p), cross3(w_W, p), then cross3(w_W, w x p), as in the reference.
    c1 = np.array(
        [
            alpha_W[1] * p[2] - alpha_W[2] * p[1],
            alpha_W[2] * p[0] - alpha_W[0] * p[2],
            alpha_W[0] * p[1] - alpha_W[1] * p[0],
        ]
    )
    wp = np.array([w_W[1] * p[2] - w_W[2] * p[1], w_W[2] * p[0] - w_W[0] * p[2], w_W[0] * p[1] - w_W[1] * p[0]])
    c2 = np.array([w_W[1] * wp[2] - w_W[2] * wp[1], w_W[2] * wp[0] - w_W[0] * wp[2], w_W[0] * wp[1] - w_W[1] * wp[0]])
    specific = np.empty(3)
    for k in range(3):
        specific[k] = ((vdot[starts[3] + k] + c1[k]) + c2[k]) - constants[3 + k]
    gyro = np.dot(R_WB.T, w_W)
    accel = np.dot(R_WB.T, specific)
    for k in range(3):
        out[4 + k] = gyro[k]
        out[7 + k] = accel[k]
    # The torque estimate, the foot sensors and the true contact forces.
    for k in range(12):
        out[_TORQUE_AT + k] = torque[k]
    for k in range(_TORQUE_AT - _FOOT_AT):
        out[_FOOT_AT + k] = 0.0
    for k in range(_FEET_W_AT, out.shape[0]):
        out[k] = 0.0
    sources = starts[4]
    for i in range(num_contacts):
        a, b = bodies[i, 0], bodies[i, 1]
        f, n = forces[i], normals[i]
        # Foot sensors (sensors.foot_normal_forces): the normal force, scalar sum as there.
        foot_a, foot_b = body_maps[0, a], body_maps[0, b]
        if foot_a >= 0 or foot_b >= 0:
            normal = abs(f[0] * n[0] + f[1] * n[1] + f[2] * n[2])
            if foot_a >= 0:
                out[_FOOT_AT + foot_a] += normal
            if foot_b >= 0:
                out[_FOOT_AT + foot_b] += normal
        # True foot forces (sensors.foot_contact_forces_W): B feels f, A its opposite.
        if foot_b >= 0:
            for k in range(3):
                out[_FEET_W_AT + 3 * foot_b + k] += f[k]
        if foot_a >= 0:
            for k in range(3):
                out[_FEET_W_AT + 3 * foot_a + k] -= f[k]
        # Robot against scene objects (scene_contact.scene_contact_forces), np.dot as there.
        source, obj = body_maps[1, a], body_maps[2, b]
        if source < 0 or obj < 0:
            source, obj = body_maps[1, b], body_maps[2, a]
        if source >= 0 and obj >= 0:
            out[_SCENE_AT + obj * sources + source] += abs(np.dot(f, n))


class PlantReadings(LeafSystemWithoutWitnesses):
    """Plant outputs -> `readings`: imu, foot_contact, torque_estimated, foot_contact_forces,
    scene_contact_forces (readings_sizes), with the scenario's sensor noise.

    Inputs: plant_state, generalized_acceleration, contact_results, motor_torque (12, Unitree order).
    """

    def __init__(
        self,
        plant: MultibodyPlant,
        plant_map: robot.Go1PlantMap,
        scene_names: list[str],
        noise: SensorNoiseConfig,
        seed: int,
        sample_period: float,
    ):
        super().__init__()
        self._noise, self._seed, self._period = noise, int(seed), sample_period
        trunk = plant.GetBodyByName(robot.TRUNK_BODY_NAME, plant_map.model)
        imu = plant.GetBodyByName(robot.IMU_BODY_NAME, plant_map.model)
        if not trunk.is_floating_base_body() or not trunk.has_quaternion_dofs():
            raise ValueError(f"PlantReadings: the trunk {trunk.name()!r} must be a quaternion floating body")
        # The trunk's floating joint: q = [quaternion R_WB (w, x, y, z), p_WB], v = [w_WB, v_WB]
        # (world frame), so its slices of the state and of vdot are the trunk's pose, velocity
        # and acceleration: cheaper to read than the plant's per-body output ports.
        nq = plant.num_positions()
        a_start = trunk.floating_velocities_start_in_v()
        self._starts = np.array(
            [trunk.floating_positions_start(), nq + a_start, a_start, a_start + 3, len(ROBOT_CONTACT_SOURCES)]
        )
        # The IMU is welded to the trunk with the trunk's orientation: its offset p_BI matters.
        context = plant.CreateDefaultContext()
        p_BI = plant.CalcRelativeTransform(context, trunk.body_frame(), imu.body_frame()).translation()
        self._constants = np.concatenate([p_BI, plant.gravity_field().gravity_vector()])
        self._body_maps = contact_body_maps(plant, plant_map, scene_names)
        self.sizes = readings_sizes(len(scene_names))
        self._state = self.DeclareVectorInputPort("plant_state", nq + plant.num_velocities())
        self._vdot = self.DeclareVectorInputPort("generalized_acceleration", plant.num_velocities())
        self._contacts = self.DeclareAbstractInputPort("contact_results", AbstractValue.Make(ContactResults()))
        self._torque = self.DeclareVectorInputPort("motor_torque", 12)
        self.DeclareVectorOutputPort("readings", sum(self.sizes.values()), self._calc)
        self._R_WB = np.zeros((3, 3))
        self._grow_contacts(16)
        self.warm_up()

    def _grow_contacts(self, n: int) -> None:
        self._bodies = np.zeros((n, 2), dtype=np.int64)
        self._forces, self._normals = np.zeros((n, 3)), np.zeros((n, 3))

    def warm_up(self) -> None:
        """Compiles (or loads) the kernel now, with the argument types of a tick, not in the first tick."""
        out = np.zeros(sum(self.sizes.values()))
        x, vdot = np.zeros(self._state.size()), np.zeros(self._vdot.size())
        x[self._starts[0]] = 1.0
        self._bodies[0] = [0, 0]
        _readings_kernel(
            x, vdot, np.zeros(12), self._bodies, self._forces, self._normals, 1, self._body_maps,
            self._starts, self._constants, out, self._R_WB,
        )  # fmt: skip

    def _calc(self, context: Context, output: BasicVector) -> None:
        self.read(
            self._state.Eval(context),
            self._vdot.Eval(context),
            self._torque.Eval(context),
            self._contacts.Eval(context),
            int(round(context.get_time() / self._period)),
            output.get_mutable_value(),
        )

    def read(
        self, x: np.ndarray, vdot: np.ndarray, torque: np.ndarray, results: ContactResults, sample: int, out: np.ndarray
    ) -> None:
        """`readings` into `out` from the plant state x, accelerations vdot, motor torques [N m]
        and contact results at sample number `sample` (time / period: it seeds the noise)."""
        n = results.num_point_pair_contacts()
        if n > len(self._bodies):
            self._grow_contacts(2 * n)
        bodies, forces, normals = self._bodies, self._forces, self._normals
        for i in range(n):
            info = results.point_pair_contact_info(i)
            bodies[i, 0], bodies[i, 1] = int(info.bodyA_index()), int(info.bodyB_index())
            forces[i] = info.contact_force()
            normals[i] = info.point_pair().nhat_BA_W
        R_WB = self._R_WB
        _readings_kernel(
            x, vdot, torque, bodies, forces, normals, n, self._body_maps, self._starts, self._constants, out, R_WB
        )
        if self._noise.enabled:
            self._add_noise(sample, out)
        else:
            out[0:4] = RotationMatrix(R_WB).ToQuaternion().wxyz()

    def _rng(self, sample: int, channel: int) -> np.random.Generator:
        return np.random.default_rng((self._seed, sample, channel))

    def _add_noise(self, sample: int, out: np.ndarray) -> None:
        """The sensors' noise, drawn and added as the reference sensors do (the same numbers)."""
        noise = self._noise
        torque = slice(_TORQUE_AT, _TORQUE_AT + 12)
        out[torque] = out[torque] + self._rng(sample, TORQUE_CHANNEL).normal(0.0, noise.joint_torque, 12)
        rng = self._rng(sample, IMU_CHANNEL)
        R_WB = self._R_WB @ axis_angle_matrix(rng.normal(0.0, noise.orientation, 3))
        out[4:7] = out[4:7] + rng.normal(0.0, noise.gyro, 3)
        out[7:10] = out[7:10] + rng.normal(0.0, noise.accelerometer, 3)
        out[0:4] = RotationMatrix(R_WB).ToQuaternion().wxyz()
        feet = slice(_FOOT_AT, _FOOT_AT + NUM_FEET)
        out[feet] = np.maximum(out[feet] + self._rng(sample, FOOT_CHANNEL).normal(0.0, noise.foot_force, 4), 0.0)


def contact_body_maps(plant: MultibodyPlant, plant_map: robot.Go1PlantMap, scene_names: list[str]) -> np.ndarray:
    """(3, num_bodies) by body index: foot number (FR, FL, RR, RL), contact source (ROBOT_CONTACT_SOURCES:
    the feet, then any other body of the robot) and scene object number (in `scene_names`'
    order); -1 where a body is none of them."""
    maps = np.full((3, plant.num_bodies()), -1, dtype=np.int64)
    for k, name in enumerate(robot.FOOT_BODY_NAMES):
        maps[0, int(plant.GetBodyByName(name, plant_map.model).index())] = k
    for body in plant.GetBodyIndices(plant_map.model):
        foot = maps[0, int(body)]
        maps[1, int(body)] = foot if foot >= 0 else NUM_FEET
    for k, name in enumerate(scene_names):
        for body in plant.GetBodyIndices(plant.GetModelInstanceByName(name)):
            maps[2, int(body)] = k
    return maps
