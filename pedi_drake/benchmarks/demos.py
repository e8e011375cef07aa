"""The whole-body controller demonstrations: missions of missions/demos/ on scenarios/wbc_demos.yaml.

    python -m pedi_drake.benchmarks.demos NAME [--out DIR]    # NAME: one of DEMOS

Each demo is a mission file (stand, three_leg_hold, five_targets, prongs, push_no_prongs,
push_prongs) and a scenario of the same name: the robot starts standing and the controller runs
on the simulated true state (estimator: ground_truth), so the figures measure the controller
alone. They run like any mission, through `pedi_drake.run.simulate` (MakePedipulationDiagram);
the push demos' force is a `pushes` entry of the mission, applied by the simulated station.
`run_demo` returns the figures of `pedi_drake.evaluation.controller_metrics`.
"""

import argparse
import dataclasses
import json
from pathlib import Path

from pedi_drake.evaluation.controller_metrics import ControllerMetrics, controller_metrics
from pedi_drake.evaluation.judge import judge_run, write_run
from pedi_drake.exceptions import ConfigError
from pedi_drake.mission.spec import DEMOS_FOLDER, shipped_demos
from pedi_drake.resources import scenarios_dir
from pedi_drake.run import simulate
from pedi_drake.scenario import Scenario, load_scenario

DEMOS = tuple(name.removeprefix(f"{DEMOS_FOLDER}/") for name in shipped_demos())
SCENARIO_FILE = scenarios_dir() / "wbc_demos.yaml"


def demo_scenario(name: str, **whole_body_overrides) -> Scenario:
    """The scenario of demo `name` (scenarios/wbc_demos.yaml), with controller config overrides."""
    if name not in DEMOS:
        raise ConfigError(f"demo: must be one of {DEMOS}, got {name!r}")
    scenario = load_scenario(filename=SCENARIO_FILE, scenario_name=name)
    scenario.whole_body = dataclasses.replace(scenario.whole_body, **whole_body_overrides)
    return scenario


def simulate_demo(name: str, scenario: Scenario | None = None):
    """Simulates demo `name` without any visualisation: (RunRecord, judged result)."""
    scenario = scenario or demo_scenario(name)
    if scenario.estimator != "ground_truth":
        raise ConfigError("the demos measure the controller alone: they need estimator: ground_truth")
    record = simulate(scenario=scenario, name=name, quiet=True, replay=False)
    return record, judge_run(record)


def run_demo(name: str, scenario: Scenario | None = None) -> ControllerMetrics:
    """Simulates demo `name` and measures the controller (ground truth, evaluation only)."""
    record, judged = simulate_demo(name, scenario)
    return controller_metrics(record, judged)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("name", choices=DEMOS)
    parser.add_argument("--out", default=None, help="also write result.json, plots and logs.npz here")
    args = parser.parse_args()
    record, judged = simulate_demo(args.name)
    metrics = controller_metrics(record, judged)
    if args.out:
        out = Path(args.out)
        out.mkdir(parents=True, exist_ok=True)
        write_run(record, judged, out)
    print(
        json.dumps({"success": judged["success"], "reason": judged["reason"], **dataclasses.asdict(metrics)}, indent=2)
    )
    return 0 if judged["success"] else 1


if __name__ == "__main__":
    raise SystemExit(main())
