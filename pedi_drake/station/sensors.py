"""Simulated Go1 sensors: joint encoders, and the reference maths of the IMU and the foot sensors.

Outputs follow the station ports of docs/conventions.md (Unitree order). Optional Gaussian
noise is drawn from a generator seeded by (scenario seed, sample index, channel), so a run is
deterministic and the sensors keep no hidden state.

The joint encoders (`JointEncoders`) are read twice a control tick (by the controller side at
the tick, by the log after it, at the next plant state), so without noise they are Drake's C++
selection of the plant state. The IMU, the foot sensors and the torque estimate are computed
with the simulation's contact ground truth in one callback (`plant_readings.PlantReadings`); the
functions here (`imu_reading`, `foot_normal_forces`, `foot_contact_forces_W`) are the same maths
on plain arrays and the plant's objects: the reference its compiled kernel is tested against.
"""

import numpy as np
from pydrake.math import RotationMatrix
from pydrake.multibody.plant import ContactResults
from pydrake.systems.framework import BasicVector, Diagram, DiagramBuilder
from pydrake.systems.primitives import SparseMatrixGain

from pedi_drake import robot
from pedi_drake.leaf_system import LeafSystemWithoutWitnesses
from pedi_drake.scenario import SensorNoiseConfig
from pedi_drake.station.motor_model import selection_matrix
from pedi_drake.vector3 import axis_angle_matrix, cross3, rotation_matrix_wxyz

# Noise channels of the encoders' generators (the other sensors draw 2 to 4, see PlantReadings).
POSITION_CHANNEL, VELOCITY_CHANNEL = 0, 1


class NoisyJointEncoders(LeafSystemWithoutWitnesses):
    """plant_state -> position_measured, velocity_measured (12 each, Unitree order) with noise."""

    def __init__(self, plant_map: robot.Go1PlantMap, nq: int, nv: int, noise: SensorNoiseConfig, seed: int, period):
        super().__init__()
        self._map, self._nq, self._noise, self._seed, self._period = plant_map, nq, noise, int(seed), period
        self._state = self.DeclareVectorInputPort("plant_state", nq + nv)
        self.DeclareVectorOutputPort("position_measured", 12, self._calc_position)
        self.DeclareVectorOutputPort("velocity_measured", 12, self._calc_velocity)

    def _rng(self, context, channel: int) -> np.random.Generator:
        sample = int(round(context.get_time() / self._period))
        return np.random.default_rng((self._seed, sample, channel))

    def _calc_position(self, context, output: BasicVector) -> None:
        q = self._map.joint_positions(self._state.Eval(context)[: self._nq])
        output.SetFromVector(q + self._rng(context, POSITION_CHANNEL).normal(0.0, self._noise.joint_position, 12))

    def _calc_velocity(self, context, output: BasicVector) -> None:
        qd = self._map.joint_velocities(self._state.Eval(context)[self._nq :])
        output.SetFromVector(qd + self._rng(context, VELOCITY_CHANNEL).normal(0.0, self._noise.joint_velocity, 12))


class JointEncoders(Diagram):
    """plant_state -> position_measured, velocity_measured (12 each, Unitree order) [rad, rad/s].

    Without noise each is a C++ selection of the plant state (exact: one 1.0 per row); with
    noise a Python system adds the seeded noise (channels POSITION_CHANNEL, VELOCITY_CHANNEL).
    """

    def __init__(self, plant_map: robot.Go1PlantMap, nq: int, nv: int, noise: SensorNoiseConfig, seed: int, period):
        super().__init__()
        builder = DiagramBuilder()
        if noise.enabled:
            encoders = builder.AddNamedSystem("noisy", NoisyJointEncoders(plant_map, nq, nv, noise, seed, period))
            builder.ExportInput(encoders.get_input_port(), "plant_state")
            for name in ("position_measured", "velocity_measured"):
                builder.ExportOutput(encoders.GetOutputPort(name), name)
        else:
            positions = builder.AddNamedSystem(
                "positions", SparseMatrixGain(selection_matrix(plant_map.q_index, nq + nv))
            )
            rates = builder.AddNamedSystem(
                "velocities", SparseMatrixGain(selection_matrix(nq + plant_map.v_index, nq + nv))
            )
            builder.ExportInput(positions.get_input_port(), "plant_state")
            builder.ConnectInput("plant_state", rates.get_input_port())
            builder.ExportOutput(positions.get_output_port(), "position_measured")
            builder.ExportOutput(rates.get_output_port(), "velocity_measured")
        builder.BuildInto(self)


def imu_reading(
    x: np.ndarray,
    vdot: np.ndarray,
    starts: tuple[int, int, int, int],
    p_BI: np.ndarray,
    gravity_W: np.ndarray,
    rng: np.random.Generator | None = None,
    noise: SensorNoiseConfig | None = None,
) -> np.ndarray:
    """The IMU's reading (IMU_SIZE: quaternion w, x, y, z; gyro [rad/s]; specific force [m/s^2],
    trunk frame) from the plant state `x` and accelerations `vdot`.

    starts: where the trunk's quaternion and angular velocity are in x, its angular and linear
    acceleration in vdot; p_BI: the IMU's offset in the trunk [m]; `rng`: the sample's generator
    of the IMU channel when noise is on (orientation, gyro, accelerometer drawn in that order).
    """
    q0, w0, alpha0, a0 = starts
    R_WB = rotation_matrix_wxyz(x[q0 : q0 + 4])
    w_W = x[w0 : w0 + 3]
    alpha_W = vdot[alpha0 : alpha0 + 3]
    p_BI_W = R_WB @ p_BI
    # Acceleration of the IMU point, then the specific force a - g in the trunk frame.
    a_WI = vdot[a0 : a0 + 3] + cross3(alpha_W, p_BI_W) + cross3(w_W, cross3(w_W, p_BI_W))
    gyro = R_WB.T @ w_W
    accel = R_WB.T @ (a_WI - gravity_W)
    if rng is not None:
        R_WB = R_WB @ axis_angle_matrix(rng.normal(0.0, noise.orientation, 3))
        gyro = gyro + rng.normal(0.0, noise.gyro, 3)
        accel = accel + rng.normal(0.0, noise.accelerometer, 3)
    quaternion = RotationMatrix(R_WB).ToQuaternion()
    return np.concatenate([[quaternion.w(), quaternion.x(), quaternion.y(), quaternion.z()], gyro, accel])


def foot_index_of_body(foot_bodies) -> dict[int, int]:
    """{body index: foot number} for `foot_normal_forces`, from the feet's body indices in foot order."""
    return {int(body): k for k, body in enumerate(foot_bodies)}


def foot_normal_forces(contact_results: ContactResults, foot_of_body: dict[int, int]) -> np.ndarray:
    """Normal contact force magnitude on each foot [N], summed over its point contacts.

    `foot_of_body` maps body indices to foot numbers (see `foot_index_of_body`).
    """
    forces = [0.0] * len(foot_of_body)
    for i in range(contact_results.num_point_pair_contacts()):
        info = contact_results.point_pair_contact_info(i)
        a, b = foot_of_body.get(int(info.bodyA_index())), foot_of_body.get(int(info.bodyB_index()))
        if a is None and b is None:
            continue
        # Scalar maths: this runs for every contact every tick, and np.dot costs more than the rest.
        f, n = info.contact_force().tolist(), info.point_pair().nhat_BA_W.tolist()
        force = abs(f[0] * n[0] + f[1] * n[1] + f[2] * n[2])
        for k in (a, b):
            if k is not None:
                forces[k] += force
    return np.array(forces)


def foot_contact_forces_W(contact_results: ContactResults, foot_of_body: dict[int, int]) -> np.ndarray:
    """(k, 3) total contact force on each foot, world frame [N] (summed over its point contacts)."""
    forces = np.zeros((len(foot_of_body), 3))
    for i in range(contact_results.num_point_pair_contacts()):
        info = contact_results.point_pair_contact_info(i)
        a, b = foot_of_body.get(int(info.bodyA_index())), foot_of_body.get(int(info.bodyB_index()))
        # contact_force() acts on body B; body A feels its opposite.
        if b is not None:
            forces[b] += info.contact_force()
        if a is not None:
            forces[a] -= info.contact_force()
    return forces
