"""Paper 003 (Wolfslag et al.) Section V on the Go1: Table I, Figs. 2-4.

Published (ANYmal, i7-7830X): Table I times per method in the teleoperation and manipulation
scenarios, prongs raising the SUF by up to 35 % at practical heights (Fig. 3).
"""

import tempfile
from pathlib import Path

import numpy as np

from pedi_drake.batch.engines import SerialEngine
from pedi_drake.batch.runner import run_study
from pedi_drake.batch.study import load_study, study_from_dict
from pedi_drake.benchmarks.suf import PAPER_MS, PRACTICAL_HEIGHTS, height_sweep_rows, run_scenario
from pedi_drake.reproduce.report import Comparison, Section
from pedi_drake.resources import studies_dir
from pedi_drake.suf.design import optimise_design, stance_for
from pedi_drake.suf.go1_configuration import stance_problem
from pedi_drake.suf.methods import METHODS, smallest_unrejectable_force
from pedi_drake.viz.suf_plots import plot_accuracy, plot_rfp, plot_suf_vs_height

PUBLISHED_PRONG_BENEFIT = 35.0  # [%] the most prongs add at practical heights (ANYmal)


def reproduce(folder: Path, *, quick: bool = False) -> Section:
    section = Section("003", "Body-ground contact and the Smallest Unrejectable Force")
    rng = np.random.default_rng(0)
    configs = 6 if quick else 40
    scenarios = {
        name: run_scenario(name, configs, min(configs - 1, 10), rng) for name in ("teleoperation", "manipulation")
    }
    for m in METHODS:
        ours = [scenarios[s]["summary"][m]["median_ms"] for s in ("teleoperation", "manipulation")]
        published = PAPER_MS[m]
        section.comparisons.append(
            Comparison(
                f"Table I: {m} [ms], teleoperation / manipulation",
                f"{published[0]:g} / {published[1]:g}",
                f"{ours[0]:.2f} / {ours[1]:.2f}",
                f"speed-up {published[0] / ours[0]:.1f} / {published[1] / ours[1]:.1f} (Go1 stances, this machine)",
            )
        )
    ratios = {m: [r["suf"][m] / r["suf"]["exact"] for r in scenarios["teleoperation"]["rows"]] for m in METHODS}
    plot_accuracy({m: v for m, v in ratios.items() if m != "exact"}, folder / "fig4_accuracy.png")
    section.figures.append(("fig4_accuracy.png", "Fig. 4: SUF of each method over the exact SUF (teleoperation)"))

    study = load_study(studies_dir() / "suf_height_sweep.yaml")
    if quick:
        study = study_from_dict(
            {
                "name": "suf_height_sweep",
                "kind": "suf",
                "factors": [
                    {"name": "trunk_height", "values": [0.20, 0.26]},
                    {"name": "prongs", "values": [False, True]},
                    {"name": "optimise_feet", "values": [True]},
                ],
            },
            "quick height sweep",
        )
    with tempfile.TemporaryDirectory() as results:
        sweep = height_sweep_rows(run_study(study, Path(results), SerialEngine(), quiet=True).rows)
    plot_suf_vs_height(sweep, folder / "fig3_suf_vs_height.png")
    section.figures.append(("fig3_suf_vs_height.png", "Fig. 3: best SUF against trunk height, with and without prongs"))
    practical = [r["benefit_percent"] for r in sweep if PRACTICAL_HEIGHTS[0] <= r["height"] <= PRACTICAL_HEIGHTS[1]]
    section.comparisons.append(
        Comparison(
            "Fig. 3: most the prongs add at practical heights",
            f"{PUBLISHED_PRONG_BENEFIT:.0f} % (ANYmal)",
            f"{max(practical):+.1f} % (Go1)",
            "the Go1's worst force lifts a foot: the unilateral contacts bound it, which prongs barely change",
        )
    )

    heights = [0.20, 0.26] if quick else [0.18, 0.20, 0.22, 0.24, 0.26, 0.28]
    best = optimise_design(heights, prongs=True)
    rfp = {
        "optimised, with prongs": smallest_unrejectable_force(
            stance_problem(stance_for(best.trunk_height, best.feet_x, best.feet_y, True)), "exact"
        ),
        "same stance, without prongs": smallest_unrejectable_force(
            stance_problem(stance_for(best.trunk_height, best.feet_x, best.feet_y, False)), "exact"
        ),
    }
    plot_rfp(rfp, folder / "fig2_rfp.png", limit=150)
    design = (
        f"trunk at {best.trunk_height:.2f} m, feet at (+-{best.feet_x:.2f}, +-{best.feet_y:.2f}) m, "
        f"SUF {best.suf:.1f} N by the affine method"
    )
    section.figures.append(("fig2_rfp.png", f"Fig. 2: rejectable force polytopes of the optimised design ({design})"))
    section.not_yet += [
        "Figs. 5-6 (push recovery on four legs with and without prongs)",
        "Figs. 9-10 (box lift with the two side legs)",
    ]
    return section
