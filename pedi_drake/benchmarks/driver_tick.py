"""CPU time per tick of the Go1 driver and the Kalman estimator on their own, replaying recorded ticks.

    python -m pedi_drake.benchmarks.driver_tick [--ticks 4000] [--evict-mb 0] [--wake-on-command]
        [--out benchmarks/results/driver_tick.json]

The hardware station (status receiver, safety filter, command sender, on an in-process bus with
the link's receive thread) and the Kalman estimator, fed the status and the commands of the
controller side's reference (tests/fixtures/controller_side_reference.npz): before each tick the
recorded status is published and the recorded command set as the station's go1.command. The
stages receive, estimate, safety and send are timed as `controller_latency` times them (its
STAGES, the loop thread's CPU time in each handler), and so are their sum and the whole tick;
what the tick costs beyond the stages is Drake's framework (event dispatch, port evaluation).

Without the whole-body controller between two ticks, the code and data of these stages stay in
the processor's caches: the numbers are their cost when warm. `--evict-mb N` walks through N MB
of memory before every tick, as a controller's tick would, to show the cost when cold.
`--wake-on-command` subscribes to the command channel on the link's bus, as a process that records
what was sent on its own bus would: the link's receive thread then wakes at every publication
of the loop (on a real bus nothing in the driver's process subscribes to it, and LCM does not
wake the thread for a channel without a subscriber).
"""

import argparse
import json
import time
from pathlib import Path

import lcm as lcm_module
import numpy as np
from pydrake.systems.analysis import Simulator
from pydrake.systems.framework import DiagramBuilder

from pedi_drake.apps.sim_bridge import status_messages
from pedi_drake.benchmarks.controller_latency import STAGES, stage_timers
from pedi_drake.estimation.kalman_estimator import KalmanEstimator
from pedi_drake.go1_driver import constants as c
from pedi_drake.go1_driver.hardware_station import MakeHardwareStation
from pedi_drake.go1_driver.link import Go1Link
from pedi_drake.scenario import load_scenario

FIXTURE = Path(__file__).resolve().parents[2] / "tests" / "fixtures" / "controller_side_reference.npz"
DRIVER_STAGES = ("receive", "estimate", "safety", "send")


def _distribution(x_ms: np.ndarray) -> dict:
    return {
        "median": float(np.median(x_ms)),
        "p99": float(np.percentile(x_ms, 99)),
        "p99_9": float(np.percentile(x_ms, 99.9)),
        "max": float(np.max(x_ms)),
    }


def run(ticks: int, evict_mb: float, wake_on_command: bool = False) -> dict:
    """Times `ticks` replayed ticks; returns {stage: distribution [ms]} and the sum's."""
    reference = np.load(FIXTURE)
    status, commands = reference["status"].astype(float), reference["commands"].astype(float)
    period = float(reference["period"])
    ticks = min(ticks, len(commands))
    scenario = load_scenario()
    config = scenario.go1_driver
    # No watchdog may trip in an unpaced replay.
    config.safety.status_timeout = config.safety.command_timeout = config.safety.warmup_command_timeout = 1e9
    config.safety.period = period
    link = Go1Link(lcm_module.LCM("memq://"), config, url="memq://")
    with stage_timers(ticks) as times:
        builder = DiagramBuilder()
        station = builder.AddNamedSystem("station", MakeHardwareStation(config, link))
        estimator = builder.AddNamedSystem(
            "estimator", KalmanEstimator(scenario.kalman, scenario.robot.initial_xy, scenario.robot.prongs)
        )
    for name in ("imu", "position_measured", "velocity_measured", "torque_estimated", "foot_contact"):
        builder.Connect(station.GetOutputPort(f"go1.{name}"), estimator.GetInputPort(name))
    builder.ExportInput(station.GetInputPort("go1.command"), "go1.command")
    diagram = builder.Build()
    simulator = Simulator(diagram)
    context = simulator.get_mutable_context()
    command_port = diagram.GetInputPort("go1.command")
    evict = np.ones(max(1, int(evict_mb * 1e6 / 8)))
    tick_ms = np.zeros(ticks)

    def publish(k: int) -> None:
        leg, state = status_messages(status[k], k)
        before = link.leg_control.received, link.state_estimator.received
        link.transport.publish(c.LEG_CONTROL_CHANNEL, leg.encode())
        link.transport.publish(c.STATE_ESTIMATOR_CHANNEL, state.encode())
        # The receive thread takes them in; the tick runs when both are in their inboxes.
        deadline = time.monotonic() + 1.0
        while link.leg_control.received == before[0] or link.state_estimator.received == before[1]:
            if time.monotonic() > deadline:
                raise RuntimeError(f"replayed status of tick {k} was not received")
            time.sleep(0.00005)

    if wake_on_command:
        link.transport.subscribe(c.COMMAND_CHANNEL, lambda _channel, _data: None)
    link.start()
    try:
        publish(0)
        command_port.FixValue(context, commands[0])
        simulator.Initialize()
        for k in range(ticks):
            publish(k + 1)
            command_port.FixValue(context, commands[k])
            if evict_mb > 0:
                evict += 1.0
            times["tick"] = k
            start = time.thread_time()
            simulator.AdvanceTo((k + 1) * period)
            tick_ms[k] = 1e3 * (time.thread_time() - start)
    finally:
        link.close()
    stages = {name: times[name] for name, _, _ in STAGES if name in DRIVER_STAGES}
    result = {name: _distribution(per_tick) for name, per_tick in stages.items()}
    result["sum"] = _distribution(sum(stages.values()))
    result["tick"] = _distribution(tick_ms)
    result["framework"] = _distribution(tick_ms - sum(stages.values()))
    return {"ticks": ticks, "evict_mb": evict_mb, "wake_on_command": wake_on_command, "stage_cpu_ms_per_tick": result}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--ticks", type=int, default=4000)
    parser.add_argument("--evict-mb", type=float, default=0.0, help="memory walked through before each tick [MB]")
    parser.add_argument(
        "--wake-on-command", action="store_true", help="subscribe to the command channel (a recorder on the link's bus)"
    )
    parser.add_argument("--out", default="benchmarks/results/driver_tick.json")
    args = parser.parse_args()
    load = Path("/proc/loadavg").read_text().split()[:3] if Path("/proc/loadavg").exists() else None
    result = run(args.ticks, args.evict_mb, args.wake_on_command)
    wake = ", the link's thread woken by every command" if args.wake_on_command else ""
    print(
        f"driver and estimator alone, {result['ticks']} replayed ticks, {args.evict_mb:g} MB evicted before each{wake}"
    )
    print(f"load average (1, 5, 15 min) at the start {load}")
    print(f"  {'stage':<10}{'median':>9}{'p99':>9}{'p99.9':>9}{'max':>9}  CPU time per tick [ms]")
    for name, row in result["stage_cpu_ms_per_tick"].items():
        print(f"  {name:<10}{row['median']:9.4f}{row['p99']:9.4f}{row['p99_9']:9.4f}{row['max']:9.3f}")
    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(json.dumps({"loadavg_start": load, **result}, indent=2))
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
