"""Simulation speed of the station: real-time factor of the standing scenario, without visualisation.

    python -m pedi_drake.benchmarks.station [--runs 5] [--duration 4] [--out benchmarks/results/station.json]

Cases, each run `--runs` times (median reported):
  stand_pd            stand controller (joint PD at 1 kHz) + estimator + loggers, plain Go1
  stand_pd_prongs     the same with the default prong design
  station_fixed_cmd   baseline measured in the same run: the station alone with a constant command
"""

import argparse
import json
import platform
import statistics
import time
from pathlib import Path

from pydrake.systems.analysis import Simulator

from pedi_drake import robot
from pedi_drake.diagram import MakePedipulationDiagram
from pedi_drake.go1_command import pack_command
from pedi_drake.scenario import load_scenario
from pedi_drake.station_interface import MakeStation


def _time(simulator: Simulator, duration: float) -> float:
    simulator.Initialize()
    start = time.perf_counter()
    simulator.AdvanceTo(duration)
    return duration / (time.perf_counter() - start)


def _stand_scenario(prongs: bool):
    prong_text = "robot: {prongs: {}}, " if prongs else ""
    return load_scenario(scenario_name="stand", scenario_text=f"{{{prong_text}stand: {{period: 0.001}}}}")


def bare_plant_simulator() -> Simulator:
    """`station_fixed_cmd`, the baseline of every speed figure: the simulated Go1 station alone, its
    command fixed (the lying pose, kp 60, kd 2), not yet initialised."""
    station = MakeStation(_stand_scenario(prongs=False))
    context = station.CreateDefaultContext()
    station.GetInputPort("go1.command").FixValue(context, pack_command(robot.LYING_Q, 0, 60, 2, 0))
    return Simulator(station, context)


def real_time_factor(case: str, duration: float) -> float:
    """One run of `case`; returns sim time / wall time."""
    if case == "station_fixed_cmd":
        return _time(bare_plant_simulator(), duration)
    scenario = _stand_scenario(prongs=case.endswith("prongs"))
    return _time(Simulator(MakePedipulationDiagram(scenario).diagram), duration)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--runs", type=int, default=5)
    parser.add_argument("--duration", type=float, default=4.0, help="simulated seconds per run")
    parser.add_argument("--out", default="benchmarks/results/station.json")
    args = parser.parse_args()
    cases = ("station_fixed_cmd", "stand_pd", "stand_pd_prongs")
    samples = {case: [] for case in cases}
    for _ in range(args.runs):  # interleaved, so machine load affects every case alike
        for case in cases:
            samples[case].append(real_time_factor(case, args.duration))
    baseline = statistics.median(samples["station_fixed_cmd"])
    print(f"{'case':<20} {'median RTF':>11} {'min':>7} {'max':>7} {'vs baseline':>12}")
    rows = {}
    for case in cases:
        median = statistics.median(samples[case])
        rows[case] = {"median_rtf": median, "samples": samples[case], "ratio_to_baseline": median / baseline}
        low, high = min(samples[case]), max(samples[case])
        print(f"{case:<20} {median:>11.2f} {low:>7.2f} {high:>7.2f} {median / baseline:>12.2f}")
    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    machine = {"processor": platform.processor() or platform.machine(), "python": platform.python_version()}
    out.write_text(
        json.dumps({"runs": args.runs, "duration_s": args.duration, "machine": machine, "cases": rows}, indent=2)
    )
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
