"""Plots of a run (PNG, matplotlib Agg): joint tracking and foot forces."""

from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

from pedi_drake import robot
from pedi_drake.control.references import LEG_BLOCK, LEG_MODE_JOINTS


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


def _shade_phases(ax, phases: list[dict]) -> None:
    """Alternating background bands for the mission phases, labelled at the top."""
    for k, phase in enumerate(phases):
        if phase["t_end"] is None or phase["status"] == "skipped":
            continue
        if k % 2 == 0:
            ax.axvspan(phase["t_start"], phase["t_end"], color="0.92", zorder=0)


def _leg_joint_figure(t, desired, measured, leg: str, phases: list[dict], what: str, path: Path) -> Path:
    """The leg's three joints, positions and velocities: `desired` (6, N) against `measured` (6, N),
    positions first [rad, rad/s]; NaN in `desired` where there is none."""
    fig, axes = plt.subplots(3, 2, figsize=(12, 8), sharex=True)
    for j, kind in enumerate(robot.JOINT_KINDS):
        for col, unit in enumerate(("rad", "rad/s")):
            ax = axes[j, col]
            _shade_phases(ax, phases)
            ax.plot(t, desired[3 * col + j], color="tab:blue", label=what)
            ax.plot(t, measured[3 * col + j], color="tab:red", linewidth=0.8, label="measured")
            ax.set_ylabel(f"{leg}_{kind} [{unit}]")
            ax.grid(alpha=0.3)
    axes[0, 0].set_title("joint positions")
    axes[0, 1].set_title("joint velocities")
    axes[0, 0].legend(fontsize=8)
    for ax in axes[-1]:
        ax.set_xlabel("time [s]")
    fig.tight_layout()
    fig.savefig(path, dpi=90)
    plt.close(fig)
    return Path(path)


def plot_leg_tracking(t, leg_reference, position, velocity, leg: str, phases: list[dict], path: Path) -> Path:
    """The pedipulation leg's joints, the mission's joint reference against the measurement
    (paper 000, Figs. 3 and 4): the tracking error the controller leaves.

    `leg_reference` is the logged mission.leg_reference (48, N); `position`, `velocity` are the
    measured joints (12, N), sampled at the same times `t`. The reference is drawn where the
    mission drives the leg's joints (LEG_MODE_JOINTS); while it drives the foot in task space
    there is no joint reference, and the gap is left blank.
    """
    i = robot.LEG_NAMES.index(leg)
    block = leg_reference[i * LEG_BLOCK : (i + 1) * LEG_BLOCK]
    joints = np.round(block[0]) == LEG_MODE_JOINTS
    desired = np.where(joints, block[1:7], np.nan)
    measured = np.vstack([position[3 * i : 3 * i + 3], velocity[3 * i : 3 * i + 3]])
    return _leg_joint_figure(t, desired, measured, leg, phases, "mission reference", path)


def plot_leg_command(t, command, position, velocity, leg: str, phases: list[dict], path: Path) -> Path:
    """The pedipulation leg's go1.command targets (q_des, qd_des) against the measurement. The
    whole-body controllers keep q_des within a few hundredths of a radian of the measured joints
    (their torque does the tracking), so this plot shows the command, not the tracking error."""
    i = robot.LEG_NAMES.index(leg)
    desired = np.vstack([command[3 * i : 3 * i + 3], command[12 + 3 * i : 12 + 3 * i + 3]])
    measured = np.vstack([position[3 * i : 3 * i + 3], velocity[3 * i : 3 * i + 3]])
    return _leg_joint_figure(t, desired, measured, leg, phases, "go1.command", path)


def plot_mission_errors(t, states, body_reference, status, plant, result: dict, path: Path) -> Path:
    """Foot error to each reach phase's target and trunk drift from its reference, over time."""
    plant_map = robot.Go1PlantMap.from_plant(plant)
    context = plant.CreateDefaultContext()
    n = min(states.shape[1], body_reference.shape[1], status.shape[1], len(t))
    q0 = plant_map.base_q_start
    drift = np.linalg.norm(states[q0 + 4 : q0 + 7, :n] - body_reference[0:3, :n], axis=0)
    fig, (ax_foot, ax_drift) = plt.subplots(2, 1, figsize=(10, 6), sharex=True)
    _shade_phases(ax_foot, result["phases"])
    _shade_phases(ax_drift, result["phases"])
    targets = {row["phase"]: row for row in result["foot_errors_m"]}
    for phase in result["phases"]:
        if phase["name"] not in targets or phase["t_end"] is None:
            continue
        window = (t[:n] >= phase["t_start"]) & (t[:n] <= phase["t_end"])
        leg, target = targets[phase["name"]]["leg"], np.asarray(targets[phase["name"]]["target_W"])
        error = []
        for k in np.nonzero(window)[0]:
            plant.SetPositionsAndVelocities(context, states[:, k])
            error.append(
                np.linalg.norm(plant.GetBodyByName(f"{leg}_foot").EvalPoseInWorld(context).translation() - target)
            )
        if error:
            ax_foot.plot(t[:n][window], 1000 * np.asarray(error), label=f"{phase['name']} ({leg})")
    ax_foot.set_ylabel("foot error [mm]")
    ax_foot.set_yscale("log")
    ax_foot.grid(alpha=0.3)
    if ax_foot.lines:  # a mission without reach phases has no foot errors to name
        ax_foot.legend(fontsize=8)
    ax_drift.plot(t[:n], 1000 * drift, color="tab:purple")
    active = status[2, :n] > 0.5
    ax_drift.fill_between(
        t[:n], 0, 1000 * drift.max(initial=0.0), where=active, color="tab:orange", alpha=0.15, label="pedipulation"
    )
    ax_drift.set_ylabel("trunk drift [mm]")
    ax_drift.set_xlabel("time [s]")
    ax_drift.grid(alpha=0.3)
    ax_drift.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=90)
    plt.close(fig)
    return Path(path)
