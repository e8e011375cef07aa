"""The `go1.command` vector: one layout for the simulated motors, the controllers and the driver.

    go1.command (60) = [q_des (12), qd_des (12), kp (12), kd (12), tau_ff (12)]

each block in Unitree motor order (FR, FL, RR, RL x hip, thigh, calf), in [rad], [rad/s],
[N m/rad], [N m s/rad] and [N m]. Each Unitree motor driver applies

    tau = tau_ff + kp (q_des - q) + kd (qd_des - qd)

saturated at the joint's effort limit. The LCM wire order differs (see the driver's README); it
is converted in `pedi_drake.go1_driver.constants` and nowhere else.
"""

import math

import numpy as np

from pedi_drake.runtime.jit import kernel

COMMAND_SIZE = 60


def split_command(command: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """(q_des, qd_des, kp, kd, tau_ff), each (12,) in Unitree order, from a 60-vector command."""
    c = np.asarray(command, dtype=float)
    return c[0:12], c[12:24], c[24:36], c[36:48], c[48:60]


def pack_command(q_des, qd_des, kp, kd, tau_ff) -> np.ndarray:
    """The 60-vector `go1.command` from its five Unitree-ordered parts (scalars broadcast)."""
    return np.concatenate([np.broadcast_to(np.asarray(x, float), (12,)) for x in (q_des, qd_des, kp, kd, tau_ff)])


def initial_command(kd: float) -> np.ndarray:
    """The command a controller holds before its first tick: no position gain, no torque and `kd`
    [N m s/rad] of joint damping. A simulated plant applies it in its first step (the controller's
    first command from the next tick on): damping, not a limp motor (kp, kd and tau all 0)."""
    return pack_command(0.0, 0.0, 0.0, kd, 0.0)


def pd_torque(command: np.ndarray, q: np.ndarray, qd: np.ndarray) -> np.ndarray:
    """tau_ff + kp (q_des - q) + kd (qd_des - qd) [N m], before the motors' saturation."""
    q_des, qd_des, kp, kd, tau_ff = split_command(command)
    return tau_ff + kp * (q_des - q) + kd * (qd_des - qd)


# Where each block of the command starts (each is 12 long).
Q_DES, QD_DES, KP, KD, TAU_FF = 0, 12, 24, 36, 48


@kernel
def write_held_command(last_command: np.ndarray, q_measured: np.ndarray, kd_min: float, out: np.ndarray) -> None:
    """`held_command` into `out` (60,), for the compiled controller ticks."""
    out[:] = last_command
    started = False
    for i in range(12):
        started |= out[KP + i] != 0.0 or out[TAU_FF + i] != 0.0
    measured = True
    for i in range(12):
        measured &= math.isfinite(q_measured[i])
    if not started and measured:
        out[Q_DES : Q_DES + 12] = q_measured
    out[QD_DES : QD_DES + 12] = 0.0
    for i in range(12):
        out[KD + i] = max(out[KD + i], kd_min)
    for i in range(COMMAND_SIZE):
        if not math.isfinite(out[i]):
            out[i] = 0.0


def held_command(last_command: np.ndarray, q_measured: np.ndarray, kd_min: float) -> np.ndarray:
    """The command a controller sends on a tick it cannot compute one (failed QP, bad input).

    The last good command, with zero velocity targets and at least `kd_min` [N m s/rad] of joint
    damping. Before any good command (no position gain and no torque in `last_command`) the
    position targets are the measured joints. Non-finite entries become 0, so this never sends NaN.
    """
    out = np.empty(COMMAND_SIZE)
    write_held_command(np.asarray(last_command, dtype=float), np.asarray(q_measured, dtype=float), float(kd_min), out)
    return out
