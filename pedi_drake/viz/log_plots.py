"""Plots of a Go1 LCM log (see pedi_drake.go1_driver.log), the same figures run_sim writes.

Joint targets (pd_plustau_targets) against measured angles (leg_control_data), the measured
angles interpolated onto the command times; foot sensor values (state_estimator_data).
"""

from pathlib import Path

import numpy as np

from pedi_drake.go1_driver import constants as c
from pedi_drake.go1_driver.log import Go1Log
from pedi_drake.viz.plots import plot_foot_forces, plot_joint_tracking


def joint_targets_vs_measured(log: Go1Log) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(t [s] from the first command, q_des (12, N), q_measured (12, N)) on the command times."""
    commands = log.channels.get(c.COMMAND_CHANNEL)
    status = log.channels.get(c.LEG_CONTROL_CHANNEL)
    if commands is None or status is None or len(status.times) < 2:
        raise ValueError("the log needs pd_plustau_targets and at least two leg_control_data messages")
    t = commands.times
    q_des = log.commands()[:, 0:12].T
    q_status = status.field("q")
    q_meas = np.array([np.interp(t, status.times, q_status[:, k]) for k in range(12)])
    return t - t[0], q_des, q_meas


def plot_go1_log(log: Go1Log, out_dir: Path) -> list[Path]:
    """Writes joint_positions.png (and foot_forces.png when the log has state_estimator_data)."""
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    t, q_des, q_meas = joint_targets_vs_measured(log)
    paths = [plot_joint_tracking(t, q_des, q_meas, out_dir / "joint_positions.png", title="Go1 log: joint targets")]
    estimator = log.channels.get(c.STATE_ESTIMATOR_CHANNEL)
    if estimator is not None:
        t0 = log.channels[c.COMMAND_CHANNEL].times[0]
        forces = estimator.field("contact_estimate").T
        paths.append(plot_foot_forces(estimator.times - t0, forces, out_dir / "foot_forces.png"))
    return paths
