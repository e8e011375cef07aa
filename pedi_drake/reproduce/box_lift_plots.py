"""Paper 003's box lift (Figs. 9-10 are motion stills) as time series: the box's height, the
holding feet's contact forces and their positions, the mission's phases marked on the time axis."""

from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

from pedi_drake.evaluation.box_lift import BoxLiftTrace
from pedi_drake.mission.spec import BoxLift

COLOURS = ("tab:red", "tab:blue", "tab:green", "tab:purple")


def plot_box_lift(trace: BoxLiftTrace, check: BoxLift, phases: list[dict], path: Path, t_from: float = 0.0) -> Path:
    """Four panels sharing the time axis (from `t_from` [s]): the box's lowest corner above the
    ground [cm] against the required height, each holding foot's contact force [N], the feet's
    heights [cm] and their x positions [cm]; a dotted line at the start of each phase."""
    keep = trace.times >= t_from
    t = trace.times[keep]
    fig, axes = plt.subplots(4, 1, figsize=(8, 9), sharex=True)
    axes[0].plot(t, 100 * trace.bottom_height[keep], color="tab:brown", label="box bottom (lowest corner)")
    axes[0].axhline(100 * check.height, color="k", linestyle="--", linewidth=0.8, label="required height")
    for i, leg in enumerate(check.feet):
        colour = COLOURS[i % len(COLOURS)]
        axes[1].plot(t, trace.foot_forces[keep, i], color=colour, label=leg)
        axes[2].plot(t, 100 * trace.foot_positions[keep, i, 2], color=colour, label=leg)
        axes[3].plot(t, 100 * trace.foot_positions[keep, i, 0], color=colour, label=leg)
    axes[1].axhline(check.contact_force, color="k", linestyle="--", linewidth=0.8, label="holding threshold")
    axes[0].set_ylabel("box bottom\nabove ground [cm]")
    axes[1].set_ylabel("foot contact\nforce [N]")
    axes[2].set_ylabel("foot centre\nheight [cm]")
    axes[3].set_ylabel("foot centre\nx [cm]")
    axes[3].set_xlabel("simulated time [s]")
    for row in phases:
        if row.get("t_start") is not None and row["t_start"] >= t_from and row["status"] != "skipped":
            for ax in axes:
                ax.axvline(row["t_start"], color="grey", linestyle=":", linewidth=0.6)
            axes[0].annotate(
                row["name"],
                (row["t_start"], 1.0),
                xycoords=("data", "axes fraction"),
                rotation=90,
                fontsize=6,
                va="top",
                ha="right",
            )
    for ax in axes:
        ax.grid(True, alpha=0.3)
        ax.legend(loc="upper right", fontsize=7)
    if len(t):
        axes[3].set_xlim(float(np.min(t)), float(np.max(t)))
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return Path(path)
