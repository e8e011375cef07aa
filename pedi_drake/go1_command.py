"""The `go1.command` vector: one layout for the simulated motors, the controllers and the driver.

    go1.command (60) = [q_des (12), qd_des (12), kp (12), kd (12), tau_ff (12)]

each block in Unitree motor order (FR, FL, RR, RL x hip, thigh, calf), in [rad], [rad/s],
[N m/rad], [N m s/rad] and [N m]. Each Unitree motor driver applies

    tau = tau_ff + kp (q_des - q) + kd (qd_des - qd)

saturated at the joint's effort limit. The LCM wire order differs (see the driver's README); it
is converted in `pedi_drake.go1_driver.constants` and nowhere else.
"""

import numpy as np

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


def held_command(last_command: np.ndarray, q_measured: np.ndarray, kd_min: float) -> np.ndarray:
    """The command a controller sends on a tick it cannot compute one (failed QP, bad input).

    The last good command, with zero velocity targets and at least `kd_min` [N m s/rad] of joint
    damping. Before any good command (no position gain and no torque in `last_command`) the
    position targets are the measured joints. Non-finite entries become 0, so this never sends NaN.
    """
    command = np.array(last_command, dtype=float)
    if not np.any(command[24:36]) and not np.any(command[48:60]) and np.all(np.isfinite(q_measured)):
        command[0:12] = q_measured
    command[12:24] = 0.0
    command[36:48] = np.maximum(command[36:48], kd_min)
    return np.nan_to_num(command, nan=0.0, posinf=0.0, neginf=0.0)
