"""Figures of the SUF analysis (paper 003, Figs. 2-4) in matplotlib, and the RFP in Meshcat.

* `plot_rfp`: rejectable force polytopes [N] with the SUF sphere, one panel per design (Fig. 2);
* `plot_suf_vs_height`: the best SUF per trunk height with and without prongs (Fig. 3);
* `plot_accuracy`: boxplot of each method's SUF relative to exact (Fig. 4);
* `show_rfp_in_meshcat`: the polytope drawn at the end-effector, scaled from newtons to metres.
"""

from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np
from mpl_toolkits.mplot3d.art3d import Poly3DCollection
from scipy.spatial import ConvexHull

from pedi_drake.suf.methods import SufResult


def _hull_triangles(vertices: np.ndarray) -> np.ndarray:
    hull = ConvexHull(vertices)
    return vertices[hull.simplices]  # (m, 3, 3)


def plot_rfp(results: dict[str, SufResult], path: Path | None = None, limit: float | None = None):
    """One 3D panel per entry {label: exact SufResult}: the RFP and the sphere of radius SUF at F = 0."""
    fig = plt.figure(figsize=(5.5 * len(results), 5))
    for k, (label, result) in enumerate(results.items()):
        ax = fig.add_subplot(1, len(results), k + 1, projection="3d")
        vertices = result.polytope.vertices
        ax.add_collection3d(
            Poly3DCollection(_hull_triangles(vertices), alpha=0.25, facecolor="tab:blue", edgecolor="tab:blue", lw=0.3)
        )
        u, v = np.meshgrid(np.linspace(0, 2 * np.pi, 24), np.linspace(0, np.pi, 12))
        r = result.value
        ax.plot_surface(r * np.cos(u) * np.sin(v), r * np.sin(u) * np.sin(v), r * np.cos(v), color="tab:red", alpha=0.5)
        ax.quiver(0, 0, 0, *(r * result.direction), color="k", linewidth=2)
        reach = limit or max(3.0 * r, 1.0)
        for setter in (ax.set_xlim, ax.set_ylim, ax.set_zlim):
            setter(-reach, reach)
        ax.set_xlabel("F_x [N]")
        ax.set_ylabel("F_y [N]")
        ax.set_zlabel("F_z [N]")
        ax.set_title(f"{label}: SUF {r:.1f} N")
    fig.tight_layout()
    if path is not None:
        fig.savefig(path, dpi=90)
        plt.close(fig)
    return fig


def plot_suf_vs_height(rows: list[dict], path: Path | None = None):
    """Fig. 3 from `design.height_sweep` rows."""
    heights = [r["height"] for r in rows]
    fig, ax = plt.subplots(figsize=(6, 4))
    ax.plot(heights, [r["without"]["suf"] for r in rows], "o-", label="without prongs")
    ax.plot(heights, [r["with_prongs"]["suf"] for r in rows], "s-", label="with prongs")
    ax.set_xlabel("trunk height [m]")
    ax.set_ylabel("SUF, feet optimised [N]")
    ax.grid(alpha=0.3)
    ax.legend()
    fig.tight_layout()
    if path is not None:
        fig.savefig(path, dpi=90)
        plt.close(fig)
    return fig


def plot_accuracy(ratios: dict[str, list[float]], path: Path | None = None):
    """Fig. 4: boxplot of SUF / exact SUF per method; above 1 (shaded) is not conservative."""
    fig, ax = plt.subplots(figsize=(6, 4))
    labels = list(ratios)
    ax.boxplot([ratios[m] for m in labels])
    ax.set_xticks(range(1, len(labels) + 1), labels)
    ax.axhspan(1.0, max(1.05, max(max(v) for v in ratios.values()) + 0.02), color="tab:red", alpha=0.08)
    ax.axhline(1.0, color="k", lw=0.8)
    ax.set_ylabel("SUF / exact SUF")
    ax.grid(alpha=0.3, axis="y")
    fig.tight_layout()
    if path is not None:
        fig.savefig(path, dpi=90)
        plt.close(fig)
    return fig


def show_rfp_in_meshcat(meshcat, result: SufResult, p_WE: np.ndarray, metres_per_newton: float = 0.005, name="suf"):
    """Draws the RFP (and the SUF sphere) at the end-effector p_WE [m], forces scaled to lengths."""
    from pydrake.geometry import Rgba, Sphere
    from pydrake.math import RigidTransform

    vertices = result.polytope.vertices * metres_per_newton
    hull = ConvexHull(vertices)
    faces = hull.simplices.copy()
    for k, (a, b, c) in enumerate(faces):  # outward winding for the renderer
        if np.dot(np.cross(vertices[b] - vertices[a], vertices[c] - vertices[a]), hull.equations[k, :3]) < 0:
            faces[k] = (a, c, b)
    meshcat.SetTriangleMesh(f"{name}/rfp", (vertices + p_WE).T, faces.T, Rgba(0.2, 0.4, 0.9, 0.35))
    meshcat.SetObject(f"{name}/sphere", Sphere(result.value * metres_per_newton), Rgba(0.9, 0.2, 0.2, 0.5))
    meshcat.SetTransform(f"{name}/sphere", RigidTransform(p_WE))


def plot_live_suf(times: np.ndarray, readings: list, phases: list[dict], path: Path) -> Path:
    """The live SUF along a run (one point per update with a lifted foot): the SUF [N] (exact:
    a line; the single-direction fallback: crosses) and the rejectable force along the direction
    the mission asked about (its push), over the mission's phases."""
    from pedi_drake.suf.warm_projection import EXACT, INCOMPLETE
    from pedi_drake.viz.plots import _shade_phases

    fig, ax = plt.subplots(figsize=(9, 3.8))
    _shade_phases(ax, phases)
    values = np.array([r.value for r in readings], float)
    reaches = np.array([r.reach for r in readings], float)
    exact = np.array([r.status == EXACT for r in readings])
    fallback = np.array([r.status == INCOMPLETE for r in readings])
    ax.plot(times, np.where(exact, values, np.nan), color="tab:blue", label="SUF (exact)")
    if fallback.any():
        ax.plot(times[fallback], values[fallback], "x", color="tab:red", label="single-direction SUF (fallback)")
    ax.plot(times, reaches, color="tab:green", linewidth=0.8, label="rejectable force along the push")
    ax.set_xlabel("time [s]")
    ax.set_ylabel("force [N]")
    ax.set_title("live SUF of the lifted-leg stance")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=90)
    plt.close(fig)
    return Path(path)
