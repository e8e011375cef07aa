"""The walking floors: static walks in simulation, seed 0 without noise and more seeds with sensor
noise, on the Kalman estimate, judged by ground truth (pedi_drake.evaluation.walks).

    python -m pedi_drake.benchmarks.walking [--missions walking/walk_forward,...]
        [--controllers whole_body,projected_impedance] [--noise-seeds 1,2,3,4,5]
        [--trot-speeds 0.5,0.6,0.7,0.8] [--engine ray|serial] [--out benchmarks/results/walking.json]

A batch study (mission x controller x noise) on Ray (every core) or serially. `--trot-speeds`
adds a trot of 3 m forward at each commanded speed (missions written for the run), for the
highest speed that holds on every seed. Prints one row per
mission and controller: successes, the largest distance and heading error from the goal at the
end, the slowest walking speed (start to stop, over the trunk's true path) and a walk_velocity's
slowest forward speed over its commanded window, the largest stance
foot slip, the estimate's largest drift against the distance walked and its largest height
error, the slowest real-time factor of the simulation beside the bare plant's
(pedi_drake.benchmarks.station measures that one), and the steps; writes every run's `walks`
rows to the JSON file.
"""

import argparse
import json
import math
import shutil
import statistics
import tempfile
from pathlib import Path

from pedi_drake.batch.engines import ENGINES, make_engine
from pedi_drake.batch.runner import run_study
from pedi_drake.batch.study import study_from_dict
from pedi_drake.benchmarks.machine import stamped
from pedi_drake.benchmarks.missions import result_of
from pedi_drake.mission.spec import load_mission

WALKING_MISSIONS = [
    "walking/walk_forward",
    "walking/walk_backward",
    "walking/walk_sideways",
    "walking/walk_square",
    "walking/walk_then_hit_target",
    "walking/walk_then_open_door",
    "walking/trot_forward",
    "walking/trot_turn",
    "walking/trot_push",
]
TROT_DISTANCE = 3.0  # [m] of each --trot-speeds trot
TROT_AT_SPEED = """description: Trot {distance} m forward at {speed} m/s, then stop on four feet.
contact_ramp_time: 0.02
phases:
  - {{kind: stand_up}}
  - {{kind: walk_velocity, twist: [{speed}, 0.0, 0.0], duration: {duration}, gait: trot}}
"""
# The walk-then-pedipulate missions are judged as their standing versions are: the touch by the
# true contact force (the judge), the door by how far it opened (tests/test_missions.py's floor).
DOOR_OPENED_DEG = 20.0
CONTROLLERS = ["whole_body", "projected_impedance"]


def walking_study(missions: list[str], controllers: list[str], noise_seeds: list[int]):
    """The study of `missions` on each controller at seed 0 without noise and at each of
    `noise_seeds` with noise."""
    noise = [{"random_seed": 0, "sensor_noise.enabled": False}]
    noise += [{"random_seed": seed, "sensor_noise.enabled": True} for seed in noise_seeds]
    return study_from_dict(
        {
            "name": "walking_benchmark",
            "kind": "mission",
            "timeout": 1200,
            "factors": [
                {"name": "mission", "values": missions},
                {"name": "controller", "values": controllers},
                {"name": "noise", "values": noise},
            ],
        },
        "pedi_drake.benchmarks.walking",
    )


def summarise(runs: list[dict]) -> dict:
    """The floors' figures over the runs of one mission on one controller."""
    walks = [walk for run in runs for walk in run.get("walks", [])]

    def largest(key):
        values = [walk[key] for walk in walks if walk.get(key) is not None]
        return max(values) if values else None

    speeds = [walk["walking_speed_m_s"] for walk in walks if walk.get("walking_speed_m_s") is not None]
    # walk_velocity: the forward speed over the commanded window, against the command.
    commanded = [walk["mean_velocity_m_s"][0] for walk in walks if walk.get("mean_velocity_m_s")]
    return {
        "runs": len(runs),
        "succeeded": sum(run["success"] for run in runs),
        "fell": sum(run["fell"] for run in runs),
        "goal_error_max_m": largest("goal_error_m"),
        "goal_yaw_error_max_deg": None
        if largest("goal_yaw_error_rad") is None
        else math.degrees(largest("goal_yaw_error_rad")),
        "walking_speed_min_m_s": min(speeds) if speeds else None,
        "commanded_window_speed_min_m_s": min(commanded) if commanded else None,
        "commanded_window_speed_max_m_s": max(commanded) if commanded else None,
        "stance_slip_max_m": max((max(walk["max_stance_slip_m"].values()) for walk in walks), default=None),
        "estimate_drift_share_max": largest("estimate_drift_share"),
        "estimate_height_error_max_m": largest("estimate_height_error_max_m"),
        "real_time_factor_min": min(run["real_time_factor"] for run in runs),
        "real_time_factor_median": statistics.median(run["real_time_factor"] for run in runs),
        "door_opened_deg_min": min((run["door"]["opened_deg"] for run in runs if "door" in run), default=None),
        "steps_median": statistics.median(sum(walk["steps"] or 0 for walk in run.get("walks", [])) for run in runs),
        "failures": [run["reason"] for run in runs if not run["success"]],
    }


def measure(missions: list[str], controllers: list[str], seeds: list[int], engine: str) -> dict[str, list[dict]]:
    """Runs `walking_study` on `engine`; every run's result, by "<mission> <controller>"."""
    for mission in missions:
        load_mission(mission)
    study = walking_study(missions, controllers, seeds)
    with tempfile.TemporaryDirectory() as folder:
        rows = run_study(study, Path(folder), make_engine(engine)).rows
    results: dict[str, list[dict]] = {}
    for row in sorted(rows, key=lambda r: r["index"]):
        result = result_of(row)
        noise = row["factor.noise"]
        result["seed"], result["noise"] = noise["random_seed"], noise["sensor_noise.enabled"]
        mission = Path(row["factor.mission"]).stem if row["factor.mission"].endswith(".yaml") else row["factor.mission"]
        results.setdefault(f"{mission} {row['factor.controller']}", []).append(result)
    return results


def print_table(summary: dict[str, dict]) -> None:
    """One row per mission and controller of `summarise`'s figures (see the module docstring)."""

    def cm(value):
        return f"{100 * value:7.2f}" if value is not None else "      -"

    def number(value, digits=2):
        return f"{value:7.{digits}f}" if value is not None else "      -"

    print(
        f"\n{'mission controller':<46} {'ok':>5} {'goal cm':>7} {'yaw deg':>7} {'v m/s':>7} {'v cmd':>7} "
        f"{'slip cm':>7} "
        f"{'drift %':>7} {'z cm':>7} {'RTF min':>7} {'steps':>6}"
    )
    for key, row in summary.items():
        drift = None if row["estimate_drift_share_max"] is None else 100 * row["estimate_drift_share_max"]
        print(
            f"{key:<46} {row['succeeded']:>2}/{row['runs']:<2} {cm(row['goal_error_max_m'])} "
            f"{number(row['goal_yaw_error_max_deg'])} {number(row['walking_speed_min_m_s'], 3)} "
            f"{number(row['commanded_window_speed_min_m_s'], 3)} "
            f"{cm(row['stance_slip_max_m'])} {number(drift)} {cm(row['estimate_height_error_max_m'])} "
            f"{number(row['real_time_factor_min'])} {row['steps_median']:>6.0f}"
        )
        if row["door_opened_deg_min"] is not None:
            print(f"    door opened {row['door_opened_deg_min']:.0f} deg at least (floor {DOOR_OPENED_DEG:.0f})")
        for reason in row["failures"]:
            print(f"    failed: {reason}")


def write_results(out: Path, results: dict[str, list[dict]], summary: dict[str, dict]) -> None:
    """Writes `summary` and every run's walking rows to the JSON file `out`."""
    out.parent.mkdir(parents=True, exist_ok=True)
    runs = {
        key: [
            {
                k: r.get(k)
                for k in ("seed", "noise", "success", "reason", "fell", "real_time_factor", "walks", "touches", "door")
            }
            for r in rs
        ]
        for key, rs in results.items()
    }
    out.write_text(json.dumps(stamped({"summary": summary, "runs": runs}), indent=2, default=str))
    print(f"wrote {out}")


def report(missions: list[str], controllers: list[str], seeds: list[int], engine: str, out: Path) -> None:
    """Runs the study (`measure`), prints its table and writes it to `out`."""
    results = measure(missions, controllers, seeds, engine)
    summary = {key: summarise(runs) for key, runs in results.items()}
    print_table(summary)
    write_results(out, results, summary)


def seeds_of(text: str) -> list[int]:
    """The noise seeds of a comma-separated `--noise-seeds`."""
    return [int(s) for s in text.split(",") if s]


def study_parser(doc: str, missions: list[str], controllers: list[str], out: str) -> argparse.ArgumentParser:
    """The command line of a walking study: --missions, --controllers, --noise-seeds, --engine and
    --out, with these defaults."""
    parser = argparse.ArgumentParser(description=doc, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--missions", default=",".join(missions))
    parser.add_argument("--controllers", default=",".join(controllers))
    parser.add_argument("--noise-seeds", default="1,2,3,4,5", help="seeds run with sensor noise ('' for none)")
    parser.add_argument("--engine", choices=ENGINES, default="ray", help="ray (every core) or serial")
    parser.add_argument("--out", default=out)
    return parser


def main() -> None:
    parser = study_parser(__doc__, WALKING_MISSIONS, CONTROLLERS, "benchmarks/results/walking.json")
    parser.add_argument("--trot-speeds", default="", help="commanded speeds of extra 3 m trots [m/s]")
    args = parser.parse_args()
    missions = [m for m in args.missions.split(",") if m]
    written = Path(tempfile.mkdtemp(prefix="walking_benchmark_"))
    for speed in [float(v) for v in args.trot_speeds.split(",") if v]:
        path = written / f"trot_at_{speed:.2f}.yaml"
        path.write_text(TROT_AT_SPEED.format(distance=TROT_DISTANCE, speed=speed, duration=TROT_DISTANCE / speed))
        missions.append(str(path))
    controllers = [c for c in args.controllers.split(",") if c]
    try:
        report(missions, controllers, seeds_of(args.noise_seeds), args.engine, Path(args.out))
    finally:
        shutil.rmtree(written)


if __name__ == "__main__":
    main()
