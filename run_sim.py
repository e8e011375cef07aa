"""Runs a pedi_drake mission (or scenario) in simulation, headless by default, and writes its results.

Writes to --out (default out/<mission or scenario>/): result.json (docs/results.md),
replay.html (a self-contained Meshcat replay: open it in a browser), PNG plots and logs.npz.
Exit codes: 0 success; 1 failure (the reason is printed), or an internal error (one line, the
traceback in DIR/error.txt); 2 bad input, before anything is built (the message names the file
or flag, the field and the allowed values); 130 stopped by Ctrl-C or SIGTERM (what ran is still
judged and written, with `interrupted: true`).

Examples:
    python run_sim.py                                   # the default mission, hit_target_front
    python run_sim.py --mission open_door --out out/door
    python run_sim.py --mission my_mission.yaml --meshcat
    python run_sim.py --scenario_name stand --out out/stand
    python run_sim.py --scenario_text "{sensor_noise: {enabled: true}, random_seed: 3}"
    python run_sim.py --graphviz out/diagram.dot       # also write the run's diagram (Graphviz)
    python run_sim.py --meshcat --teleop               # drive the foot from the Meshcat page's panel
    python run_sim.py --hardware --mission hit_target_front   # over LCM: a Go1, or the simulator
        # bridge started first in another terminal:
        #   python -m pedi_drake.apps.sim_bridge --mission hit_target_front
"""

# The stop handlers go in before pydrake loads (seconds): a Ctrl-C even then ends the run cleanly.
from pedi_drake.runtime.interrupt import EXIT_INTERRUPTED, StopRequest  # noqa: I001

STOP = StopRequest().install()

import argparse  # noqa: E402
import sys  # noqa: E402
import traceback  # noqa: E402
from pathlib import Path  # noqa: E402

from pydrake.common.yaml import yaml_load  # noqa: E402
from pydrake.geometry import Meshcat  # noqa: E402

from pedi_drake.diagram import MakePedipulationDiagram, apply_mission  # noqa: E402
from pedi_drake.exceptions import ConfigError, LcmTimeout  # noqa: E402
from pedi_drake.mission.spec import load_mission  # noqa: E402
from pedi_drake.run import run  # noqa: E402
from pedi_drake.run_checks import check_duration, check_out_dir, check_scene_geometry  # noqa: E402
from pedi_drake.scenario import MISSION_CONTROLLERS, default_scenario_file, load_scenario  # noqa: E402

ERROR_FILE = "error.txt"
# The mission of `--teleop` unless --mission names another or the scenario's own mission takes an
# operator: the default scenario's mission is autonomous and would never hand the foot to the panel.
# The FR foot is lifted 5 cm from a wall, so that a push on it shows the force display.
TELEOP_MISSION = "operator/teleop_foot_wall"


def _prepare(args):
    """(scenario, name, out_dir) from the command line, every value checked; raises ConfigError."""
    scenario = load_scenario(
        filename=args.scenario_file, scenario_name=args.scenario_name, scenario_text=args.scenario_text
    )
    if args.teleop:
        scenario.operator.source = "meshcat"
        if args.mission is None and not (scenario.mission and load_mission(scenario.mission).takes_an_operator()):
            args.mission = TELEOP_MISSION
    mission = None
    if args.mission is not None:
        overrides = yaml_load(data=args.scenario_text) if args.scenario_text.strip() else {}
        asked = overrides.get("controller") if isinstance(overrides, dict) else None
        if asked not in (None, *MISSION_CONTROLLERS):
            raise ConfigError(
                f"--scenario_text: controller: a mission runs under one of {MISSION_CONTROLLERS}, got {asked!r}"
            )
        mission = load_mission(args.mission)  # validate now: bad input exits 2 before anything runs
        # The scenario's own mission controller stays (paper 002's in teleop_paper002, say).
        kept = scenario.controller if scenario.controller in MISSION_CONTROLLERS else "whole_body"
        scenario.mission, scenario.controller = args.mission, asked or kept
    elif scenario.mission:
        mission = load_mission(scenario.mission)
    if mission is not None and args.duration is None:
        # Room for every phase to use its timeout: the run stops as soon as the mission is over.
        scenario.simulation_duration = max(scenario.simulation_duration, mission.longest_duration())
    if args.duration is not None:
        if not args.duration > 0:
            raise ConfigError(f"--duration: must be > 0 s, got {args.duration}")
        scenario.simulation_duration = args.duration
    check_duration(scenario, "--duration" if args.duration is not None else "simulation_duration")
    if args.hardware and scenario.estimator == "ground_truth":
        raise ConfigError(
            "estimator: 'ground_truth' exists in simulation only; with --hardware use "
            '--scenario_text "{estimator: kalman}"'
        )
    merged = apply_mission(scenario, mission) if mission is not None else scenario
    if not args.hardware:
        # The merged scene lists the scenario's objects first, then the mission's.
        check_scene_geometry(merged, where="scene")
    name = Path(scenario.mission).stem if scenario.mission else args.scenario_name
    out_dir = Path(args.out) if args.out else Path("out") / name
    check_out_dir(out_dir)
    return scenario, name, out_dir


def command_line() -> argparse.ArgumentParser:
    """run_sim.py's options."""
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
        help="Simulated duration [s], finite and at least one control tick (overrides the scenario; by "
        "default a mission gets room for every phase to reach its timeout, and the run ends when the "
        "mission does).",
    )
    parser.add_argument("--meshcat", action="store_true", help="Serve a live Meshcat view (prints its URL).")
    parser.add_argument(
        "--teleop",
        action="store_true",
        help="Drive the foot from a panel in the Meshcat page (operator source meshcat: foot velocity sliders, "
        f"teleop / autonomous / E-stop buttons; implies --meshcat; the mission {TELEOP_MISSION} unless --mission "
        "names another). The simulation then runs in real time.",
    )
    parser.add_argument(
        "--hardware",
        action="store_true",
        help="Drive the Go1 over LCM (the scenario's bus 'go1') in real time instead of simulating it.",
    )
    parser.add_argument(
        "--graphviz",
        default=None,
        help="Also write the run's diagram (its systems and their wiring) to this Graphviz file.",
    )
    return parser


def main() -> int:
    args = command_line().parse_args()
    try:
        scenario, name, out_dir = _prepare(args)
    except ConfigError as error:
        print(f"error: {error}", file=sys.stderr)
        return 2
    meshcat = None
    if args.meshcat or args.teleop:
        meshcat = Meshcat()
        print(f"Meshcat: {meshcat.web_url()}")
    if args.graphviz:
        # The same function builds the run's diagram below; this copy is only drawn. Depth 1
        # keeps the station one box, as controllers see it.
        diagram = MakePedipulationDiagram(scenario, meshcat, hardware=args.hardware).diagram
        Path(args.graphviz).parent.mkdir(parents=True, exist_ok=True)
        Path(args.graphviz).write_text(diagram.GetGraphvizString(max_depth=1))
        print(f"diagram written to {args.graphviz}")
    where = f"over LCM ({scenario.lcm_buses['go1'].lcm_url})" if args.hardware else "in simulation"
    print(f"running {name} {where} ({scenario.simulation_duration:.1f} s max, seed {scenario.random_seed})", flush=True)
    try:
        result = run(scenario=scenario, name=name, out_dir=out_dir, meshcat=meshcat, hardware=args.hardware, stop=STOP)
    except ConfigError as error:  # found only when the folder is claimed (another run holds it)
        print(f"error: {error}", file=sys.stderr)
        return 2
    except LcmTimeout as error:
        print(f"error: {error}", file=sys.stderr)
        return 1
    except Exception as error:  # a bug, not bad input: one line here, the traceback in a file
        return _internal_error(error, out_dir)
    errors = [f"{row['phase']} {row['leg']} {1000 * row['error']:.1f} mm" for row in result["foot_errors_m"]]
    print(
        f"{name}: {'succeeded' if result['success'] else 'FAILED: ' + result['reason']}; "
        f"{'run' if args.hardware else 'sim'} {result['sim_time_s']:.2f} s in {result['wall_time_s']:.2f} s wall "
        f"(real-time factor {result['real_time_factor'] or 0.0:.2f})"
        + (f"; foot errors ({result['judged_by'].replace('_', ' ')}): {', '.join(errors)}" if errors else "")
        + f"; results in {out_dir}/"
    )
    if result["interrupted"]:
        return EXIT_INTERRUPTED
    return 0 if result["success"] else 1


def _internal_error(error: Exception, out_dir: Path) -> int:
    """Writes the traceback of `error` to out_dir/error.txt, prints one line naming it, returns 1."""
    text = "".join(traceback.format_exception(error))
    try:
        out_dir.mkdir(parents=True, exist_ok=True)
        path = out_dir / ERROR_FILE
        path.write_text(text)
        where = f"traceback in {path}"
    except OSError:
        where = "traceback not written: " + text.strip().splitlines()[-1]
    print(f"internal error (a bug, please report it): {type(error).__name__}: {error}; {where}", file=sys.stderr)
    return 1


if __name__ == "__main__":
    code = main()
    # The run is over and written: a signal now has nothing to stop. Ignored rather than left to
    # Python's shutdown, which puts the default handlers back and would die of it (exit -2).
    STOP.ignore_from_now_on()
    sys.exit(code)
