"""Simulated Go1 sensors: joint encoders, torque estimate, IMU and foot force sensors.

Outputs follow the station ports of docs/conventions.md (Unitree order). Optional Gaussian
noise is drawn from a generator seeded by (scenario seed, sample index), so a run is
deterministic and the sensors keep no hidden state.
"""

import numpy as np
from pydrake.common.value import AbstractValue
from pydrake.math import RotationMatrix
from pydrake.multibody.plant import ContactResults, MultibodyPlant
from pydrake.systems.framework import BasicVector, LeafSystem

from pedi_drake import robot
from pedi_drake.scenario import SensorNoiseConfig
from pedi_drake.vector3 import axis_angle_matrix, cross3, rotation_matrix_wxyz

IMU_SIZE = 10  # quaternion w, x, y, z; gyro (3); accelerometer (3)


class Go1SensorModel(LeafSystem):
    """Plant signals -> go1.position_measured, velocity_measured, imu, foot_contact (+ noisy torque)."""

    def __init__(
        self,
        plant: MultibodyPlant,
        plant_map: robot.Go1PlantMap,
        noise: SensorNoiseConfig,
        seed: int,
        sample_period: float,
    ):
        super().__init__()
        self._plant = plant
        self._map = plant_map
        self._nq = plant.num_positions()
        self._noise = noise
        self._seed = int(seed)
        self._period = sample_period
        trunk = plant.GetBodyByName(robot.TRUNK_BODY_NAME, plant_map.model)
        imu = plant.GetBodyByName(robot.IMU_BODY_NAME, plant_map.model)
        if not trunk.is_floating_base_body() or not trunk.has_quaternion_dofs():
            raise ValueError(f"Go1SensorModel: the trunk {trunk.name()!r} must be a quaternion floating body")
        # The trunk's floating joint: q = [quaternion R_WB (w, x, y, z), p_WB], v = [w_WB, v_WB]
        # (world frame), so its slices of the state and of vdot are the trunk's pose, velocity
        # and acceleration: cheaper to read than the plant's per-body output ports (a Python
        # object per body each).
        self._quaternion = slice(trunk.floating_positions_start(), trunk.floating_positions_start() + 4)
        v_start = self._nq + trunk.floating_velocities_start_in_v()
        self._w_WB = slice(v_start, v_start + 3)
        a_start = trunk.floating_velocities_start_in_v()
        self._alpha_WB = slice(a_start, a_start + 3)
        self._a_WB = slice(a_start + 3, a_start + 6)
        # The IMU is welded to the trunk with the trunk's orientation; keep its offset p_BI.
        context = plant.CreateDefaultContext()
        self._p_BI = plant.CalcRelativeTransform(context, trunk.body_frame(), imu.body_frame()).translation()
        self._gravity_W = plant.gravity_field().gravity_vector()
        # Foot number by body index (plain ints), made once: the contact loop looks up every
        # contact's two bodies in it, every tick.
        self._foot_of_body = foot_index_of_body(
            [plant.GetBodyByName(name, plant_map.model).index() for name in robot.FOOT_BODY_NAMES]
        )

        nx = plant.num_positions() + plant.num_velocities()
        self._state = self.DeclareVectorInputPort("plant_state", nx)
        self._vdot = self.DeclareVectorInputPort("generalized_acceleration", plant.num_velocities())
        self._contacts = self.DeclareAbstractInputPort(
            "contact_results", plant.get_contact_results_output_port().Allocate()
        )
        self._torque = self.DeclareVectorInputPort("motor_torque", 12)
        self.DeclareVectorOutputPort("position_measured", 12, self._calc_position)
        self.DeclareVectorOutputPort("velocity_measured", 12, self._calc_velocity)
        self.DeclareVectorOutputPort("torque_estimated", 12, self._calc_torque)
        self.DeclareVectorOutputPort("imu", IMU_SIZE, self._calc_imu)
        self.DeclareVectorOutputPort("foot_contact", 4, self._calc_foot_contact)

    def _rng(self, context, channel: int) -> np.random.Generator | None:
        """A generator for this sample and signal channel, or None when noise is off."""
        if not self._noise.enabled:
            return None
        sample = int(round(context.get_time() / self._period))
        return np.random.default_rng((self._seed, sample, channel))

    def _calc_position(self, context, output: BasicVector) -> None:
        q = self._map.joint_positions(self._state.Eval(context)[: self._nq])
        rng = self._rng(context, 0)
        if rng is not None:
            q = q + rng.normal(0.0, self._noise.joint_position, 12)
        output.SetFromVector(q)

    def _calc_velocity(self, context, output: BasicVector) -> None:
        qd = self._map.joint_velocities(self._state.Eval(context)[self._nq :])
        rng = self._rng(context, 1)
        if rng is not None:
            qd = qd + rng.normal(0.0, self._noise.joint_velocity, 12)
        output.SetFromVector(qd)

    def _calc_torque(self, context, output: BasicVector) -> None:
        tau = self._torque.Eval(context).copy()
        rng = self._rng(context, 2)
        if rng is not None:
            tau = tau + rng.normal(0.0, self._noise.joint_torque, 12)
        output.SetFromVector(tau)

    def _calc_imu(self, context, output: BasicVector) -> None:
        x = self._state.Eval(context)
        vdot = self._vdot.Eval(context)
        R_WB = rotation_matrix_wxyz(x[self._quaternion])
        w_W = x[self._w_WB]
        alpha_W = vdot[self._alpha_WB]
        p_BI_W = R_WB @ self._p_BI
        # Acceleration of the IMU point, then the specific force a - g in the trunk frame.
        a_WI = vdot[self._a_WB] + cross3(alpha_W, p_BI_W) + cross3(w_W, cross3(w_W, p_BI_W))
        gyro = R_WB.T @ w_W
        accel = R_WB.T @ (a_WI - self._gravity_W)
        rng = self._rng(context, 3)
        if rng is not None:
            R_WB = R_WB @ axis_angle_matrix(rng.normal(0.0, self._noise.orientation, 3))
            gyro = gyro + rng.normal(0.0, self._noise.gyro, 3)
            accel = accel + rng.normal(0.0, self._noise.accelerometer, 3)
        quaternion = RotationMatrix(R_WB).ToQuaternion()
        output.SetFromVector(
            np.concatenate([[quaternion.w(), quaternion.x(), quaternion.y(), quaternion.z()], gyro, accel])
        )

    def _calc_foot_contact(self, context, output: BasicVector) -> None:
        forces = foot_normal_forces(self._contacts.Eval(context), self._foot_of_body)
        rng = self._rng(context, 4)
        if rng is not None:
            forces = np.maximum(forces + rng.normal(0.0, self._noise.foot_force, 4), 0.0)
        output.SetFromVector(forces)


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


class FootContactForces(LeafSystem):
    """Simulation only (`sim.foot_contact_forces`): the true contact force on each foot, world
    frame [N], FR, FL, RR, RL x (x, y, z). For judging force estimates; controllers never read it."""

    def __init__(self, plant, plant_map) -> None:
        super().__init__()
        feet = [plant.GetBodyByName(name, plant_map.model).index() for name in robot.FOOT_BODY_NAMES]
        self._foot_of_body = foot_index_of_body(feet)
        self._contacts = self.DeclareAbstractInputPort("contact_results", AbstractValue.Make(ContactResults()))
        self.DeclareVectorOutputPort("foot_contact_forces", 12, self._calc)

    def _calc(self, context, output: BasicVector) -> None:
        output.SetFromVector(foot_contact_forces_W(self._contacts.Eval(context), self._foot_of_body).ravel())
