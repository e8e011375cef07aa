"""The teleoperation floors at real time over UDP: three processes, as on the robot.

    python -m pedi_drake.benchmarks.teleop [--scenarios square fuzz switches] [--fuzz_count 10000]
        [--seed N] [--realtime_priority 0] [--wait auto] [--work out/teleop_benchmark]
        [--out benchmarks/results/teleop.json]

Each scenario (pedi_drake.evaluation.teleop_floors) is `pedi_drake.apps.sil` with an operator:
the simulator bridge (the robot side, its own process, real time, 500 Hz, writing the ground
truth), the controller side as `run_sim.py --hardware` runs it (driver, estimator, mission,
whole-body controller), and the scripted operator as a person would run one,
`python -m pedi_drake.apps.teleop_lcm --lcm_log FILE --start_on_feedback` in a third process,
sending the scenario's stream (written to FILE) over UDP on the controller's clock. Each is judged
against the bridge's ground truth, on the controller's logs, as the lock-step tests judge theirs
(tests/test_teleop_square.py, test_teleop_fuzz.py, test_random_mode_switches.py).

Prints a table (square tracking error max and RMS, violations, fuzz messages sent and rejected by
reason, switches done, falls, the controller loop's deadline misses per 1000 ticks, the load
average before and after) and writes the figures as JSON. This machine may be shared: the load
average says how quiet it was. `--realtime_priority N` runs the controller's loop under SCHED_FIFO at
priority N (the driver's `realtime_priority`), as a robot's computer would; the simulator bridge
keeps its own setting (normal scheduling by default, see Go1BridgeConfig). `--wait spin` makes the
controller's loop busy-wait for its periods (the driver's `wait`, pedi_drake/go1_driver/pacing.py).
"""

import argparse
import dataclasses
import json
import os
import platform
import time
from pathlib import Path

import numpy as np

from pedi_drake.apps.sil import run_sil
from pedi_drake.benchmarks.machine import stamped
from pedi_drake.evaluation import command_fuzz, judge, random_switches, teleop_square
from pedi_drake.evaluation.teleop_floors import (
    SCENARIO_TEXT,
    Truth,
    floor_figures,
    truth_from_bridge_log,
    truth_from_plant_log,
)
from pedi_drake.go1_driver.pacing import WAITS
from pedi_drake.mission import spec
from pedi_drake.mission.spec import load_mission
from pedi_drake.operator.config import DEFAULT_FOOT_COMMAND_CHANNEL
from pedi_drake.operator.message_stream import TimedMessage, write_lcm_log
from pedi_drake.run import simulate
from pedi_drake.run_logs import SignalLog
from pedi_drake.scenario import Scenario, apply_scenario_text, load_scenario

SCENARIOS = ("square", "fuzz", "switches")


@dataclasses.dataclass
class LockStepRun:
    """A simulated run of an operator's stream: its result (result.json's content), logs and truth."""

    result: dict
    logs: dict[str, SignalLog]
    truth: Truth
    scenario: Scenario
    mission: spec.MissionSpec


def lock_step_run(mission: str, messages: list[TimedMessage], duration: float) -> LockStepRun:
    """Runs `mission` in simulation for `duration` [s] with `messages` played in lock step."""
    scenario = apply_scenario_text(
        load_scenario(scenario_text=SCENARIO_TEXT), f"{{mission: {mission}, simulation_duration: {duration}}}"
    )
    record = simulate(scenario=scenario, name=mission, quiet=True, replay=False, operator_messages=messages)
    plant = record.built.diagram.GetSubsystemByName("station").GetSubsystemByName("plant")
    truth = truth_from_plant_log(plant, record.logs["sim.plant_state"])
    return LockStepRun(judge.judge_run(record), record.logs, truth, scenario, record.built.mission)


def _load() -> list[str] | None:
    path = Path("/proc/loadavg")
    return path.read_text().split()[:3] if path.exists() else None


def _stream(name: str, seed: int | None, fuzz_count: int):
    """(mission, messages, simulation duration [s], the scenario's own inputs to the judge); `seed`
    None: the tests' seed."""
    channel = DEFAULT_FOOT_COMMAND_CHANNEL
    if name == "square":
        return teleop_square.MISSION, teleop_square.square_stream(channel), teleop_square.SIMULATION_DURATION, None
    if name == "fuzz":
        stream = command_fuzz.fuzz_stream(command_fuzz.SEED if seed is None else seed, fuzz_count, channel)
        return command_fuzz.MISSION, stream.messages, stream.simulation_duration, stream
    seed = random_switches.SEED if seed is None else seed
    stream = random_switches.switch_stream(seed, random_switches.ROUND_TRIPS, channel)
    return random_switches.MISSION, stream.messages, stream.simulation_duration, stream


def one_scenario(
    name: str, seed: int | None, fuzz_count: int, work: Path, realtime_priority: int = 0, wait: str = "auto"
) -> dict:
    """Runs scenario `name` at real time over UDP and judges it (module docstring); with
    `realtime_priority` > 0 the controller's loop runs under SCHED_FIFO at that priority, and it
    waits for its periods as `wait` says (the driver's setting)."""
    mission_name, messages, duration, stream = _stream(name, seed, fuzz_count)
    out_dir = work / name
    log = write_lcm_log(messages, work / f"{name}_operator.lcmlog")
    # The controller side's scenario: apps.sil adds the mission, the bus, the controller and estimator.
    scenario_text = f"{{operator: {{source: lcm}}, simulation_duration: {duration}"
    scenario_text += f", go1_driver: {{realtime_priority: {realtime_priority}, wait: {wait}}}}}"
    scenario = apply_scenario_text(load_scenario(scenario_text=SCENARIO_TEXT), scenario_text)
    load_before, start = _load(), time.monotonic()
    records = []
    result = run_sil(mission_name, out_dir, scenario_text=scenario_text, operator_log=log, records=records)
    wall = time.monotonic() - start
    # The run's own logs, at full precision: the bounds are met to the last digit (logs.npz keeps 7).
    logs = records[0].logs
    with np.load(out_dir / "bridge_truth.npz") as archive:
        truth = truth_from_bridge_log({key: archive[key] for key in archive.files}, logs["wall_clock"])
    mission = load_mission(mission_name)
    figures = floor_figures(result, logs, truth, scenario, mission)
    row = {
        "scenario": name,
        "mission": mission_name,
        "success": bool(result["success"]),
        "reason": result["reason"],
        "driver_latched": result["driver"]["latched"],
        "driver_interventions": result["driver"]["interventions"],
        "operator_process": result["sil"].get("operator"),
        "messages_sent": len(messages),
        **figures,
        "teleop": result["teleop"],
        "mode_switch_list": result["mode_switches"],
        "lcm_url": result["sil"]["lcm_url"],
        "scheduling": {
            "controller": result["driver"]["loop"]["scheduling"],
            "bridge": result["sil"]["bridge_scheduling"],
        },
        "real_time_factor": result["real_time_factor"],
        "wall_s": wall,
        "load_before": load_before,
        "load_after": _load(),
    }
    if name == "square":
        row["square"] = teleop_square.square_errors(truth.times, truth.foot("FR"))
    if name == "fuzz":
        row["fuzz"] = {"sent": stream.sent, "expected_rejections": stream.expected, "expected_taken": stream.taken}
    if name == "switches":
        row["switch_plan"] = stream.plan
    return row


def _rejected(row: dict) -> str:
    counted = row["operator_messages"] or {}
    return ", ".join(f"{reason} {n}" for reason, n in sorted(counted.get("rejected", {}).items())) or "-"


def print_table(rows: list[dict]) -> None:
    print(
        f"{'scenario':<10}{'square max/RMS [mm]':>21}{'violations':>12}{'sent':>7}{'taken':>7}{'rejected':>10}"
        f"{'switches':>10}{'rate limits':>13}{'fell':>6}{'misses/1000':>13}  load before -> after"
    )
    for row in rows:
        square = row.get("square")
        error = f"{1e3 * square['timed_max_m']:.1f} / {1e3 * square['timed_rms_m']:.1f}" if square else "-"
        counted = row["operator_messages"] or {}
        within = all(limit["within"] for limit in row["rate_limits"].values())
        print(
            f"{row['scenario']:<10}{error:>21}{row['violations']['total']:>12}{row['messages_sent']:>7}"
            f"{counted.get('received', 0):>7}{counted.get('dropped', 0):>10}{row['mode_switches']:>10}"
            f"{'within' if within else 'EXCEEDED':>13}{'yes' if row['fell'] else 'no':>6}"
            f"{row['deadline_misses_per_1000']:>13.2f}  {row['load_before']} -> {row['load_after']}"
        )
    for row in rows:
        operator = row["operator_process"] or {}
        print(
            f"{row['scenario']}: rejected by reason: {_rejected(row)}; success {row['success']} {row['reason']}; "
            f"operator process exit {operator.get('returncode')}: {operator.get('output', '')[-200:]!r}"
        )
        if row.get("square"):
            square = row["square"]
            print(
                f"  square: distance to the path max {1e3 * square['path_max_m']:.1f} mm, RMS "
                f"{1e3 * square['path_rms_m']:.1f} mm; to the commanded point max {1e3 * square['timed_max_m']:.1f} mm"
                f", RMS {1e3 * square['timed_rms_m']:.1f} mm; farthest corner {1e3 * square['corner_max_m']:.1f} mm"
            )
        if row.get("fuzz"):
            fuzz = row["fuzz"]
            print(f"  fuzz: sent by kind {fuzz['sent']}; expected rejections {fuzz['expected_rejections']}")
        steps = ", ".join(
            f"{name} {limit['step']:.4g} (limit {limit['limit']:.4g})" for name, limit in row["rate_limits"].items()
        )
        print(f"  largest steps a tick: {steps}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--scenarios", nargs="+", choices=SCENARIOS, default=list(SCENARIOS))
    parser.add_argument(
        "--seed", type=int, default=None, help="seed of the fuzzed and the switching operators (default: the tests')"
    )
    parser.add_argument("--fuzz_count", type=int, default=command_fuzz.FUZZ_COUNT)
    parser.add_argument(
        "--realtime_priority",
        type=int,
        default=0,
        help="SCHED_FIFO priority of the controller and the bridge (0: normal scheduling)",
    )
    parser.add_argument(
        "--wait",
        choices=WAITS,
        default="auto",
        help="how the controller's loop waits for its periods (auto: sleep, as the operator's input needs the core)",
    )
    parser.add_argument("--work", default="out/teleop_benchmark", help="folder of the runs' outputs")
    parser.add_argument("--out", default="benchmarks/results/teleop.json")
    args = parser.parse_args()
    rows = []
    for name in args.scenarios:
        row = one_scenario(name, args.seed, args.fuzz_count, Path(args.work), args.realtime_priority, args.wait)
        rows.append(row)
        print(f"{name}: done in {row['wall_s']:.0f} s, load {row['load_before']} -> {row['load_after']}", flush=True)
    print_table(rows)
    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    machine = {"processor": platform.processor() or platform.machine(), "cpus": os.cpu_count()}
    out.write_text(
        json.dumps(
            stamped(
                {
                    "seed": args.seed,
                    "realtime_priority": args.realtime_priority,
                    "wait": args.wait,
                    "machine": machine,
                    "scenarios": rows,
                }
            ),
            indent=2,
            default=float,
        )
    )
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
