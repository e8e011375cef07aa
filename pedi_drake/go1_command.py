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


def pd_torque(command: np.ndarray, q: np.ndarray, qd: np.ndarray) -> np.ndarray:
    """tau_ff + kp (q_des - q) + kd (qd_des - qd) [N m], before the motors' saturation."""
    q_des, qd_des, kp, kd, tau_ff = split_command(command)
    return tau_ff + kp * (q_des - q) + kd * (qd_des - qd)
