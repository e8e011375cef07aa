"""Paper 003's push-recovery figure (Fig. 6) in matplotlib: trunk displacement, applied force and
a knee torque, with and without prongs, on one time axis from the push's start."""

from pathlib import Path

import matplotlib.pyplot as plt

from pedi_drake import robot
from pedi_drake.evaluation.push_response import PushSeries

# Paper 003's colours: red with prongs, blue without.
COLOURS = ("tab:red", "tab:blue", "tab:green", "tab:purple")


def plot_push_response(series: dict[str, PushSeries], path: Path, knee_leg: str = "FL") -> Path:
    """Three panels sharing the time axis, one line per entry {label: PushSeries}: the trunk's
    displacement along the push [mm], the push force [N], and the `knee_leg` calf torque [N m]
    (paper 003 shows the left front knee)."""
    fig, axes = plt.subplots(3, 1, figsize=(7, 7.5), sharex=True)
    knee = robot.LEG_NAMES.index(knee_leg)
    for (label, s), colour in zip(series.items(), COLOURS, strict=False):
        axes[0].plot(s.times, 1e3 * s.displacement, color=colour, label=label)
        axes[1].plot(s.times, s.force, color=colour, label=label)
        axes[2].plot(s.times, s.knee_torques[knee], color=colour, label=label)
    axes[0].set_ylabel("trunk displacement\nalong the push [mm]")
    axes[1].set_ylabel("push force [N]")
    axes[2].set_ylabel(f"{knee_leg} knee torque [N m]")
    axes[2].set_xlabel("time from the push's start [s]")
    for ax in axes:
        ax.grid(True, alpha=0.3)
    axes[0].legend(loc="best")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return Path(path)
