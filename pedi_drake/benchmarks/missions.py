"""Every shipped mission in simulation: seed 0 without noise, and more seeds with sensor noise.

    python -m pedi_drake.benchmarks.missions [--missions a,b] [--noise-seeds 1,2,3,4,5]
        [--engine ray|serial] [--out benchmarks/results/missions.json]

A batch study (the same as studies/missions_benchmark.yaml), run on Ray (every core of this
machine) or serially. Prints one row per mission (successes, foot errors, trunk drift,
real-time factor without any visualisation, the estimator's largest errors against the
simulated truth, the capture point's smallest margin in the safety polygon on three feet [mm],
and the mission-specific checks: door opening, box push, obstacle classification) and writes
every run's result.json content to the JSON file.
"""

import argparse
import json
import statistics
import tempfile
from pathlib import Path

from pedi_drake.batch.engines import ENGINES, make_engine
from pedi_drake.batch.results_file import read_rows
from pedi_drake.batch.runner import run_study
from pedi_drake.batch.study import study_from_dict
from pedi_drake.benchmarks.machine import stamped
from pedi_drake.mission.spec import load_mission, shipped_missions

# What each press of the obstacle-sensing missions touches, from the missions' scenes:
# {mission: {press phase: (rigid or soft, fixed or mobile)}}.
EXPECTED_OBSTACLES = {
    "obstacle_sensing": {"press_a": ("rigid", "fixed"), "press_b": ("soft", "fixed")},
    "obstacle_sensing_mobile": {"press_c": ("rigid", "mobile"), "press_d": ("soft", "mobile")},
}


def obstacle_calls(presses: list[dict]) -> dict[str, tuple[str, str]]:
    """{press phase: (rigid or soft, fixed or mobile)} as a run's `presses` classified them."""
    return {press["phase"]: (press["classified_as"], press["mobility"]) for press in presses}


def mission_study(missions: list[str], noise_seeds: list[int]):
    """The study of `missions` at seed 0 without noise and at each of `noise_seeds` with noise."""
    noise = [{"random_seed": 0, "sensor_noise.enabled": False}]
    noise += [{"random_seed": seed, "sensor_noise.enabled": True} for seed in noise_seeds]
    return study_from_dict(
        {
            "name": "missions_benchmark",
            "kind": "mission",
            "base": {"scenario_text": "{simulation_duration: 60.0}"},
            "timeout": 900,
            "factors": [{"name": "mission", "values": missions}, {"name": "noise", "values": noise}],
        },
        "pedi_drake.benchmarks.missions",
    )


def result_of(row: dict) -> dict:
    """A study row's result.json content (a crashed or timed-out task becomes a failed result)."""
    if "result" in row:
        return row["result"]
    return {
        "success": False,
        "fell": False,
        "reason": f"{row['status']}: {row['reason']}",
        "foot_errors_m": [],
        "max_base_drift_m": 0.0,
        "real_time_factor": 0.0,
    }


def summarise(mission: str, runs: list[dict]) -> dict:
    """Per-mission figures over its runs."""
    errors = [row["error"] for r in runs for row in r["foot_errors_m"]]
    row = {
        "runs": len(runs),
        "succeeded": sum(r["success"] for r in runs),
        "fell": sum(r["fell"] for r in runs),
        "foot_error_median_m": statistics.median(errors) if errors else None,
        "foot_error_max_m": max(errors) if errors else None,
        "max_base_drift_m": max(r["max_base_drift_m"] for r in runs),
        "real_time_factor_median": statistics.median(r["real_time_factor"] for r in runs),
        "failures": [r["reason"] for r in runs if not r["success"]],
    }
    margins = [r["three_leg_capture_point_margin_m"] for r in runs if r.get("three_leg_capture_point_margin_m")]
    if margins:
        # The capture point's smallest distance inside the manager's safety polygon on three feet.
        row["capture_point_margin_min_m"] = min(m["min"] for m in margins)
    estimates = [r["estimator_errors"] for r in runs if "estimator_errors" in r]
    if estimates:
        row["estimator_position_error_max_m"] = max(e["position_error_max_m"] for e in estimates)
        row["estimator_velocity_rms_max_m_s"] = max(e["velocity_rms_m_s"] for e in estimates)
        row["estimator_orientation_error_max_deg"] = max(e["orientation_error_max_deg"] for e in estimates)
    doors = [r["door"]["opened_deg"] for r in runs if "door" in r]
    if doors:
        row["door_opened_deg_min"] = min(doors)
    boxes = [r["box"]["moved_m"] for r in runs if "box" in r]
    if boxes:
        row["box_moved_m_min"] = min(boxes)
    if mission in EXPECTED_OBSTACLES:
        expected = EXPECTED_OBSTACLES[mission]
        row["obstacles_correct"] = sum(obstacle_calls(r.get("presses", [])) == expected for r in runs)
    pushes = [r["object_push"]["moved_m"] for r in runs if "object_push" in r]
    if pushes:
        row["object_pushed_m_min"] = min(pushes)
        row["stance_foot_slide_m_max"] = max(
            max(r["object_push"]["stance_feet_slide_m"].values(), default=0.0) for r in runs if "object_push" in r
        )
    return row


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--missions", default=",".join(shipped_missions()))
    parser.add_argument("--noise-seeds", default="1,2,3,4,5", help="seeds run with sensor noise ('' for none)")
    parser.add_argument("--engine", choices=ENGINES, default="ray", help="ray (every core) or serial")
    parser.add_argument("--out", default="benchmarks/results/missions.json")
    parser.add_argument(
        "--study-results",
        default=None,
        help="summarise the rows a run of studies/missions_benchmark.yaml wrote to this folder instead of running",
    )
    args = parser.parse_args()
    missions = [m for m in args.missions.split(",") if m]
    for mission in missions:
        load_mission(mission)
    seeds = [int(s) for s in args.noise_seeds.split(",") if s]
    study = mission_study(missions, seeds)
    results: dict[str, list[dict]] = {m: [] for m in missions}
    if args.study_results:
        wanted = {task.task_id for task in study.tasks}
        rows = [row for row in read_rows(Path(args.study_results)) if row["task_id"] in wanted]
        # Same tasks as the shipped study file: their ids come from the same settings.
        missing = len(wanted) - len(rows)
        if missing:
            print(f"note: {missing} of the {len(wanted)} runs have no row in {args.study_results}")
    else:
        with tempfile.TemporaryDirectory() as folder:
            rows = run_study(study, Path(folder), make_engine(args.engine)).rows
    for row in sorted(rows, key=lambda r: r["index"]):
        result = result_of(row)
        noise = row["factor.noise"]
        result["seed"], result["noise"] = noise["random_seed"], noise["sensor_noise.enabled"]
        results[row["factor.mission"]].append(result)
    summary = {m: summarise(m, runs) for m, runs in results.items() if runs}
    print(
        f"\n{'mission':<24} {'ok':>5} {'err med':>8} {'err max':>8} {'drift':>7} {'RTF':>5} "
        f"{'est pos':>8} {'est vel':>8} {'est ori':>8} {'cp marg':>8}  extra"
    )
    for mission, row in summary.items():
        extra = ""
        if "door_opened_deg_min" in row:
            extra += f"door +{row['door_opened_deg_min']:.0f} deg (min) "
        if "box_moved_m_min" in row:
            extra += f"box +{100 * row['box_moved_m_min']:.1f} cm (min) "
        if "obstacles_correct" in row:
            extra += f"obstacles right {row['obstacles_correct']}/{row['runs']} "
        if "object_pushed_m_min" in row:
            extra += (
                f"pushed +{100 * row['object_pushed_m_min']:.1f} cm (min), stance feet "
                f"{1000 * row['stance_foot_slide_m_max']:.1f} mm (max)"
            )

        def mm(value):
            return f"{1000 * value:8.1f}" if value is not None else "       -"

        def deg(value):
            return f"{value:8.2f}" if value is not None else "       -"

        print(
            f"{mission:<24} {row['succeeded']:>2}/{row['runs']:<2} {mm(row['foot_error_median_m'])} "
            f"{mm(row['foot_error_max_m'])} {mm(row['max_base_drift_m'])} "
            f"{row['real_time_factor_median']:5.2f} {mm(row.get('estimator_position_error_max_m'))} "
            f"{mm(row.get('estimator_velocity_rms_max_m_s'))} {deg(row.get('estimator_orientation_error_max_deg'))}"
            f" {mm(row.get('capture_point_margin_min_m'))}  {extra}"
        )
    all_errors = [row["error"] for runs in results.values() for r in runs for row in r["foot_errors_m"]]
    if all_errors:
        print(
            f"\nfoot error over all reach phases: median {1000 * statistics.median(all_errors):.1f} mm, "
            f"max {1000 * max(all_errors):.1f} mm ({len(all_errors)} reaches)"
        )
    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(json.dumps(stamped({"summary": summary, "runs": results}), indent=2, default=str))
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
