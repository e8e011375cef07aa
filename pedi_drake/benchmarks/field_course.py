"""Paper 002's field course (missions/terrain/field_course.yaml) in simulation over seeds, each
stage judged by physics.

    python -m pedi_drake.benchmarks.field_course [--seeds 0 1 2 3 4 5] [--workers N]
        [--out benchmarks/results/field_course.json]

The course runs on the HQP with the Kalman estimate; seed 0 without sensor noise, the others with
it. The E-stop press comes from an operator program that finds the button's cap by touch
(pedi_drake.operator.button_search) on an in-process LCM bus, started when the robot offers it the
FR foot, as `python -m pedi_drake.apps.teleop_lcm --search_button 180` does over a real bus.

Prints one row per run: the box's slide after the prong strike, each walk's true distance from its
goal (the climb's goal is on the platform), the largest stance foot slip on the slippery bridge,
the plunger's travel and the true force on it, falls, and the course's simulated time (to the
mission's end) beside its wall time; writes every row and the run's result.json figures to the
JSON file. Runs go in parallel, one per worker process.
"""

import argparse
import concurrent.futures
import json
import math
import os
from pathlib import Path

from pedi_drake.benchmarks.machine import stamped
from pedi_drake.evaluation.judge import judge_run
from pedi_drake.mission.spec import Walk, load_mission
from pedi_drake.operator.button_search import ButtonSearch
from pedi_drake.operator.scripted_operator import ScriptedOperator
from pedi_drake.run import simulate_with_operator
from pedi_drake.scenario import load_scenario

MISSION = "terrain/field_course"
HEADING = math.pi  # [rad] the robot's heading at the button, as the operator sees it
# [s] of simulated time at most: the course takes about 140 s.
LONGEST = 200.0
# The walks of the course, in order, by phase name.
WALKS = ("trot_to_box", "to_the_slope", "climb", "turn", "descend", "cross_the_bridge")


def run_course(seed: int) -> dict:
    """judge_run's result.json of the field course at `seed` (0: no sensor noise), the operator
    program on an in-process bus."""
    noise = "" if seed == 0 else f", random_seed: {seed}, sensor_noise: {{enabled: true}}"
    text = f"{{mission: {MISSION}, simulation_duration: {LONGEST}, operator: {{source: lcm}}{noise}}}"
    scenario = load_scenario(scenario_text=text)

    def operator(lcm):
        channel = scenario.operator.feedback_channel
        return ScriptedOperator(lcm, program=ButtonSearch(HEADING), start_on_leg="FR", feedback_channel=channel)

    record = simulate_with_operator(scenario, operator, f"field_course seed {seed}", end_with_mission=True)
    return judge_run(record)


def stage_row(seed: int, result: dict) -> dict:
    """The course's figures of one run, stage by stage (see the module docstring)."""
    walks = {row["phase"]: row for row in result.get("walks", [])}
    tolerances = {phase.name: phase.tolerance for phase in load_mission(MISSION).phases if isinstance(phase, Walk)}
    within = all(name in walks and walks[name]["goal_error_m"] <= tolerance for name, tolerance in tolerances.items())
    push = result.get("object_push") or {}
    press = result.get("button_press") or {}
    bridge = walks.get("cross_the_bridge", {})
    ends = [row["t_end"] for row in result["phases"] if row["t_end"] is not None]
    return {
        "seed": seed,
        "success": bool(result["success"]),
        "reason": result["reason"],
        "fell": bool(result["fell"]),
        "box_moved_m": push.get("moved_m"),
        "walk_goal_errors_m": {name: walks[name]["goal_error_m"] for name in WALKS if name in walks},
        "walk_goal_yaw_errors_rad": {name: walks[name]["goal_yaw_error_rad"] for name in WALKS if name in walks},
        "bridge_stance_slip_max_m": max(bridge["max_stance_slip_m"].values()) if bridge else None,
        "stance_slip_max_m": max((max(row["max_stance_slip_m"].values()) for row in walks.values()), default=None),
        "estimate_drift_max_m": max((row["estimate_drift_m"] for row in walks.values()), default=None),
        "on_the_platform": "climb" in walks and walks["climb"]["goal_error_m"] <= tolerances["climb"],
        "walks_within_tolerance": within,
        "pressed": bool(press.get("pressed", False)),
        "plunger_travel_max_m": press.get("max_travel_m"),
        "button_true_force_max_n": press.get("max_force_n"),
        "course_time_s": max(ends, default=0.0),
        "wall_time_s": result["wall_time_s"],
    }


def _cm(value) -> str:
    return "    -" if value is None else f"{100 * value:5.1f}"


def print_row(row: dict) -> None:
    errors = row["walk_goal_errors_m"]
    walks = " ".join(_cm(errors.get(name)) for name in WALKS)
    travel = "-" if row["plunger_travel_max_m"] is None else f"{1000 * row['plunger_travel_max_m']:.1f}"
    force = "-" if row["button_true_force_max_n"] is None else f"{row['button_true_force_max_n']:.1f}"
    print(
        f"{row['seed']:>4}  {'yes' if row['success'] else 'NO':<4}{_cm(row['box_moved_m'])}  {walks}  "
        f"{_cm(row['bridge_stance_slip_max_m'])}  {travel:>6} {force:>6}  {'yes' if row['fell'] else 'no':<5}"
        f"{row['course_time_s']:7.1f}{row['wall_time_s']:7.1f}" + ("" if row["success"] else f"  {row['reason']}"),
        flush=True,
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--seeds", type=int, nargs="+", default=[0, 1, 2, 3, 4, 5])
    parser.add_argument("--workers", type=int, default=os.cpu_count() or 1)
    parser.add_argument("--out", default="benchmarks/results/field_course.json")
    args = parser.parse_args()
    print(
        "seed  ok  box [cm]  walks' goal error [cm]: "
        + " ".join(WALKS)
        + "  bridge slip [cm]  plunger [mm] force [N]  fell  course [s] wall [s]"
    )
    rows = []
    with concurrent.futures.ProcessPoolExecutor(max_workers=args.workers) as pool:
        for seed, result in zip(args.seeds, pool.map(run_course, args.seeds), strict=True):
            rows.append(stage_row(seed, result))
            print_row(rows[-1])
    summary = {
        "runs": len(rows),
        "succeeded": sum(row["success"] for row in rows),
        "fell": sum(row["fell"] for row in rows),
        "box_moved_min_m": min((row["box_moved_m"] or 0.0) for row in rows),
        "walk_goal_error_max_m": max(max(row["walk_goal_errors_m"].values(), default=0.0) for row in rows),
        "bridge_stance_slip_max_m": max((row["bridge_stance_slip_max_m"] or 0.0) for row in rows),
        "pressed": sum(row["pressed"] for row in rows),
        "button_true_force_max_n": max((row["button_true_force_max_n"] or 0.0) for row in rows),
        "course_time_max_s": max(row["course_time_s"] for row in rows),
        # Each stage by physics, in how many runs it happened.
        "box_pushed_20cm": sum((row["box_moved_m"] or 0.0) >= 0.20 for row in rows),
        "on_the_platform": sum(row["on_the_platform"] for row in rows),
        "walks_within_tolerance": sum(row["walks_within_tolerance"] for row in rows),
        "wall_time_median_s": sorted(row["wall_time_s"] for row in rows)[len(rows) // 2],
    }
    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(json.dumps(stamped({"summary": summary, "runs": rows}), indent=2))
    print(
        f"stages by physics over {summary['runs']} runs: box pushed 20 cm {summary['box_pushed_20cm']}, on the "
        f"platform {summary['on_the_platform']}, every walk within its tolerance {summary['walks_within_tolerance']}, "
        f"E-stop pressed {summary['pressed']}, fell {summary['fell']}"
    )
    print(
        f"{summary['succeeded']} of {summary['runs']} courses; box moved at least "
        f"{100 * summary['box_moved_min_m']:.1f} cm; walks within {100 * summary['walk_goal_error_max_m']:.1f} cm "
        f"of their goals; {summary['pressed']} presses; longest course {summary['course_time_max_s']:.1f} s"
    )
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
