"""Paper 002 (Xin et al., ANYmal) Section IV on the Go1: IV-A (Figs. 3 to 5) and IV-B (Fig. 7).

Published (simulation, ANYmal; the text states no figure's numbers, only what they show):

* IV-A: five dimensions of the left-fore foot held in the world (yaw relaxed) while the torso
  tracks a circle in the x-y plane at constant height; the foot's yaw error "much greater than
  the other directions" and the torso's tracking "not as good as the foot", since the torso is
  controlled in the foot's null space;
* IV-B: the torso rotates in pitch, roll and yaw about one prong while the two rear feet stand
  and the fore feet keep their positions, with no change to the controller;
* planner, controller and state estimator in one 400 Hz cycle on an i7-4600U (2.1 GHz).

Ours: the same runs on paper 002's controller (`projected_impedance`) and, for comparison, on
the paper-000 HQP (`whole_body`), on the Kalman estimate, judged on simulation ground truth by
`pedi_drake.benchmarks.paper002.mission_row`. `--quick` runs the short versions in
missions/quick/ (one lap, each rotation once) on paper 002's controller only.
"""

import json
from pathlib import Path

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
