"""Paper 002 (Xin et al., ANYmal) Section IV on the Go1: IV-A (Figs. 3 to 5) and IV-B (Fig. 7).

Published (simulation, ANYmal; the text states no figure's numbers, only what they show):

* IV-A: five dimensions of the left-fore foot held in the world (yaw relaxed) while the torso
  tracks a circle in the x-y plane at constant height; the foot's yaw error "much greater than
  the other directions" and the torso's tracking "not as good as the foot", since the torso is
  controlled in the foot's null space;
* IV-B: the torso rotates in pitch, roll and yaw about one prong while the two rear feet stand
  and the fore feet keep their positions, with no change to the controller;
* planner, controller and state estimator in one 400 Hz cycle on an i7-4600U (2.1 GHz);
* in its text (no figures): six dimensions of a foot ("in fact, the shank") controlled for
  manipulation, a leg that "overcame a singularity configuration without instability", the
  controllers switched at runtime from the GUI, and the E-stop pressed by a teleoperated foot
  with its force estimate fed back (IV-C f).

Ours: the same runs on paper 002's controller (`projected_impedance`) and, for comparison, on
the paper-000 HQP (`whole_body`), on the Kalman estimate, judged on simulation ground truth by
`pedi_drake.benchmarks.paper002.mission_row`. `--quick` runs the short versions in
missions/quick/ (one lap, each rotation once) on paper 002's controller only. A full run adds
the text's four claims, each from the benchmark that measures it (one run each: seed 0).
"""

import json
from pathlib import Path

from pedi_drake.benchmarks import controller_switches, estop_button, reach_edge, shank_hold
from pedi_drake.benchmarks.paper002 import mission_row
from pedi_drake.evaluation import paper002 as evaluation
from pedi_drake.reproduce.report import Comparison, Section
from pedi_drake.resources import missions_dir

CONTROLLERS = ("projected_impedance", "whole_body")
# (name, shipped mission, its short version) per evaluation.
EVALUATIONS = (
    ("IV-A", "torso_circle_foot_hold", "quick/torso_circle_one_lap"),
    ("IV-B", "prong_pivot_rotations", "quick/pivot_rotations_once"),
)
PUBLISHED_CYCLE_MS = 2.5  # [ms] one 400 Hz cycle of planner, controller and estimator together


def evaluation_rows(folder: Path, *, quick: bool = False) -> list[dict]:
    """The IV-A and IV-B rows (benchmark `mission_row`) with their figures under `folder`."""
    rows = []
    for name, shipped, short in EVALUATIONS:
        for controller in CONTROLLERS[:1] if quick else CONTROLLERS:
            if quick:
                mission, scenario_text = str(missions_dir() / f"{short}.yaml"), "robot: {initial_pose: standing}"
            else:
                mission, scenario_text = shipped, ""
            row = mission_row(
                mission,
                controller,
                folder / "runs" / controller / Path(short if quick else shipped).name,
                folder / "figures",
                scenario_text=scenario_text,
                case=name,
            )
            rows.append(row)
    return rows


def _iv_a(row: dict) -> list[Comparison]:
    controller = row["controller"]
    if "foot_position_error_max_m" not in row:
        return [Comparison(f"IV-A ({controller})", "runs", f"FAILED: {row['reason']}")]
    foot_mm, torso_mm = 1000 * row["foot_position_error_max_m"], 1000 * row["torso_tracking_rms_m"]
    roll_pitch, yaw = row["foot_orientation_error_max_deg"], row["foot_yaw_error_max_deg"]
    return [
        Comparison(
            f"IV-A Fig. 4: held foot position error, max ({controller})",
            "shown, no number given",
            f"{foot_mm:.2f} mm",
            f"floor {1000 * evaluation.FOOT_POSITION_FLOOR_M:.0f} mm",
        ),
        Comparison(
            f"IV-A Fig. 5: foot roll/pitch error, max; yaw (free) ({controller})",
            "yaw error much greater than the other directions",
            f"{roll_pitch:.2f} deg; yaw {yaw:.2f} deg",
            f"yaw {yaw / max(roll_pitch, 1e-9):.0f} times roll/pitch"
            + ("" if yaw > roll_pitch else ", unlike the paper")
            + ": yaw is relaxed, and the Go1's leg (hip roll, thigh and calf pitch) cannot turn the calf "
            "in yaw without the trunk",
        ),
        Comparison(
            f"IV-A Fig. 3: torso circle tracking, RMS ({controller})",
            "not as good as the foot's",
            f"{torso_mm:.2f} mm",
            f"{torso_mm / max(foot_mm, 1e-9):.1f} times the foot's largest error"
            + (", as in the paper" if torso_mm > foot_mm else ", unlike the paper")
            + (
                " (the torso is in the foot's null space)"
                if controller == "projected_impedance"
                else " (the HQP weighs torso and foot in one level: both give)"
            )
            + "; a 1.5 cm circle: with the foot's position, roll and pitch held, the Go1's three leg joints leave "
            "the trunk one translation at fixed attitude (see the mission's description)",
        ),
    ]


def _iv_b(row: dict) -> list[Comparison]:
    if "rotation_reached_deg" not in row:
        return [Comparison(f"IV-B ({row['controller']})", "runs", f"FAILED: {row['reason']}")]
    reached = ", ".join(f"{axis} {lo:+.1f}/{hi:+.1f}" for axis, (lo, hi) in row["rotation_reached_deg"].items())
    return [
        Comparison(
            f"IV-B Fig. 7: trunk rotation about one prong ({row['controller']})",
            "pitch, roll and yaw, amplitude not given",
            f"{reached} deg",
            "6 deg asked each way (5 deg the floor), about a start 0.14 rad nose down (so that only the "
            "front prong is loaded): 6 deg nose up leaves the rear prong's tip 1 cm above the floor",
        ),
        Comparison(
            f"IV-B: front feet held, largest displacement ({row['controller']})",
            "keep their positions",
            f"{1000 * row['front_feet_drift_max_m']:.2f} mm (prong tip slip {1000 * row['pivot_slip_max_m']:.1f} mm)",
            "true foot positions; the feet are held in the estimated world (Kalman estimate)",
        ),
    ]


def _text_claims(folder: Path) -> list[Comparison]:
    """The claims of the paper's text, each measured by one seed-0 run of its benchmark."""
    comparisons = []
    for controller in CONTROLLERS:
        row = shank_hold.one_run(controller, "6-D", folder)
        held = (
            f"foot within {1000 * row['foot_position_error_max_m']:.1f} mm, calf within "
            f"{max(row['calf_roll_error_max_deg'], row['calf_pitch_error_max_deg'], row['calf_yaw_error_max_deg']):.2f}"
            f" deg while the trunk moved {1000 * row['trunk_displacement_max_m']:.1f} mm"
            if "foot_position_error_max_m" in row
            else f"FAILED: {row['reason']}"
        )
        comparisons.append(
            Comparison(
                f"six dimensions of the shank held ({controller})",
                "controlled for manipulation (no figure)",
                held,
                "missions/evaluations/shank_hold.yaml; the 5-D task beside it: "
                "python -m pedi_drake.benchmarks.shank_hold",
            )
        )
        edge, _ = reach_edge.one_run(controller)
        passed = (
            f"{'no fall' if not edge['fell'] else 'FELL'}; foot error "
            f"{1000 * edge['foot_error_beyond_reach_max_m']:.1f} mm beyond reach, "
            f"{1000 * edge['foot_error_after_max_m']:.2f} mm after; torque at most "
            f"{100 * edge['torque_share_of_limit_max']:.0f} % of its limit"
            if "foot_error_beyond_reach_max_m" in edge
            else f"FAILED: {edge['reason']}"
        )
        comparisons.append(
            Comparison(
                f"a singularity passed without instability ({controller})",
                "overcame a singularity configuration without instability",
                passed,
                "the Go1's knee cannot straighten within its limits: the foot is driven 1.8 cm beyond the edge "
                "of its reach instead (missions/evaluations/reach_edge.yaml)",
            )
        )
    switches = controller_switches.one_run(0, 20)
    comparisons.append(
        Comparison(
            "controllers switched at runtime",
            "from the GUI (no figure)",
            f"{switches['switches']} hand-overs, {'mission done' if switches['success'] else 'FAILED'}, "
            f"{'no fall' if not switches['fell'] else 'FELL'}; largest joint-target step "
            f"{switches['max_target_step_rad']:.4f} rad (rate limit {switches['target_step_limit_rad']:.3f})",
            "20 random operator requests with a foot lifted, and the mission's own four",
        )
    )
    press = estop_button.one_run("projected_impedance", 0)
    comparisons.append(
        Comparison(
            "IV-C f: E-stop pressed by the teleoperated foot, Eq. 11 fed back",
            "pressed (no force stated)",
            f"{'pressed' if press['pressed'] else 'NOT pressed'}, largest true force "
            f"{press['max_true_force_n']:.1f} N against the {press['force_bound_n']:.0f} N bound",
            "paper 002's controller with its Eq. 11 estimate (scenario estop_paper002), a scripted operator",
        )
    )
    return comparisons


def reproduce(folder: Path, *, quick: bool = False) -> Section:
    section = Section("002", "Variable autonomy of whole-body control (IV-A, IV-B)")
    rows = evaluation_rows(folder, quick=quick)
    (folder / "rows.json").write_text(json.dumps(rows, indent=2, default=float))
    for row in rows:
        section.comparisons += _iv_a(row) if row["case"] == "IV-A" else _iv_b(row)
        section.comparisons.append(
            Comparison(
                f"{row['case']}: controller tick, median / p99 ({row['controller']})",
                f"{PUBLISHED_CYCLE_MS} ms cycle (planner, controller, estimator; i7-4600U)",
                f"{row['tick_median_ms']:.2f} / {row['tick_p99_ms']:.2f} ms",
                "the controller alone, Python on this machine, shared with other work",
            )
        )
        for path in row.get("plots", []):
            caption = {
                "iva_positions.png": "Fig. 3: torso and held foot positions",
                "iva_foot_position_error.png": "Fig. 4: held foot position error",
                "iva_foot_orientation_error.png": "Fig. 5: held foot (calf) orientation error",
                "ivb_rotations.png": "Fig. 7: trunk rotations about one prong, front feet displacement",
            }[Path(path).name]
            section.figures.append((str(Path(path).relative_to(folder)), f"{caption} ({row['controller']})"))
    if not quick:
        section.comparisons += _text_claims(folder)
    section.notes.append(
        "The paper's figures are curves without stated values; where it says how they compare "
        "(yaw error against the others, torso against foot), the same comparison can be read off ours. "
        "Ours are the Go1 in Drake judged on ground truth; the paper's are ANYmal in its simulator."
    )
    if quick:
        section.notes.append(
            "Quick run: the short missions in missions/quick/ on paper 002's controller only; "
            "not the published comparison."
        )
    return section
