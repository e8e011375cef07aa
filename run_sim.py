"""Runs a pedi_drake scenario in simulation (headless by default) and writes its results.

Writes to --out: result.json (DESIGN.md section 5), replay.html (a self-contained Meshcat
replay: open it in a browser) and PNG plots. Exit code 0 on success, 1 on failure (the
reason is printed), 2 on bad input.

Examples:
    python run_sim.py --out out/default
    python run_sim.py --scenario_name stand_with_prongs --out out/prongs
    python run_sim.py --scenario_text "{simulation_duration: 2.0}" --meshcat
"""

import argparse
import sys
import time
from pathlib import Path

import numpy as np
from pydrake.geometry import Meshcat
from pydrake.systems.analysis import Simulator

from pedi_drake import robot
from pedi_drake.diagram import MakePedipulationDiagram
from pedi_drake.exceptions import ConfigError
from pedi_drake.results import trunk_fell, write_result
from pedi_drake.station.scenario import Scenario, default_scenario_file, load_scenario
from pedi_drake.viz.plots import plot_foot_forces, plot_joint_tracking


def run(*, scenario: Scenario, scenario_name: str, out_dir: Path, meshcat: Meshcat | None = None) -> dict:
    """Simulates `scenario`, writes result.json, replay.html and plots to `out_dir`; returns the result."""
    out_dir.mkdir(parents=True, exist_ok=True)
    # A Meshcat is always made: it records the replay even when nobody watches live.
    meshcat = meshcat or Meshcat()
    built = MakePedipulationDiagram(scenario, meshcat)
    diagram = built.diagram
    simulator = Simulator(diagram)
    simulator.Initialize()
    meshcat.StartRecording(set_visualizations_while_recording=False)
    wall_start = time.perf_counter()
    simulator.AdvanceTo(scenario.simulation_duration)
    wall_time = time.perf_counter() - wall_start
    meshcat.StopRecording()
    meshcat.PublishRecording()
    (out_dir / "replay.html").write_text(meshcat.StaticHtml())

    context = simulator.get_context()
    logs = {name: diagram.GetSubsystemByName(logger).FindLog(context) for name, logger in built.loggers.items()}
    plant = diagram.GetSubsystemByName("station").GetSubsystemByName("plant")
    plant_map = robot.Go1PlantMap.from_plant(plant)
    state_log = logs["sim.plant_state"].data()
    t = logs["go1.command"].sample_times()
    command = logs["go1.command"].data()
    position = logs["go1.position_measured"].data()
    plot_joint_tracking(t, command[:12], position, out_dir / "joint_positions.png", title=scenario_name)
    plot_foot_forces(
        logs["go1.foot_contact"].sample_times(), logs["go1.foot_contact"].data(), out_dir / "foot_forces.png"
    )

    fell = trunk_fell(state_log, plant_map, has_prongs=scenario.robot.prongs is not None)
    sim_time = float(context.get_time())
    final_height = float(state_log[plant_map.base_q_start + 6, -1])
    result = {
        "mission": scenario.mission or None,
        "scenario": scenario_name,
        "success": not fell,
        "reason": "the trunk fell" if fell else "",
        "phases": [],
        "foot_errors_m": [],
        "max_base_drift_m": None,
        "fell": fell,
        "sim_time_s": sim_time,
        "wall_time_s": wall_time,
        "real_time_factor": sim_time / wall_time if wall_time > 0 else None,
        "controller_tick_ms": None,
        "controller": scenario.controller,
        "final_trunk_height_m": final_height,
        "final_joint_error_rad": float(np.max(np.abs(position[:, -1] - command[:12, -1]))),
    }
    write_result(out_dir, result)
    return result


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--scenario_file", default=str(default_scenario_file()), help="YAML file of named scenarios.")
    parser.add_argument("--scenario_name", default="default", help="Scenario to run from --scenario_file.")
    parser.add_argument("--scenario_text", default="{}", help="YAML mapping merged onto the scenario.")
    parser.add_argument("--out", default=None, help="Output folder (default: out/<scenario_name>).")
    parser.add_argument("--duration", type=float, default=None, help="Simulated duration [s] (overrides the scenario).")
    parser.add_argument("--meshcat", action="store_true", help="Serve a live Meshcat view (prints its URL).")
    args = parser.parse_args()
    try:
        scenario = load_scenario(
            filename=args.scenario_file, scenario_name=args.scenario_name, scenario_text=args.scenario_text
        )
        if args.duration is not None:
            if not args.duration > 0:
                raise ConfigError(f"--duration: must be > 0 s, got {args.duration}")
            scenario.simulation_duration = args.duration
    except ConfigError as error:
        print(f"error: {error}", file=sys.stderr)
        return 2
    out_dir = Path(args.out) if args.out else Path("out") / args.scenario_name
    meshcat = None
    if args.meshcat:
        meshcat = Meshcat()
        print(f"Meshcat: {meshcat.web_url()}")
    result = run(scenario=scenario, scenario_name=args.scenario_name, out_dir=out_dir, meshcat=meshcat)
    print(
        f"{args.scenario_name}: {'succeeded' if result['success'] else 'FAILED: ' + result['reason']}; "
        f"sim {result['sim_time_s']:.2f} s in {result['wall_time_s']:.2f} s wall "
        f"(real-time factor {result['real_time_factor']:.2f}); results in {out_dir}/"
    )
    return 0 if result["success"] else 1


if __name__ == "__main__":
    sys.exit(main())
