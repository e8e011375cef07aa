"""Runs a pedi_drake mission (or scenario) in simulation, headless by default, and writes its results.

Writes to --out (default out/<mission or scenario>/): result.json (docs/results.md),
replay.html (a self-contained Meshcat replay: open it in a browser) and PNG plots. Exit code 0
on success, 1 on failure (the reason is printed), 2 on bad input.

Examples:
    python run_sim.py                                   # the default mission, hit_target_front
    python run_sim.py --mission open_door --out out/door
    python run_sim.py --mission my_mission.yaml --meshcat
    python run_sim.py --scenario_name stand --out out/stand
    python run_sim.py --scenario_text "{sensor_noise: {enabled: true}, random_seed: 3}"
    python run_sim.py --hardware --mission hit_target_front   # over LCM: a Go1, or the simulator
        # bridge started first in another terminal:
        #   python -m pedi_drake.apps.sim_bridge --mission hit_target_front
"""

import argparse
import sys
from pathlib import Path

from pydrake.geometry import Meshcat

from pedi_drake.exceptions import ConfigError, LcmTimeout
from pedi_drake.mission.spec import load_mission
from pedi_drake.run import run
from pedi_drake.scenario import MISSION_CONTROLLERS, default_scenario_file, load_scenario


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument(
        "--mission",
        default=None,
        help="Mission name (missions/) or YAML file (controller: whole_body unless the scenario picks one).",
    )
    parser.add_argument("--scenario_file", default=str(default_scenario_file()), help="YAML file of named scenarios.")
    parser.add_argument("--scenario_name", default="default", help="Scenario to run from --scenario_file.")
    parser.add_argument("--scenario_text", default="{}", help="YAML mapping merged onto the scenario.")
    parser.add_argument("--out", default=None, help="Output folder (default: out/<mission or scenario>).")
    parser.add_argument(
        "--duration",
        type=float,
        default=None,
        help="Simulated duration [s] (overrides the scenario; by default a mission gets room for "
        "every phase to reach its timeout, and the run ends when the mission does).",
    )
    parser.add_argument("--meshcat", action="store_true", help="Serve a live Meshcat view (prints its URL).")
    parser.add_argument(
        "--hardware",
        action="store_true",
        help="Drive the Go1 over LCM (the scenario's bus 'go1') in real time instead of simulating it.",
    )
    args = parser.parse_args()
    try:
        scenario = load_scenario(
            filename=args.scenario_file, scenario_name=args.scenario_name, scenario_text=args.scenario_text
        )
        mission = None
        if args.mission is not None:
            mission = load_mission(args.mission)  # validate now: bad input exits 2 before anything runs
            scenario.mission = args.mission
            if scenario.controller not in MISSION_CONTROLLERS:
                scenario.controller = "whole_body"
        elif scenario.mission:
            mission = load_mission(scenario.mission)
        if mission is not None and args.duration is None:
            # Room for every phase to use its timeout: the run stops as soon as the mission is over.
            scenario.simulation_duration = max(scenario.simulation_duration, mission.longest_duration())
        if args.duration is not None:
            if not args.duration > 0:
                raise ConfigError(f"--duration: must be > 0 s, got {args.duration}")
            scenario.simulation_duration = args.duration
        if args.hardware and scenario.estimator == "ground_truth":
            raise ConfigError(
                "estimator: 'ground_truth' exists in simulation only; with --hardware use "
                '--scenario_text "{estimator: kalman}"'
            )
    except ConfigError as error:
        print(f"error: {error}", file=sys.stderr)
        return 2
    name = Path(scenario.mission).stem if scenario.mission else args.scenario_name
    out_dir = Path(args.out) if args.out else Path("out") / name
    meshcat = None
    if args.meshcat:
        meshcat = Meshcat()
        print(f"Meshcat: {meshcat.web_url()}")
    where = f"over LCM ({scenario.lcm_buses['go1'].lcm_url})" if args.hardware else "in simulation"
    print(f"running {name} {where} ({scenario.simulation_duration:.1f} s max, seed {scenario.random_seed})")
    try:
        result = run(scenario=scenario, name=name, out_dir=out_dir, meshcat=meshcat, hardware=args.hardware)
    except LcmTimeout as error:
        print(f"error: {error}", file=sys.stderr)
        return 1
    errors = [f"{row['phase']} {row['leg']} {1000 * row['error']:.1f} mm" for row in result["foot_errors_m"]]
    print(
        f"{name}: {'succeeded' if result['success'] else 'FAILED: ' + result['reason']}; "
        f"{'run' if args.hardware else 'sim'} {result['sim_time_s']:.2f} s in {result['wall_time_s']:.2f} s wall "
        f"(real-time factor {result['real_time_factor']:.2f})"
        + (f"; foot errors ({result['judged_by'].replace('_', ' ')}): {', '.join(errors)}" if errors else "")
        + f"; results in {out_dir}/"
    )
    return 0 if result["success"] else 1


if __name__ == "__main__":
    sys.exit(main())
