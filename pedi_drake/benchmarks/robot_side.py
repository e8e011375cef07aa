"""The robot side's cost per 2 ms step: the simulated station in a closed-loop mission and in the
SIL bridge, against the bare plant measured in the same run.

    python -m pedi_drake.benchmarks.robot_side [--mission hit_target_front] [--duration 6]
        [--runs 3] [--cases bare_plant,closed_loop,bridge] [--callbacks]
        [--out benchmarks/results/robot_side.json]

Cases, run interleaved `--runs` times (medians reported), each simulated for `--duration`
seconds from the start, unpaced:
  bare_plant    the station alone with a constant command (`station_fixed_cmd` of
                `pedi_drake.benchmarks.station`): the plant's own step, the baseline
  closed_loop   the mission in simulation as `run_sim.py` runs it (seed 0, no sensor noise,
                no visualisation): plant, station, estimator, mission, IK, controller, log
  bridge        `apps.sim_bridge`'s diagram on an in-process bus: the station publishing the
                status messages and applying the last command (one command is on the bus
                before the start, so the hold applies a received command as in a SIL run)

Per case: the main thread's CPU time per 2 ms of simulated time (`time.thread_time`: what
other processes on the machine do not change much) and the real-time factor (wall clock). The
closed loop's ratios to the bare plant, by CPU time and by wall clock, are the figures the
project's floor is about (closed-loop real-time factor at least half the bare plant's).

`--callbacks` adds one pass of the closed loop and of the bridge that times every Python
callback of the diagram (`controller_latency.callback_timers`): calls and CPU time per 2 ms
step, and what the step costs outside all Python code (the plant, Drake's framework, pybind).

For instruction counts, independent of the machine's load, run one case under callgrind:
    valgrind --tool=callgrind --callgrind-out-file=/tmp/cg.out \\
        python -m pedi_drake.benchmarks.robot_side --cases closed_loop --runs 1 --duration 1
(the count includes building the diagram; compare two durations to get the per-step cost).
"""

import argparse
import json
import platform
import statistics
import time
from pathlib import Path

import numpy as np
from pydrake.lcm import DrakeLcm
from pydrake.systems.analysis import Simulator
from pydrake.systems.framework import EventStatus

from pedi_drake import robot
from pedi_drake.apps.bridge_options import bridge_scenario
from pedi_drake.apps.sim_bridge import MakeSimBridgeDiagram
from pedi_drake.benchmarks.controller_latency import _callback_table, callback_timers
from pedi_drake.benchmarks.station import bare_plant_simulator
from pedi_drake.diagram import MakePedipulationDiagram
from pedi_drake.go1_command import pack_command
from pedi_drake.go1_driver import constants as c
from pedi_drake.scenario import load_scenario

STEP = 0.002  # [s] the control period the costs are given per
CASES = ("bare_plant", "closed_loop", "bridge")


def _loadavg() -> list[str] | None:
    path = Path("/proc/loadavg")
    return path.read_text().split()[:3] if path.exists() else None


def _closed_loop(mission: str, duration: float) -> Simulator:
    scenario = load_scenario(scenario_text=f"{{mission: {mission}, sensor_noise: {{enabled: false}}}}")
    built = MakePedipulationDiagram(scenario)
    simulator = Simulator(built.diagram)
    built.reserve_logs(simulator.get_mutable_context(), duration)
    return simulator


def _bridge(mission: str) -> Simulator:
    """The bridge's diagram on an in-process bus, with a command on the bus (the standing pose)."""
    scenario = load_scenario(scenario_text=f"{{mission: {mission}}}")
    lcm = DrakeLcm("memq://")
    diagram = MakeSimBridgeDiagram(bridge_scenario(scenario, mission), lcm)
    command = c.command_to_message(pack_command(robot.LYING_Q, 0, 60, 2, 0))
    lcm.Publish(c.COMMAND_CHANNEL, command.encode())
    return Simulator(diagram)


def _build(case: str, mission: str, duration: float) -> Simulator:
    if case == "bare_plant":
        return bare_plant_simulator()
    if case == "closed_loop":
        return _closed_loop(mission, duration)
    return _bridge(mission)


def measure(simulator: Simulator, duration: float) -> dict:
    """Advances `simulator` (not yet initialised) by `duration` [s]; CPU ms per STEP and RTF."""
    simulator.Initialize()
    cpu, wall = time.thread_time(), time.perf_counter()
    simulator.AdvanceTo(duration)
    cpu, wall = time.thread_time() - cpu, time.perf_counter() - wall
    return {"cpu_ms_per_step": 1e3 * cpu * STEP / duration, "real_time_factor": duration / wall}


def callbacks_pass(case: str, mission: str, duration: float) -> dict:
    """Every Python callback of `case`'s diagram timed: {callback: calls and CPU per STEP}."""
    steps = int(round(duration / STEP))
    with callback_timers(steps) as (times, calls):
        simulator = _build(case, mission, duration)
    cpu = np.zeros(steps)
    last = {"cpu": None}

    def monitor(context) -> EventStatus:
        now = time.thread_time()
        k = times["tick"]
        if last["cpu"] is not None and 0 <= k < steps:
            cpu[k] += 1e3 * (now - last["cpu"])
        last["cpu"] = now
        # The step that starts at t belongs to the period [k STEP, (k + 1) STEP) that holds t.
        times["tick"] = int(np.floor(context.get_time() / STEP + 1e-6))
        return EventStatus.Succeeded()

    simulator.set_monitor(monitor)
    simulator.Initialize()
    times["tick"] = 0
    last["cpu"] = time.thread_time()
    simulator.AdvanceTo(duration)
    return _callback_table(times, calls, cpu)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--mission", default="hit_target_front")
    parser.add_argument("--duration", type=float, default=6.0, help="simulated seconds per run")
    parser.add_argument("--runs", type=int, default=3)
    parser.add_argument("--cases", default=",".join(CASES))
    parser.add_argument("--callbacks", action="store_true", help="one more pass timing every Python callback")
    parser.add_argument("--out", default="benchmarks/results/robot_side.json")
    args = parser.parse_args()
    cases = [case for case in args.cases.split(",") if case]
    unknown = set(cases) - set(CASES)
    if unknown:
        parser.error(f"--cases: unknown {sorted(unknown)}; expected some of {CASES}")
    load_start = _loadavg()
    samples = {case: [] for case in cases}
    for _ in range(args.runs):  # interleaved, so the machine's load affects every case alike
        for case in cases:
            samples[case].append(measure(_build(case, args.mission, args.duration), args.duration))
    rows = {}
    for case, runs in samples.items():
        rows[case] = {
            "cpu_ms_per_step": statistics.median(r["cpu_ms_per_step"] for r in runs),
            "real_time_factor": statistics.median(r["real_time_factor"] for r in runs),
            "runs": runs,
        }
    callbacks = {}
    if args.callbacks:
        for case in ("closed_loop", "bridge"):
            if case in cases:
                callbacks[case] = callbacks_pass(case, args.mission, args.duration)
    load_end = _loadavg()

    print(f"robot side of {args.mission}: {args.runs} runs of {args.duration:.1f} s per case")
    print(f"load average (1, 5, 15 min) at the start {load_start}, at the end {load_end}")
    print(f"{'case':<14}{'CPU ms/2ms':>12}{'RTF':>8}{'CPU vs bare':>13}{'RTF vs bare':>13}")
    bare = rows.get("bare_plant")
    for case, row in rows.items():
        cpu_ratio = bare["cpu_ms_per_step"] / row["cpu_ms_per_step"] if bare else float("nan")
        rtf_ratio = row["real_time_factor"] / bare["real_time_factor"] if bare else float("nan")
        row["rtf_ratio_to_bare_by_cpu"], row["rtf_ratio_to_bare_by_wall"] = cpu_ratio, rtf_ratio
        print(
            f"{case:<14}{row['cpu_ms_per_step']:12.3f}{row['real_time_factor']:8.2f}{cpu_ratio:13.2f}{rtf_ratio:13.2f}"
        )
    for case, table in callbacks.items():
        print(f"{case}: CPU per 2 ms step by Python callback [us]")
        print(f"  {'callback':<58}{'calls':>7}{'mean':>8}{'p99':>8}")
        for name, row in table.items():
            print(f"  {name:<58}{row['calls_per_tick']:7.2f}{1e3 * row['mean_ms']:8.1f}{1e3 * row['p99']:8.1f}")
    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    machine = {"processor": platform.processor() or platform.machine(), "python": platform.python_version()}
    out.write_text(
        json.dumps(
            {
                "mission": args.mission,
                "duration_s": args.duration,
                "machine": machine,
                "loadavg_start": load_start,
                "loadavg_end": load_end,
                "cases": rows,
                "callback_cpu_ms_per_step": callbacks,
            },
            indent=2,
        )
    )
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
