"""The Go1 motor drivers as the simulation sees them: joint PD plus feed-forward torque, clamped.

Each Unitree motor driver applies tau = tau_ff + kp (q_des - q) + kd (qd_des - qd), saturated at
the joint's effort limit. Here that law is evaluated at the plant's rate (1 kHz by default)
from the plant state, which is what the driver's encoders would read.
"""

import numpy as np
from pydrake.systems.framework import BasicVector, LeafSystem

from pedi_drake import robot

COMMAND_SIZE = 60  # q_des[12], qd_des[12], kp[12], kd[12], tau_ff[12]


def split_command(command: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """(q_des, qd_des, kp, kd, tau_ff), each (12,) in Unitree order, from a 60-vector command."""
    c = np.asarray(command, dtype=float)
    return c[0:12], c[12:24], c[24:36], c[36:48], c[48:60]


def pack_command(q_des, qd_des, kp, kd, tau_ff) -> np.ndarray:
    """The 60-vector `go1.command` from its five Unitree-ordered parts."""
    return np.concatenate([np.broadcast_to(np.asarray(x, float), (12,)) for x in (q_des, qd_des, kp, kd, tau_ff)])


def damping_command(kd: float = 2.0) -> np.ndarray:
    """A safe command: no position gain, joint damping only, no feed-forward."""
    return pack_command(np.zeros(12), np.zeros(12), np.zeros(12), np.full(12, kd), np.zeros(12))


def motor_torque(command: np.ndarray, q: np.ndarray, qd: np.ndarray) -> np.ndarray:
    """Motor torques [N m] the drivers apply for `command` at joint angles q and rates qd.

    Non-finite commands produce zero torque on that motor (a driver that rejects the command);
    the controllers must never send them, and the hardware safety layer replaces them.
    """
    q_des, qd_des, kp, kd, tau_ff = split_command(command)
    tau = tau_ff + kp * (q_des - q) + kd * (qd_des - qd)
    tau = np.where(np.isfinite(tau), tau, 0.0)
    return np.clip(tau, -robot.EFFORT_LIMIT, robot.EFFORT_LIMIT)


class Go1MotorModel(LeafSystem):
    """go1.command + plant state -> plant actuation (plant order) and applied torques (Unitree order)."""

    def __init__(self, plant_map: robot.Go1PlantMap, num_positions: int, num_velocities: int, num_actuators: int):
        super().__init__()
        self._map = plant_map
        self._nq = num_positions
        self._num_actuators = num_actuators
        self._command = self.DeclareVectorInputPort("command", COMMAND_SIZE)
        self._state = self.DeclareVectorInputPort("plant_state", num_positions + num_velocities)
        self.DeclareVectorOutputPort("actuation", num_actuators, self._calc_actuation)
        self.DeclareVectorOutputPort("torque", 12, self._calc_torque)

    def _torque(self, context) -> np.ndarray:
        x = self._state.Eval(context)
        q = self._map.joint_positions(x[: self._nq])
        qd = self._map.joint_velocities(x[self._nq :])
        return motor_torque(self._command.Eval(context), q, qd)

    def _calc_actuation(self, context, output: BasicVector) -> None:
        output.SetFromVector(self._map.actuation(self._torque(context), self._num_actuators))

    def _calc_torque(self, context, output: BasicVector) -> None:
        output.SetFromVector(self._torque(context))
