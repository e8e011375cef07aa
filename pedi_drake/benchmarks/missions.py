"""Every shipped mission in simulation: seed 0 without noise, and more seeds with sensor noise.

    python -m pedi_drake.benchmarks.missions [--missions a,b] [--noise-seeds 1,2,3,4,5] [--jobs 2]
                                           [--out benchmarks/results/missions.json]

Prints one row per mission (successes, foot errors, trunk drift, real-time factor without any
visualisation, the estimator's largest errors against the simulated truth, and the
mission-specific checks: door opening, box push, obstacle classification) and writes every
run's result.json content to the JSON file. Runs are independent processes (`--jobs`).
"""

import argparse
import json
import statistics
import tempfile
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

from pedi_drake.mission.spec import load_mission, shipped_missions
from pedi_drake.run import run
from pedi_drake.scenario import load_scenario

# The obstacle each press of obstacle_sensing touches, from the mission's scene.
EXPECTED_OBSTACLE_CLASS = {"press_a": "rigid", "press_b": "soft"}


def run_one(mission: str, seed: int, noise: bool) -> dict:
    """One run of `mission`; returns its result dictionary (result.json)."""
    text = (
        f"{{mission: {mission}, controller: whole_body, random_seed: {seed}, simulation_duration: 60.0, "
        f"sensor_noise: {{enabled: {'true' if noise else 'false'}}}}}"
    )
    scenario = load_scenario(scenario_text=text)
    with tempfile.TemporaryDirectory() as out:
        return run(scenario=scenario, name=mission, out_dir=Path(out), quiet=True, replay=False)


def _run_job(job) -> tuple[str, int, bool, dict]:
    mission, seed, noise = job
    return mission, seed, noise, run_one(mission, seed, noise)


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
    presses = [p for r in runs for p in r.get("presses", [])]
    if presses:
        row["obstacles_correct"] = sum(
            all(p["classified_as"] == EXPECTED_OBSTACLE_CLASS.get(p["phase"]) for p in r["presses"])
            and len(r["presses"]) == len(EXPECTED_OBSTACLE_CLASS)
            for r in runs
        )
    return row


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--missions", default=",".join(shipped_missions()))
    parser.add_argument("--noise-seeds", default="1,2,3,4,5", help="seeds run with sensor noise ('' for none)")
    parser.add_argument("--jobs", type=int, default=2)
    parser.add_argument("--out", default="benchmarks/results/missions.json")
    args = parser.parse_args()
    missions = [m for m in args.missions.split(",") if m]
    for mission in missions:
        load_mission(mission)
    seeds = [int(s) for s in args.noise_seeds.split(",") if s]
    jobs = [(m, 0, False) for m in missions] + [(m, s, True) for m in missions for s in seeds]
    results: dict[str, list[dict]] = {m: [] for m in missions}
    with ProcessPoolExecutor(max_workers=args.jobs) as pool:
        for mission, seed, noise, result in pool.map(_run_job, jobs):
            result["seed"], result["noise"] = seed, noise
            results[mission].append(result)
            status = "ok" if result["success"] else f"FAILED ({result['reason'][:80]})"
            print(f"  {mission:<24} seed {seed} noise {noise!s:<5} {status}", flush=True)
    summary = {m: summarise(m, runs) for m, runs in results.items()}
    print(
        f"\n{'mission':<24} {'ok':>5} {'err med':>8} {'err max':>8} {'drift':>7} {'RTF':>5} "
        f"{'est pos':>8} {'est vel':>8} {'est ori':>8}  extra"
    )
    for mission, row in summary.items():
        extra = ""
        if "door_opened_deg_min" in row:
            extra += f"door +{row['door_opened_deg_min']:.0f} deg (min) "
        if "box_moved_m_min" in row:
            extra += f"box +{100 * row['box_moved_m_min']:.1f} cm (min) "
        if "obstacles_correct" in row:
            extra += f"obstacles right {row['obstacles_correct']}/{row['runs']}"

        def mm(value):
            return f"{1000 * value:8.1f}" if value is not None else "       -"

        def deg(value):
            return f"{value:8.2f}" if value is not None else "       -"

        print(
            f"{mission:<24} {row['succeeded']:>2}/{row['runs']:<2} {mm(row['foot_error_median_m'])} "
            f"{mm(row['foot_error_max_m'])} {mm(row['max_base_drift_m'])} "
            f"{row['real_time_factor_median']:5.2f} {mm(row.get('estimator_position_error_max_m'))} "
            f"{mm(row.get('estimator_velocity_rms_max_m_s'))} {deg(row.get('estimator_orientation_error_max_deg'))}"
            f"  {extra}"
        )
    all_errors = [row["error"] for runs in results.values() for r in runs for row in r["foot_errors_m"]]
    if all_errors:
        print(
            f"\nfoot error over all reach phases: median {1000 * statistics.median(all_errors):.1f} mm, "
            f"max {1000 * max(all_errors):.1f} mm ({len(all_errors)} reaches)"
        )
    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(json.dumps({"summary": summary, "runs": results}, indent=2, default=str))
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
