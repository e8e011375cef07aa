"""Plots of a run (PNG, matplotlib Agg): joint tracking and foot forces."""

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from pedi_drake import robot  # noqa: E402


def plot_joint_tracking(t: np.ndarray, q_des: np.ndarray, q_meas: np.ndarray, path: Path, title: str = "") -> Path:
    """Desired vs measured joint angles of all 12 joints; arrays are (12, N) [rad]."""
    fig, axes = plt.subplots(4, 3, figsize=(12, 10), sharex=True)
    for k, name in enumerate(robot.JOINT_NAMES):
        ax = axes[k // 3, k % 3]
        ax.plot(t, q_des[k], color="tab:blue", label="desired")
        ax.plot(t, q_meas[k], color="tab:red", label="measured", linewidth=0.8)
        ax.set_title(name, fontsize=9)
        ax.grid(alpha=0.3)
    axes[0, 0].legend(fontsize=8)
    for ax in axes[-1]:
        ax.set_xlabel("time [s]")
    for row in axes:
        row[0].set_ylabel("angle [rad]")
    fig.suptitle(title or "joint positions")
    fig.tight_layout()
    fig.savefig(path, dpi=90)
    plt.close(fig)
    return Path(path)


def plot_foot_forces(t: np.ndarray, forces: np.ndarray, path: Path) -> Path:
    """Foot contact forces (4, N) [N] over time."""
    fig, ax = plt.subplots(figsize=(8, 3.5))
    for k, leg in enumerate(robot.LEG_NAMES):
        ax.plot(t, forces[k], label=leg)
    ax.set_xlabel("time [s]")
    ax.set_ylabel("foot normal force [N]")
    ax.grid(alpha=0.3)
    ax.legend()
    fig.tight_layout()
    fig.savefig(path, dpi=90)
    plt.close(fig)
    return Path(path)
