"""What both robot sides of the Go1 wire take from their command line: the scenario (with a
mission's scene and robot variant), the bus, the pace and the status's latency and drops.

`apps.sim_bridge` (the project's Drake simulation) and `apps.mujoco_bridge` (MuJoCo) share these
options, so either can stand in for the other in a user's first terminal or in `apps.sil`.
"""

import argparse
import math

from pedi_drake.diagram import apply_mission
from pedi_drake.exceptions import ConfigError
from pedi_drake.go1_driver.config import Go1BridgeConfig
from pedi_drake.mission.spec import load_mission
from pedi_drake.scenario import Scenario, load_scenario


def add_bridge_arguments(parser: argparse.ArgumentParser) -> None:
    """The options every robot side takes (see the module docstring)."""
    parser.add_argument("--scenario_file", default=None, help="scenario YAML (default: the shipped one)")
    parser.add_argument("--scenario_name", default="default")
    parser.add_argument("--scenario_text", default="{}", help="YAML mapping merged onto the scenario")
    parser.add_argument("--duration", type=float, default=math.inf, help="simulated seconds (default: until killed)")
    parser.add_argument("--lcm_url", default=None, help="override the scenario's bus 'go1' URL")
    parser.add_argument("--latency", type=float, default=None, help="status latency [s]")
    parser.add_argument("--drop_probability", type=float, default=None, help="status drop probability [-]")
    parser.add_argument("--realtime_rate", type=float, default=1.0)
    parser.add_argument("--mission", default=None, help="add this mission's scene objects and robot variant")
    parser.add_argument("--truth_log", default=None, help="write the ground truth (npz) here on exit")


def bridge_scenario(scenario: Scenario, mission: str | None) -> Scenario:
    """`scenario` with the mission's scene objects and robot variant, as the controller side has them."""
    if not mission:
        return scenario
    return apply_mission(scenario, load_mission(mission))


def bridge_settings(args: argparse.Namespace) -> tuple[Scenario, Go1BridgeConfig]:
    """The robot side's scenario and its bridge settings (`--latency`, `--drop_probability` over
    the scenario's); raises ConfigError naming the file, field or flag that is wrong."""
    scenario = load_scenario(
        filename=args.scenario_file, scenario_name=args.scenario_name, scenario_text=args.scenario_text
    )
    scenario = bridge_scenario(scenario, args.mission)
    if not (math.isfinite(args.realtime_rate) and args.realtime_rate > 0.0):
        raise ConfigError(f"--realtime_rate: must be a positive number, got {args.realtime_rate}")
    config = scenario.go1_driver.bridge
    if args.latency is not None:
        config.latency = args.latency
    if args.drop_probability is not None:
        config.drop_probability = args.drop_probability
    return scenario, config
