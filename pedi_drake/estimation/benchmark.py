"""Kalman estimator accuracy over whole missions in simulation, with sensor noise, against the truth.

    python -m pedi_drake.estimation.benchmark [--missions hit_target_front,open_door] [--seeds 1,2]
                                              [--jobs 2] [--out benchmarks/results/estimator.json]

Each run is a shipped mission with `estimator: kalman` (the controller and the mission manager
act on the estimate) and `sensor_noise: {enabled: true}`; the logged estimate is compared with
the logged plant state afterwards. Prints one row per run (trunk position error max and final,
velocity RMS error, orientation error max, mission success, true reach errors) and the floors.
"""

import argparse
import json
import tempfile
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

from pedi_drake.mission.spec import load_mission, shipped_missions

# Floors of the estimator (issue 7).
POSITION_DRIFT_FLOOR_M = 0.02
VELOCITY_RMS_FLOOR_M_S = 0.05
ORIENTATION_FLOOR_DEG = 1.0


def run_one(mission: str, seed: int) -> dict:
    """One noisy mission on the Kalman estimate; its result with an `estimator_errors` entry."""
    from pedi_drake import robot
    from pedi_drake.diagram import apply_mission
    from pedi_drake.estimation.accuracy import estimate_errors
    from pedi_drake.run_logs import read_run_logs
    from pedi_drake.simulation_run import run
    from pedi_drake.station.scenario import load_scenario
    from pedi_drake.station.sim_station import MakeSimulationStation

    text = (
        f"{{mission: {mission}, controller: whole_body, estimator: kalman, random_seed: {seed}, "
        "simulation_duration: 60.0, sensor_noise: {enabled: true}}"
    )
    scenario = load_scenario(scenario_text=text)
    with tempfile.TemporaryDirectory() as out:
        result = run(scenario=scenario, name=mission, out_dir=Path(out), quiet=True)
        logs = read_run_logs(out)
    plant = MakeSimulationStation(apply_mission(scenario, load_mission(mission))).GetSubsystemByName("plant")
    plant_map = robot.Go1PlantMap.from_plant(plant)
    result["estimator_errors"] = estimate_errors(
        logs["base_state"], logs["sim.plant_state"], plant_map, plant.num_positions()
    )
    result["seed"] = seed
    return result


def _job(args) -> tuple[str, int, dict]:
    mission, seed = args
    return mission, seed, run_one(mission, seed)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--missions", default=",".join(shipped_missions()))
    parser.add_argument("--seeds", default="1")
    parser.add_argument("--jobs", type=int, default=2)
    parser.add_argument("--out", default="benchmarks/results/estimator.json")
    args = parser.parse_args()
    missions = [m for m in args.missions.split(",") if m]
    for mission in missions:
        load_mission(mission)
    jobs = [(m, int(s)) for m in missions for s in args.seeds.split(",") if s]
    rows = []
    print(f"{'mission':<24}{'seed':>5}{'pos max mm':>11}{'pos end mm':>11}{'vel rms mm/s':>13}{'ori max deg':>12}  ok")
    with ProcessPoolExecutor(max_workers=args.jobs) as pool:
        for mission, seed, result in pool.map(_job, jobs):
            e = result["estimator_errors"]
            reach = ", ".join(f"{1000 * r['error']:.1f}" for r in result["foot_errors_m"])
            print(
                f"{mission:<24}{seed:>5}{1000 * e['position_error_max_m']:11.1f}"
                f"{1000 * e['position_error_final_m']:11.1f}"
                f"{1000 * e['velocity_rms_m_s']:13.1f}{e['orientation_error_max_deg']:12.3f}  "
                f"{'yes' if result['success'] else 'NO: ' + result['reason'][:60]}  reach mm: {reach}",
                flush=True,
            )
            rows.append(
                {
                    "mission": mission,
                    "seed": seed,
                    **e,
                    "success": result["success"],
                    "reason": result["reason"],
                    "foot_errors_m": result["foot_errors_m"],
                }
            )
    floors = {
        "position_drift_below_2cm": all(r["position_error_max_m"] < POSITION_DRIFT_FLOOR_M for r in rows),
        "velocity_rms_below_5cm_s": all(r["velocity_rms_m_s"] < VELOCITY_RMS_FLOOR_M_S for r in rows),
        "orientation_below_1deg": all(r["orientation_error_max_deg"] < ORIENTATION_FLOOR_DEG for r in rows),
        "missions_succeed": all(r["success"] for r in rows),
    }
    print("Floors:", json.dumps(floors))
    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(json.dumps({"rows": rows, "floors": floors}, indent=2))
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
