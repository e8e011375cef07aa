"""Plots of paper 002's evaluations (Figs. 3 to 5 of IV-A, Fig. 7 of IV-B) from
`pedi_drake.evaluation.paper002`."""

from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

from pedi_drake.evaluation.paper002 import FootHoldEvaluation, PivotEvaluation


def plot_foot_hold(evaluation: FootHoldEvaluation, out_dir: Path, title: str = "") -> list[Path]:
    """Figs. 3 to 5 of paper 002: positions, foot position error, foot orientation error (PNG)."""
    out_dir.mkdir(parents=True, exist_ok=True)
    e = evaluation
    paths = []
    fig, ax = plt.subplots(figsize=(5, 5))
    ax.plot(e.trunk_reference[:, 0], e.trunk_reference[:, 1], "k--", label="torso reference")
    ax.plot(e.trunk[:, 0], e.trunk[:, 1], label="torso")
    ax.plot(e.foot[:, 0], e.foot[:, 1], "o", markersize=2, label="held foot")
    ax.set(xlabel="x [m]", ylabel="y [m]", title=f"{title} positions (Fig. 3)", aspect="equal")
    ax.legend()
    paths.append(out_dir / "iva_positions.png")
    fig.savefig(paths[-1], dpi=100)
    plt.close(fig)
    t = e.times - e.times[0]
    fig, ax = plt.subplots(figsize=(7, 3.5))
    for k, axis in enumerate("xyz"):
        ax.plot(t, 1e3 * e.foot_error[:, k], label=axis)
    ax.set(xlabel="t [s]", ylabel="foot position error [mm]", title=f"{title} foot position error (Fig. 4)")
    ax.legend()
    paths.append(out_dir / "iva_foot_position_error.png")
    fig.savefig(paths[-1], dpi=100)
    plt.close(fig)
    fig, ax = plt.subplots(figsize=(7, 3.5))
    for k, axis in enumerate(("roll", "pitch", "yaw (free)")):
        ax.plot(t, np.degrees(e.orientation_error[:, k]), label=axis)
    ax.set(xlabel="t [s]", ylabel="calf orientation error [deg]", title=f"{title} foot orientation error (Fig. 5)")
    ax.legend()
    paths.append(out_dir / "iva_foot_orientation_error.png")
    fig.savefig(paths[-1], dpi=100)
    plt.close(fig)
    return paths


def plot_pivot_rotations(evaluation: PivotEvaluation, out_dir: Path, title: str = "") -> Path:
    """Fig. 7 of paper 002 as curves: the trunk's rotation about the prong (roll, pitch, yaw from
    its start attitude) and the held front feet's displacement, against time (PNG)."""
    out_dir.mkdir(parents=True, exist_ok=True)
    e = evaluation
    t = e.times - e.times[0]
    fig, (top, bottom) = plt.subplots(2, 1, figsize=(7, 5.5), sharex=True)
    for k, axis in enumerate(("roll (x)", "pitch (y)", "yaw (z)")):
        top.plot(t, np.degrees(e.rotation[:, k]), label=axis)
    top.set(ylabel="trunk rotation [deg]", title=f"{title} rotations about one prong (Fig. 7)")
    top.legend()
    for k, leg in enumerate(("FR", "FL")):
        bottom.plot(t, 1e3 * np.linalg.norm(e.front_feet_displacement[:, k], axis=1), label=leg)
    bottom.set(xlabel="t [s]", ylabel="front foot displacement [mm]")
    bottom.legend()
    path = out_dir / "ivb_rotations.png"
    fig.savefig(path, dpi=100)
    plt.close(fig)
    return path
