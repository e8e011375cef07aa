"""Plots of paper 002's evaluations (Figs. 3 to 5 of IV-A) from `pedi_drake.evaluation.paper002`."""

from pathlib import Path
from typing import TYPE_CHECKING

import matplotlib.pyplot as plt
import numpy as np

if TYPE_CHECKING:  # the plots read the evaluation's fields; the evaluation never imports plots
    from pedi_drake.evaluation.paper002 import FootHoldEvaluation


def plot_foot_hold(evaluation: "FootHoldEvaluation", out_dir: Path, title: str = "") -> list[Path]:
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
