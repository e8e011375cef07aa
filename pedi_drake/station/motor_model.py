"""The Go1 motor drivers as the simulation sees them: joint PD plus feed-forward torque, clamped.

Each Unitree motor driver applies tau = tau_ff + kp (q_des - q) + kd (qd_des - qd), saturated at
the joint's effort limit. Here that law is evaluated at the plant's rate (1 kHz by default)
from the plant state, which is what the driver's encoders would read, in Drake's C++ systems
(see Go1MotorModel).

The scenario's model error (`pedi_drake.station.model_error`) changes the motors the plant
has, never the law the controllers assume: each leg's motor strength scales the torque and its
limit, a command latency delays the command by whole plant steps, and joint damping and friction
take torque away before it reaches the joint (the torque the motors report is what they apply).
"""

import math

import numpy as np
import scipy.sparse
from pydrake import symbolic
from pydrake.systems.framework import BasicVector, Diagram, DiagramBuilder
from pydrake.systems.primitives import (
    Demultiplexer,
    DiscreteTimeDelay,
    Multiplexer,
    SparseMatrixGain,
    SymbolicVectorSystem,
)

from pedi_drake import robot
from pedi_drake.exceptions import PediError
from pedi_drake.go1_command import COMMAND_SIZE, pd_torque
from pedi_drake.leaf_system import LeafSystemWithoutWitnesses
from pedi_drake.model_error_config import ModelErrorConfig
from pedi_drake.runtime.jit import kernel
from pedi_drake.station.model_error import FRICTION_VELOCITY_BAND

# Command entries are clipped to this magnitude before the motor law, so that no product or sum of
# them can overflow to inf (or inf - inf to NaN) [rad, rad/s, N m/rad, N m s/rad, N m].
COMMAND_MAGNITUDE_LIMIT = 1e6


def guarded_command(command: np.ndarray) -> np.ndarray:
    """The command the drivers act on (`command` itself when it needs no change).

    A motor with any non-finite entry gets all-zero entries (no torque: a driver that rejects the
    command), and every entry is clipped to +-COMMAND_MAGNITUDE_LIMIT. The controllers must never
    send non-finite commands, and the hardware safety layer replaces them; this only keeps the
    simulation defined."""
    command = np.asarray(command, dtype=float)
    if np.abs(command).max() <= COMMAND_MAGNITUDE_LIMIT:  # False for NaN too: the usual case, cheaply
        return command  # unchanged (not a copy)
    parts = command.reshape(5, 12).copy()  # rows: q_des, qd_des, kp, kd, tau_ff
    parts[:, ~np.isfinite(parts).all(axis=0)] = 0.0
    return np.clip(parts, -COMMAND_MAGNITUDE_LIMIT, COMMAND_MAGNITUDE_LIMIT).ravel()


@kernel
def _guard_kernel(command: np.ndarray, out: np.ndarray) -> None:
    """`guarded_command(command)` written into `out`, compiled: the same values (clipping a
    finite entry within the limit returns it unchanged)."""
    for k in range(12):
        finite = True
        for row in range(5):
            finite = finite and math.isfinite(command[12 * row + k])
        for row in range(5):
            value = command[12 * row + k]
            out[12 * row + k] = min(max(value, -COMMAND_MAGNITUDE_LIMIT), COMMAND_MAGNITUDE_LIMIT) if finite else 0.0


def motor_torque(command: np.ndarray, q: np.ndarray, qd: np.ndarray, strength: np.ndarray | float = 1.0) -> np.ndarray:
    """Motor torques [N m] the drivers apply for `command` at joint angles q and rates qd.

    Non-finite commands produce zero torque on that motor (see `guarded_command`). `strength`
    [-]: each motor's factor on the clamped torque (ModelErrorConfig.torque_scale; 1: the rated
    motor). The same law as `Go1MotorModel`, on plain arrays.
    """
    tau = pd_torque(guarded_command(command), q, qd)
    return strength * np.minimum(np.maximum(tau, -robot.EFFORT_LIMIT), robot.EFFORT_LIMIT)


class MotorCommandGuard(LeafSystemWithoutWitnesses):
    """go1.command -> `guarded_command(go1.command)`, by a compiled kernel.

    Its output depends on the command alone, so Drake computes it once per new command (once
    per controller tick), not once per plant step.
    """

    def __init__(self) -> None:
        super().__init__()
        _guard_kernel(np.zeros(COMMAND_SIZE), np.zeros(COMMAND_SIZE))  # compiled now, not in a tick
        self._command = self.DeclareVectorInputPort("command", COMMAND_SIZE)
        self.DeclareVectorOutputPort(
            "guarded_command",
            COMMAND_SIZE,
            self._calc,
            prerequisites_of_calc={self.input_port_ticket(self._command.get_index())},
        )

    def _calc(self, context, output: BasicVector) -> None:
        _guard_kernel(self._command.Eval(context), output.get_mutable_value())


def selection_matrix(rows: np.ndarray, num_columns: int) -> scipy.sparse.csc_matrix:
    """The sparse matrix S with (S x)[i] = x[rows[i]]."""
    rows = np.asarray(rows)
    return scipy.sparse.csc_matrix((np.ones(len(rows)), (np.arange(len(rows)), rows)), shape=(len(rows), num_columns))


class Go1MotorModel(Diagram):
    """go1.command + plant state -> plant actuation (plant order) and applied torques (Unitree order).

    The law (`motor_torque`) runs at the plant's rate, every step, so it is built from Drake's
    C++ systems: a selection of the joint states (SparseMatrixGain), the law itself as a
    SymbolicVectorSystem, and a selection of the applied torques. Only the command guard is
    Python, and it runs once per command: a Python LeafSystem for the law would add a Python
    callback to every plant step.

    `error` (the scenario's model error) scales each motor's torque and limit by its leg's
    strength, delays the guarded command by n = `error.latency_steps(time_step)` plant steps (a
    DiscreteTimeDelay updating with the plant: the plant's step from t applies the command of
    t - n time_step; before the first command has come through, a delay of n >= 2 applies the
    zero command (no torque) and a delay of 1 the first command), and subtracts the joints'
    damping and friction
    (`model_error.joint_loss_torque`) from the actuation but not from `torque`, which is what
    the motors apply. Without error (None or the defaults) the systems are exactly those of the
    rated motors.

    Inputs: command (60), plant_state (plant positions and velocities).
    Outputs: actuation (plant actuation vector), torque (12, Unitree order) [N m].
    """

    def __init__(
        self,
        plant_map: robot.Go1PlantMap,
        num_positions: int,
        num_velocities: int,
        num_actuators: int,
        *,
        error: ModelErrorConfig | None = None,
        time_step: float = 0.0,
    ):
        super().__init__()
        error = error if error is not None else ModelErrorConfig()
        builder = DiagramBuilder()
        guard = builder.AddNamedSystem("command_guard", MotorCommandGuard())
        state_rows = np.concatenate([plant_map.q_index, num_positions + plant_map.v_index])
        joints = builder.AddNamedSystem(
            "joint_state", SparseMatrixGain(selection_matrix(state_rows, num_positions + num_velocities))
        )
        inputs = builder.AddNamedSystem("law_inputs", Multiplexer([COMMAND_SIZE, 24]))
        u = symbolic.MakeVectorVariable(COMMAND_SIZE + 24, "u")
        q_des, qd_des, kp, kd, tau_ff = (u[12 * k : 12 * k + 12] for k in range(5))
        q, qd = u[COMMAND_SIZE : COMMAND_SIZE + 12], u[COMMAND_SIZE + 12 :]
        strength = error.torque_scale()
        actuation = [symbolic.Expression(0.0)] * num_actuators
        applied = []
        for k in range(12):
            tau = tau_ff[k] + kp[k] * (q_des[k] - q[k]) + kd[k] * (qd_des[k] - qd[k])
            limit = float(robot.EFFORT_LIMIT[k])
            tau = symbolic.min(symbolic.max(tau, -limit), limit)
            if strength[k] != 1.0:
                tau = float(strength[k]) * tau
            applied.append(tau)
            loss = error.joint_damping * qd[k] + error.joint_friction * symbolic.min(
                symbolic.max(qd[k] / FRICTION_VELOCITY_BAND, -1.0), 1.0
            )
            actuation[plant_map.u_index[k]] = tau - loss if error.has_joint_losses() else tau
        if error.has_joint_losses():
            # The joints get less than the motors apply: the torque output is the motors'.
            law = builder.AddNamedSystem("motor_law", SymbolicVectorSystem(input=u, output=actuation + applied))
            split = builder.AddNamedSystem("motor_law.split", Demultiplexer([num_actuators, 12]))
            builder.Connect(law.get_output_port(), split.get_input_port())
            actuation_port, torque_port = split.get_output_port(0), split.get_output_port(1)
        else:
            law = builder.AddNamedSystem("motor_law", SymbolicVectorSystem(input=u, output=actuation))
            torque = builder.AddNamedSystem(
                "unitree_torque", SparseMatrixGain(selection_matrix(plant_map.u_index, num_actuators))
            )
            builder.Connect(law.get_output_port(), torque.get_input_port())
            actuation_port, torque_port = law.get_output_port(), torque.get_output_port()
        if error.command_latency > 0.0 and not time_step > 0.0:
            raise PediError(f"Go1MotorModel: a command latency needs the plant's time step [s], got {time_step}")
        steps = error.latency_steps(time_step) if error.command_latency > 0.0 else 0
        if steps > 0:
            # After the guard, whose output then still changes once per command, not every step.
            # DiscreteTimeDelay(k) outputs, before its update at t, the input it sampled at
            # t - (k + 1) time steps: the plant's step from t reads that value, so k = steps - 1.
            delay = builder.AddNamedSystem("command_latency", DiscreteTimeDelay(time_step, steps - 1, COMMAND_SIZE))
            builder.Connect(guard.get_output_port(), delay.get_input_port())
            builder.Connect(delay.get_output_port(), inputs.get_input_port(0))
        else:
            builder.Connect(guard.get_output_port(), inputs.get_input_port(0))
        builder.Connect(joints.get_output_port(), inputs.get_input_port(1))
        builder.Connect(inputs.get_output_port(), law.get_input_port())
        builder.ExportInput(guard.get_input_port(), "command")
        builder.ExportInput(joints.get_input_port(), "plant_state")
        builder.ExportOutput(actuation_port, "actuation")
        builder.ExportOutput(torque_port, "torque")
        builder.BuildInto(self)
