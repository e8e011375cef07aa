"""Simulation speed of the station: real-time factor of the standing scenario, without visualisation.

    python -m pedi_drake.benchmarks.station [--runs 5] [--duration 4] [--out benchmarks/results/station.json]
    python -m pedi_drake.benchmarks.station --mission hit_target_front   # + the plant at a mission's states

Cases, each run `--runs` times (median reported):
  stand_pd            stand controller (joint PD at 1 kHz) + estimator + loggers, plain Go1
  stand_pd_prongs     the same with the default prong design
  station_fixed_cmd   baseline measured in the same run: the station alone with a constant command
                      (the lying pose)
  mission_states      with --mission M: the station alone (M's scene objects included), stepped
                      from the plant states and commands of M's own closed-loop run, a few steps
                      from each of evenly spaced samples (`mission_states_real_time_factor`):
                      what the plant costs where the mission takes it (standing, on three feet,
                      touching objects), against the lying robot of station_fixed_cmd
"""

import argparse
import json
import platform
import statistics
import time
from pathlib import Path

import numpy as np
from pydrake.systems.analysis import Simulator

from pedi_drake import robot
from pedi_drake.benchmarks.machine import stamped
from pedi_drake.diagram import MakePedipulationDiagram, apply_mission
from pedi_drake.go1_command import pack_command
from pedi_drake.mission.spec import load_mission
from pedi_drake.run import simulate
from pedi_drake.scenario import load_scenario
from pedi_drake.station_interface import MakeStation

# mission_states: how many samples of the mission's run, and how many steps from each [-].
MISSION_SAMPLES = 200
STEPS_PER_SAMPLE = 5


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


def mission_states_real_time_factor(mission: str) -> float:
    """Sim time / wall time of the station alone, stepped from the plant states and commands that
    `mission`'s closed-loop run (seed 0, no visualisation) logged: from each of MISSION_SAMPLES
    evenly spaced samples, STEPS_PER_SAMPLE control periods with that sample's command held. Only
    the steps are timed, not setting each sample's state."""
    scenario = load_scenario(scenario_text=f"{{mission: {mission}}}")
    record = simulate(scenario=scenario, name=mission, quiet=True, replay=False)
    states, commands = record.logs["sim.plant_state"], record.logs["go1.command"]
    station = MakeStation(apply_mission(scenario, load_mission(scenario.mission)))
    plant = station.GetSubsystemByName("plant")
    simulator = Simulator(station)
    context = simulator.get_mutable_context()
    plant_context = plant.GetMyMutableContextFromRoot(context)
    period = float(states.times[1] - states.times[0])
    last = len(states.times) - STEPS_PER_SAMPLE - 1
    stepped, wall = 0.0, 0.0
    for k in np.linspace(0, last, MISSION_SAMPLES).round().astype(int):
        context.SetTime(float(states.times[k]))
        plant.SetPositionsAndVelocities(plant_context, states.data[:, k])
        station.GetInputPort("go1.command").FixValue(context, commands.data[:, k])
        simulator.Initialize()
        start = time.perf_counter()
        simulator.AdvanceTo(float(states.times[k]) + STEPS_PER_SAMPLE * period)
        wall += time.perf_counter() - start
        stepped += STEPS_PER_SAMPLE * period
    return stepped / wall


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
    parser.add_argument("--mission", help="also time the station at this mission's states (mission_states)")
    parser.add_argument("--out", default="benchmarks/results/station.json")
    args = parser.parse_args()
    cases = ("station_fixed_cmd", "stand_pd", "stand_pd_prongs") + (("mission_states",) if args.mission else ())
    samples = {case: [] for case in cases}
    for _ in range(args.runs):  # interleaved, so machine load affects every case alike
        for case in cases:
            if case == "mission_states":
                samples[case].append(mission_states_real_time_factor(args.mission))
            else:
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
        json.dumps(
            stamped(
                {
                    "runs": args.runs,
                    "duration_s": args.duration,
                    "mission": args.mission,
                    "machine": machine,
                    "cases": rows,
                }
            ),
            indent=2,
        )
    )
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
