"""Paper 003 (Wolfslag et al.) Sections V and VII on the Go1: Table I, Figs. 2-4, Figs. 5-6, and
the box lift of Figs. 9-10.

Published (ANYmal, i7-7830X): Table I times per method in the teleoperation and manipulation
scenarios, prongs raising the SUF by up to 35 % at practical heights (Fig. 3); pushed at the
middle of the trunk with about 30 N for 5 s in the default stance lowered to prong height, the
knee torque is "significantly lower with prong, despite a slightly stiffer torso" (Fig. 6, no
numbers in the text). Section VII-C: leaning on the prongs and the right legs, the robot lifts a
box between its two left feet "controlled in task-space with low-gains" (Figs. 9-10: motion
stills of two boxes, no numbers in the text).
"""

import tempfile
from pathlib import Path

import numpy as np

from pedi_drake.batch.engines import SerialEngine
from pedi_drake.batch.runner import run_study
from pedi_drake.batch.study import load_study, study_from_dict
from pedi_drake.benchmarks.demos import demo_scenario
from pedi_drake.benchmarks.prong_push import DESIGNS, DIRECTIONS, one_run
from pedi_drake.benchmarks.suf import PAPER_MS, PRACTICAL_HEIGHTS, height_sweep_rows, run_scenario
from pedi_drake.diagram import apply_mission
from pedi_drake.evaluation.box_lift import box_corners_B, box_lift_trace
from pedi_drake.evaluation.judge import judge_run, scene_graph_inspector, write_run
from pedi_drake.evaluation.push_response import STANCE_FOOT_SLIDE_LIMIT, push_series
from pedi_drake.reproduce.box_lift_plots import plot_box_lift
from pedi_drake.reproduce.push_plots import plot_push_response
from pedi_drake.reproduce.report import Comparison, Section
from pedi_drake.resources import studies_dir
from pedi_drake.run import simulate
from pedi_drake.scenario import load_scenario
from pedi_drake.suf.design import optimise_design, stance_for
from pedi_drake.suf.methods import METHODS, smallest_unrejectable_force
from pedi_drake.suf.stances import stance_problem
from pedi_drake.viz.suf_plots import plot_accuracy, plot_rfp, plot_suf_vs_height

PUBLISHED_PRONG_BENEFIT = 35.0  # [%] the most prongs add at practical heights (ANYmal)
# The push missions (default scenario: from lying, on the Kalman estimate), with and without
# prongs; --quick runs their short demos (from standing, on the simulated true state).
PUSH_MISSIONS = {"with prongs": "push_recovery_prongs", "without prongs": "push_recovery_no_prongs"}
QUICK_PUSH_DEMOS = {"with prongs": "push_recovery_short_prongs", "without prongs": "push_recovery_short_no_prongs"}
# The paper's Fig. 6 shows the left front knee.
FIG6_KNEE = "FL"
# The box lift: the mission (default scenario: from lying, on the Kalman estimate); --quick runs
# its short demo (from standing, on the simulated true state, a 1 s hold).
BOX_LIFT_MISSION, QUICK_BOX_LIFT_DEMO = "box_lift_side_legs", "box_lift_short"


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
    _push_recovery(folder, section, quick)
    if not quick:
        _prong_placement(folder, section)
    _box_lift(folder, section, quick)
    return section


def _run_judged(folder: Path, mission: str, quick_demo: str | None):
    """(record, result) of `mission` on the default scenario (or of `quick_demo` on its own demo
    scenario), judged by physics and written to folder/<name>."""
    if quick_demo is not None:
        name, scenario = quick_demo, demo_scenario(quick_demo)
    else:
        name = mission
        scenario = load_scenario(
            scenario_text=f"{{mission: {mission}, controller: whole_body, simulation_duration: 60.0}}"
        )
    record = simulate(scenario=scenario, name=name, quiet=True, replay=False)
    result = judge_run(record)
    (folder / name).mkdir(parents=True, exist_ok=True)
    write_run(record, result, folder / name)
    return record, result


def _prong_placement(folder: Path, section: Section) -> None:
    """Section VII-A's claim, controlled: the push along x and along y, without prongs, with a pair on
    the centre line and with a pair at the sides (pedi_drake.benchmarks.prong_push)."""
    (folder / "prong_push").mkdir(parents=True, exist_ok=True)
    largest = {
        (direction, design): one_run(design, direction, folder / "prong_push")["largest_knee_torque_added_Nm"]
        for direction in DIRECTIONS
        for design in DESIGNS
    }
    for direction in DIRECTIONS:
        across = "centre_line" if direction == "x" else "sides"
        holds = largest[direction, across] < largest[direction, "none"]
        section.comparisons.append(
            Comparison(
                f"largest knee torque a 30 N push along {direction} adds [N m]: no prongs / centre-line pair / "
                "side pair",
                "significantly lower with prongs",
                " / ".join(f"{largest[direction, design]:.2f}" for design in DESIGNS),
                f"the pair whose line runs along the push ({across.replace('_', ' ')}) carries its moment: "
                + ("lower with it, as the paper says" if holds else "NOT lower with it")
                + "; a pair across the push takes its force by friction but not its moment "
                "(python -m pedi_drake.benchmarks.prong_push)",
            )
        )


def _box_lift(folder: Path, section: Section, quick: bool) -> None:
    """Figs. 9-10: the box lift with the two left legs, run, judged by physics and plotted."""
    record, result = _run_judged(folder, BOX_LIFT_MISSION, QUICK_BOX_LIFT_DEMO if quick else None)
    name, scenario, mission = record.name, record.scenario, record.built.mission
    check = mission.box_lift
    plant = record.built.diagram.GetSubsystemByName("station").GetSubsystemByName("plant")
    states, forces = record.logs["sim.plant_state"], record.logs["sim.foot_contact_forces"]
    trace = box_lift_trace(
        plant, scene_graph_inspector(record), check, states.times, states.data, forces.times, forces.data
    )
    lift = result["box_lift"]
    phases = {row["name"]: row for row in result["phases"]}
    squeeze = next(phase for phase in mission.phases if phase.name == "squeeze")
    t_from = phases["squeeze"]["t_start"] - 2.0 if phases["squeeze"]["t_start"] is not None else 0.0
    plot_box_lift(trace, check, result["phases"], folder / "fig9_box_lift.png", t_from=t_from)
    section.figures.append(
        (
            "fig9_box_lift.png",
            f"Figs. 9-10 as time series ({name}): the box's lowest corner, the contact force and position of "
            f"{' and '.join(check.feet)} (ground truth)",
        )
    )
    held = trace.bottom_height >= check.height
    window = held & (trace.times >= (lift["held_from_s"] or 0.0))
    heights = trace.foot_positions[window][:, :, 2] if lift["held_from_s"] is not None else np.zeros((0, 2))
    outcome = "succeeded" if result["success"] else f"FAILED ({result['reason']})"
    forces_held = lift["mean_foot_force_held_n"]
    section.comparisons += [
        Comparison(
            "Figs. 9-10: the box lift",
            "on the prongs and the right legs, leaning right, the two left feet lift a box in a low-gain "
            "task-space mode (motion stills of two boxes; no numbers)",
            f"{outcome}: the box's bottom {100 * lift['max_bottom_height_m']:.1f} cm above the ground at most, "
            f"{lift['held_s']:.2f} s at {100 * check.height:.0f} cm or more held by {'+'.join(check.feet)} "
            f"(required {check.hold:.1f} s); dropped: {'no' if lift['dropped_at_s'] is None else lift['dropped_at_s']}",
            f"a {_box_summary(plant, record, check)} box (the mission's scene), judged on the simulated plant state",
        ),
        Comparison(
            "low-gain foot mode: stiffness, and the squeeze",
            "low task-space gains (values not given)",
            f"kp {squeeze.foot_gains.kp:g} 1/s^2, kd {squeeze.foot_gains.kd:g} 1/s (the default foot task: "
            f"{scenario.whole_body.foot_position.kp:g}, {scenario.whole_body.foot_position.kd:g}); references "
            f"moved {100 * abs(squeeze.feet[0].offset[0]):.0f} cm inwards from beside the faces; "
            "contact force while held "
            + (" / ".join(f"{f:.1f}" for f in forces_held) + " N" if forces_held else "none")
            + f" ({'/'.join(check.feet)})",
            "the Eq. 1 foot acceleration task at lower gains: blocked by the box, each foot pushes with about its "
            "leg's task-space inertia times kp times the distance of its reference inside",
        ),
        Comparison(
            "foot heights while held [cm], min-max",
            "not reported",
            " / ".join(f"{100 * heights[:, i].min():.1f}-{100 * heights[:, i].max():.1f}" for i in range(2))
            if len(heights)
            else "not held",
            f"the references rose {100 * _lift_offset(mission):.0f} cm; the difference is the sag under the "
            "box's weight at the low gains",
        ),
        Comparison(
            "largest trunk drift while legs are lifted [mm]",
            "not reported",
            f"{1e3 * result['max_base_drift_m']:.1f}",
            "the trunk origin from its reference (ground truth)",
        ),
    ]
    section.notes.append(
        "Figs. 9-10 of paper 003 are photographs. The paper enforces a smooth contact force when the left legs "
        "are lifted; here the controller ramps a released contact's force bounds out over its contact_ramp_time."
    )


def _box_summary(plant, record, check) -> str:
    """The box's size [m] and mass [kg], as the plant has them."""
    box = plant.GetBodyByName(check.box, plant.GetModelInstanceByName(check.box))
    corners = box_corners_B(plant, scene_graph_inspector(record), box)
    size = corners.max(axis=0) - corners.min(axis=0)
    return " x ".join(f"{v:.2f}" for v in size) + f" m, {box.default_mass():.2f} kg"


def _lift_offset(mission) -> float:
    """How far the lift phase raises the feet's references [m]."""
    lift = next(phase for phase in mission.phases if phase.name == "lift")
    return float(lift.feet[0].offset[2])


def _pair(rows: dict[str, dict], value, digits: int = 1, scale: float = 1.0) -> str:
    """'with / without' of value(row) for the two push runs."""
    return " / ".join(f"{scale * value(rows[label]):.{digits}f}" for label in PUSH_MISSIONS)


def _push_recovery(folder: Path, section: Section, quick: bool) -> None:
    """Figs. 5-6: the push with and without prongs, run, judged and plotted on one time axis."""
    rows, series = {}, {}
    for label, mission in PUSH_MISSIONS.items():
        record, result = _run_judged(folder, mission, QUICK_PUSH_DEMOS[label] if quick else None)
        (spec,) = apply_mission(record.scenario, record.built.mission).pushes
        plant = record.built.diagram.GetSubsystemByName("station").GetSubsystemByName("plant")
        series[label] = push_series(plant, record.logs, spec)
        rows[label] = {**result["pushes"][0], **{key: result[key] for key in ("success", "reason", "stack")}}
    plot_push_response(series, folder / "fig6_push.png", knee_leg=FIG6_KNEE)
    section.notes.append(
        "Figs. 5-6 of paper 003 are images (ANYmal pushed by hand through a force-torque sensor); the text "
        "gives no numbers for them, so the published column quotes Section VII-A's statements."
    )
    push = rows["with prongs"]
    section.figures.append(
        (
            "fig6_push.png",
            f"Fig. 6: trunk displacement, push force and {FIG6_KNEE} knee torque with (red) and without (blue) "
            f"prongs, {push['force_N']:.0f} N at the middle of the trunk along {spec.direction} "
            f"({', '.join(QUICK_PUSH_DEMOS.values() if quick else PUSH_MISSIONS.values())})",
        )
    )
    outcome = " / ".join(
        "succeeded" if r["success"] else f"FAILED ({r['reason']})" for r in (rows[label] for label in PUSH_MISSIONS)
    )
    # The legs on the side the push goes to take its roll moment (the right ones, y < 0, for -y).
    loaded = ("FR", "RR") if spec.direction[1] < 0 else ("FL", "RL")
    added = {
        label: float(np.mean([r["knee_torque_full_force_Nm"][leg] - r["knee_torque_before_Nm"][leg] for leg in loaded]))
        for label, r in rows.items()
    }
    section.comparisons += [
        Comparison(
            "Fig. 5: the push",
            "about 30 N by hand through a force sensor, at the middle of the base, held 5 s; "
            "default stance lowered to prong height",
            f"{push['force_N']:.0f} N at the trunk origin along {spec.direction}, "
            f"{push['end_s'] - push['start_s']:.0f} s "
            f"from start to end (ramps included); on {len(push['stance_legs'])} feet at prong height, "
            f"stack {push['stack']}",
            "a scheduled force of the simulated world (the missions' `pushes`), not a hand",
        ),
        Comparison(
            "Fig. 6: run outcome, with / without prongs",
            "no fall",
            outcome,
            f"physics is the judge: no fall, no stance foot sliding more than {100 * STANCE_FOOT_SLIDE_LIMIT:.0f} cm",
        ),
        Comparison(
            "largest stance-foot slide [mm], with / without prongs",
            "not reported",
            _pair(rows, lambda r: r["max_foot_slide_m"], 2, 1e3)
            + " (per foot FR, FL, RR, RL: "
            + "; ".join(
                ", ".join(f"{1e3 * rows[label]['foot_slide_m'][leg]:.2f}" for leg in rows[label]["foot_slide_m"])
                for label in PUSH_MISSIONS
            )
            + ")",
            "simulated foot centres, from where each stood at the push's start",
        ),
        Comparison(
            "Fig. 6: largest trunk displacement [mm], with / without prongs",
            "slightly stiffer torso with prongs (figure only)",
            _pair(rows, lambda r: r["trunk_displacement_m"], 1, 1e3),
            "the trunk origin from its position at the push's start (ground truth)",
        ),
        Comparison(
            f"Fig. 6: {FIG6_KNEE} knee torque at full force [N m], with / without prongs",
            "significantly lower with prongs (figure only)",
            _pair(rows, lambda r: r["knee_torque_full_force_Nm"][FIG6_KNEE], 2)
            + f" (before the push: {_pair(rows, lambda r: r['knee_torque_before_Nm'][FIG6_KNEE], 2)})",
            "mean calf motor torque",
        ),
        Comparison(
            "largest stance knee torque over the push [N m], with / without prongs",
            "lower with prongs",
            _pair(rows, lambda r: max(r["knee_torque_peak_Nm"].values()), 2),
            "the largest absolute calf motor torque of the stance legs",
        ),
        Comparison(
            f"knee torque the push adds on the loaded side ({', '.join(loaded)}) [N m], with / without prongs",
            "lower with prongs (the paper's amplification from force to torque)",
            " / ".join(f"{added[label]:.2f}" for label in PUSH_MISSIONS),
            "mean at full force minus mean before the push. The shipped prongs sit on the trunk's centre line; "
            f"they took {_pair(rows, lambda r: abs(r['prong_share_of_push']), 0, 100)} % of the sideways force "
            f"at the ground and {_pair(rows, lambda r: abs(r['prong_load_N']), 0)} N of the weight, but no roll "
            "moment about their own line, which a push along y makes; the prong placement comparison below "
            "pushes along x and y with the prongs placed either way.",
        ),
    ]
