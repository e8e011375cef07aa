"""Paper 002's E-stop press (IV-C f) on both controllers, each bounding the teleoperated foot by
its own force estimate, over seeds.

    python -m pedi_drake.benchmarks.estop_button [--seeds 0 1 2 3 4 5]
        [--setups whole_body projected_impedance] [--out benchmarks/results/estop_button.json]

A scripted operator (missions/operator/press_estop_button.ops, on an in-process LCM bus) raises
the FR foot over the button's cap, brings it down until the plunger trips and takes it back. The
judge reads the plunger's travel and the foot's contact force from the simulation's ground
truth: the plunger must pass its trip travel with the true force under the teleop phase's bound
(15 N). Setups: `whole_body` (the HQP, the joint-torque estimate; the mission's default) and
`projected_impedance` (paper 002's controller with its Eq. 11 estimate: the shipped scenario
estop_paper002). Seed 0 runs without sensor noise, the others with it.
"""

import argparse
import json
from pathlib import Path

from pedi_drake.apps.teleop_lcm import parse_script
from pedi_drake.benchmarks.machine import stamped
from pedi_drake.evaluation.judge import judge_run
from pedi_drake.operator.command import FRAME_WORLD
from pedi_drake.operator.scripted_operator import ScriptedOperator
from pedi_drake.resources import missions_dir
from pedi_drake.run import simulate_with_operator
from pedi_drake.scenario import load_scenario

MISSION = "operator/press_estop_button"
SCRIPT = missions_dir() / "operator" / "press_estop_button.ops"
# [s]: the script asks for the autonomous mode at 19.8 s; the leg is back on the ground by about 23 s.
END = 24.5
# Each setup: the shipped scenario it runs (its controller and force estimate).
SETUPS = {"whole_body": "default", "projected_impedance": "estop_paper002"}


def run_scripted_press(scenario_name: str, scenario_text: str, script: str, name: str) -> dict:
    """judge_run's result.json of the E-stop mission on the shipped scenario `scenario_name` (with
    `scenario_text` over it), a scripted operator playing `script` over an in-process LCM bus
    until END."""
    text = f"{{mission: {MISSION}, simulation_duration: {END}, operator: {{source: lcm}}{scenario_text}}}"
    scenario = load_scenario(scenario_name=scenario_name, scenario_text=text)
    steps = parse_script(script, name, frame=FRAME_WORLD)
    record = simulate_with_operator(scenario, lambda lcm: ScriptedOperator(lcm, steps, until=steps[-1].start), name)
    return judge_run(record)


def seed_text(seed: int) -> str:
    """The scenario_text tail of `seed`: 0 without sensor noise, any other with it."""
    return "" if seed == 0 else f", random_seed: {seed}, sensor_noise: {{enabled: true}}"


def one_run(setup: str, seed: int) -> dict:
    result = run_scripted_press(SETUPS[setup], seed_text(seed), SCRIPT.read_text(), f"{setup} seed {seed}")
    press = result["button_press"]
    teleop = next(row for row in result["teleop"] if row["phase"] == "teleop")
    return {
        "setup": setup,
        "seed": seed,
        "success": bool(result["success"]),
        "reason": result["reason"],
        "pressed": bool(press["pressed"]),
        "max_travel_m": press["max_travel_m"],
        "max_true_force_n": press["max_force_n"],
        "force_bound_n": press["force_bound_n"],
        "max_estimated_force_n": teleop["max_force_n"],
        "force_bound_activations": teleop["bound_activations"]["force"],
        "fell": bool(result["fell"]),
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--seeds", type=int, nargs="+", default=[0, 1, 2, 3, 4, 5])
    parser.add_argument("--setups", nargs="+", choices=list(SETUPS), default=list(SETUPS))
    parser.add_argument("--out", default="benchmarks/results/estop_button.json")
    args = parser.parse_args()
    rows = []
    print(f"{'setup':<22}{'seed':>5}  {'pressed':<8}{'travel [mm]':>12}{'true [N]':>10}{'estimate [N]':>13}  ok")
    for setup in args.setups:
        for seed in args.seeds:
            row = one_run(setup, seed)
            rows.append(row)
            print(
                f"{setup:<22}{seed:>5}  {'yes' if row['pressed'] else 'no':<8}{1000 * row['max_travel_m']:>12.1f}"
                f"{row['max_true_force_n']:>10.2f}{row['max_estimated_force_n']:>13.2f}  "
                f"{'yes' if row['success'] else 'NO: ' + row['reason']}",
                flush=True,
            )
    summary = {
        setup: {
            "runs": sum(row["setup"] == setup for row in rows),
            "succeeded": sum(row["setup"] == setup and row["success"] for row in rows),
            "max_true_force_n": max((row["max_true_force_n"] for row in rows if row["setup"] == setup), default=None),
        }
        for setup in args.setups
    }
    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(json.dumps(stamped({"summary": summary, "runs": rows}), indent=2))
    for setup, figures in summary.items():
        largest = figures["max_true_force_n"]
        print(f"{setup}: {figures['succeeded']} of {figures['runs']}; largest true force {largest:.2f} N")
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
