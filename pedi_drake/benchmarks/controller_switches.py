"""Runtime controller switching under a random operator: the HQP and paper 002's controller handed
over again and again while the FR foot is lifted.

    python -m pedi_drake.benchmarks.controller_switches [--seeds 0 1 2 3 4 5] [--switches 20]
        [--out benchmarks/results/controller_switches.json]

Each run is the shipped scenario controller_switching (missions/operator/switch_controllers.yaml:
its own four switches, two of them with the foot lifted) with a scripted operator on an
in-process LCM bus that asks for the other controller `--switches` times, at seeded random
moments of the mission's 12 s trunk circle, while the FR foot holds its world pose in the air:
the gaps between requests are drawn from 30 ms to 0.5 s, so some requests reverse a hand-over
still under way. Seed 0 runs without sensor noise, the others with it.

Judged from the simulation's ground truth: the mission's success (which includes that no
hand-over stepped a joint target beyond the safety filter's rate limit), no fall, and, over the
circle, how far the lifted foot strayed from where it held (the controllers hand over a foot
held in the air). Reported per run: the switches made, the largest joint-target and
applied-torque steps in a hand-over and elsewhere.
"""

import argparse
import json
from pathlib import Path

import numpy as np

from pedi_drake import robot
from pedi_drake.benchmarks.machine import stamped
from pedi_drake.evaluation.judge import judge_run
from pedi_drake.evaluation.mission_results import foot_positions_W
from pedi_drake.operator.command import CONTROLLER_PROJECTED_IMPEDANCE, CONTROLLER_WHOLE_BODY
from pedi_drake.operator.scripted_operator import ScriptedOperator, ScriptStep
from pedi_drake.run import RunRecord, simulate_with_operator
from pedi_drake.scenario import load_scenario

SCENARIO = "controller_switching"
END = 30.0  # [s]: the mission ends at about 28 s
# The requests start in the trunk circle (which runs from about 9 s to 21 s) [s] ...
FIRST_REQUEST = 10.0
# ... and follow each other after random gaps in this range [s]: the shortest is three of the
# operator input's 10 ms polls, so that every request is seen; gaps under the 0.1 s blend reverse
# a hand-over under way. Twenty gaps take at most 10 s, inside the circle.
GAPS = (0.03, 0.5)
CIRCLE_PHASE = "trunk_circle"
LIFTED_LEG = "FR"


def request_times(seed: int, count: int) -> np.ndarray:
    """`count` random request times [s] from FIRST_REQUEST on, GAPS apart, drawn from `seed`."""
    rng = np.random.default_rng(1000 + seed)
    return FIRST_REQUEST + np.cumsum(np.concatenate([[0.0], rng.uniform(*GAPS, count - 1)]))


def switch_script(times: np.ndarray) -> list[ScriptStep]:
    """The operator's steps: at each time, a request for the controller the previous one did not
    name (the mission hands the circle to the HQP, so the first asks for paper 002's)."""
    codes = (CONTROLLER_PROJECTED_IMPEDANCE, CONTROLLER_WHOLE_BODY)
    return [ScriptStep(0.0)] + [ScriptStep(float(t), controller_request=codes[k % 2]) for k, t in enumerate(times)]


def lifted_foot_stray(record: RunRecord, result: dict) -> float | None:
    """The largest true distance [m] of the lifted foot from its position at the circle's start,
    over the circle; None if the circle did not run."""
    phase = next((row for row in result["phases"] if row["name"] == CIRCLE_PHASE), None)
    if phase is None or phase["t_start"] is None or phase["t_end"] is None:
        return None
    plant = record.built.diagram.GetSubsystemByName("station").GetSubsystemByName("plant")
    states = record.logs["sim.plant_state"]
    window = np.flatnonzero((states.times >= phase["t_start"]) & (states.times <= phase["t_end"]))
    feet = foot_positions_W(plant, states.data, window)[:, robot.LEG_NAMES.index(LIFTED_LEG)]
    return float(np.max(np.linalg.norm(feet - feet[0], axis=1)))


def one_run(seed: int, switches: int) -> dict:
    """The judged run of `seed` with `switches` random operator requests."""
    noise = "" if seed == 0 else f", random_seed: {seed}, sensor_noise: {{enabled: true}}"
    scenario = load_scenario(
        scenario_name=SCENARIO,
        scenario_text=f"{{simulation_duration: {END}, operator: {{source: lcm}}{noise}}}",
    )
    times = request_times(seed, switches)
    record = simulate_with_operator(
        scenario, lambda lcm: ScriptedOperator(lcm, switch_script(times)), f"switches seed {seed}"
    )
    result = judge_run(record)
    summary = result["controller_switches"]
    return {
        "seed": seed,
        "success": bool(result["success"]),
        "reason": result["reason"],
        "fell": bool(result["fell"]),
        "operator_requests": len(times),
        "switches": summary["switches"],
        "max_target_step_rad": summary["max_target_step_rad"],
        "target_step_limit_rad": summary["target_step_limit_rad"],
        "max_target_step_elsewhere_rad": summary["max_target_step_elsewhere_rad"],
        "max_torque_step_nm": summary["max_torque_step_nm"],
        "max_torque_step_elsewhere_nm": summary["max_torque_step_elsewhere_nm"],
        "lifted_foot_stray_m": lifted_foot_stray(record, result),
        "foot_errors_m": result["foot_errors_m"],
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--seeds", type=int, nargs="+", default=[0, 1, 2, 3, 4, 5])
    parser.add_argument("--switches", type=int, default=20)
    parser.add_argument("--out", default="benchmarks/results/controller_switches.json")
    args = parser.parse_args()
    rows = []
    print(
        f"{'seed':>4}{'switches':>10}{'target step [rad]':>19}{'limit':>8}{'torque step [N m]':>19}"
        f"{'elsewhere':>11}{'foot stray [mm]':>17}  ok"
    )
    for seed in args.seeds:
        row = one_run(seed, args.switches)
        rows.append(row)
        stray = row["lifted_foot_stray_m"]
        print(
            f"{seed:>4}{row['switches']:>10}{row['max_target_step_rad']:>19.4f}{row['target_step_limit_rad']:>8.3f}"
            f"{row['max_torque_step_nm']:>19.2f}{row['max_torque_step_elsewhere_nm']:>11.2f}"
            f"{'-' if stray is None else f'{1000 * stray:.1f}':>17}  "
            f"{'yes' if row['success'] and not row['fell'] else 'NO: ' + row['reason']}",
            flush=True,
        )
    summary = {
        "runs": len(rows),
        "succeeded": sum(row["success"] and not row["fell"] for row in rows),
        "switches_per_run_min": min(row["switches"] for row in rows),
        "max_target_step_rad": max(row["max_target_step_rad"] for row in rows),
        "target_step_limit_rad": rows[0]["target_step_limit_rad"],
        "max_torque_step_nm": max(row["max_torque_step_nm"] for row in rows),
        "max_lifted_foot_stray_m": max((row["lifted_foot_stray_m"] or 0.0) for row in rows),
    }
    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(json.dumps(stamped({"summary": summary, "runs": rows}), indent=2))
    print(
        f"{summary['succeeded']} of {summary['runs']} runs; at least {summary['switches_per_run_min']} switches a run; "
        f"largest joint-target step in a hand-over {summary['max_target_step_rad']:.4f} rad "
        f"(limit {summary['target_step_limit_rad']:.3f}); largest lifted-foot stray "
        f"{1000 * summary['max_lifted_foot_stray_m']:.1f} mm"
    )
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
