"""Latency of the controller side of a hardware run, against a replay of recorded status messages.

    python -m pedi_drake.benchmarks.controller_latency [--mission hit_target_front] [--period 0.002]
        [--callbacks [--window START:END]] [--parts]
        [--framework-floor] [--out benchmarks/results/controller_latency.json]

1. Records: the mission in simulation (seed 0); the status the robot would have sent at every
   tick (q, qd, tau_est, IMU, foot sensors) is read from the run's logs.
2. Replays: the `--hardware` diagram (driver, estimator, mission manager, live SUF, IK,
   whole-body controller) is built on an in-process bus and advanced as a hardware run advances it (one
   AdvanceTo, with a monitor); before every tick the recorded status is published, and the tick
   (receive, estimate, mission, IK, control, safety, send) is timed alone, unpaced.
   Two passes: with the garbage collector as Python leaves it, and as a hardware run runs
   (go1_driver.hardware_run: the heap frozen at the start). Each tick is attributed to what ran
   in it: a garbage collection (gc.callbacks), a mission phase transition, or nothing special.
   A tick is the whole period's work; "to the wire" is the part of it from the status in the inbox
   to the command's departure (the link's stamp), the latency a robot sees: the driver sends the
   command within the tick, after the controller, and the period's other work (the log, updates
   between ticks) comes after it. Beside the loop's ticks, the CPU time of the link's receive
   thread per tick (it decodes the status messages). The commands sent are kept by the link
   (`Go1Link.keep_sent_messages`), not by a subscriber on its bus, which would wake the receive
   thread in every tick as a hardware run's does not.
3. A timed pass gives each stage's CPU time: the event handlers of every system of the
   controller side (status receivers, estimator, mission manager and its reference outputs, live
   SUF, leg IK, whole-body controller, safety filter, command sender) are wrapped, while that pass's
   diagram is built, in a timer of the loop thread's CPU time; what the tick costs beyond them is
   Drake's framework (event dispatch, port evaluation, the log sinks).
   With `--callbacks`, one more pass times every Python callback of the diagram (periodic event
   handlers and output calculations, whatever their system): what the framework share is made
   of, and what Drake and pybind cost outside all Python code; and the costliest ticks of the run
   (or of `--window START:END`, in seconds of diagram time: where a run at real time stalled),
   each with the callbacks that took its time.
   With `--parts`, one more pass times the parts of the mission manager's update and the
   whole-body controller's compiled call (PARTS: CPU time per call, each part's own and its
   callees'). With `--framework-floor`, one more pass with every handler of the controller side
   a no-op (NO_OPS): what Drake, pybind and the log cost a tick by themselves.
4. The same mission in simulation: the whole-body controller's own tick (its diagnostics).
5. The bare plant's cost in the same run (`station_fixed_cmd` of the station benchmark: the
   simulated Go1 with a constant command), the baseline for machines of different speed.

Prints a table and writes JSON. The run is open loop (the replayed status ignores the commands),
which is what a latency measurement needs: the same inputs for every pass.

    python -m pedi_drake.benchmarks.controller_latency --record-reference FILE.npz [--reference-ticks N]

records the first N replayed ticks' status and the commands the controller side sent for them
(float32, as on the wire): the reference that `tests/test_controller_side_reference.py` replays
to show that a faster controller side sends the same commands.
"""

import argparse
import contextlib
import gc
import json
import platform
import time
from pathlib import Path

import numpy as np
from pydrake.systems.analysis import Simulator
from pydrake.systems.framework import EventStatus

from pedi_drake.apps.sim_bridge import status_messages
from pedi_drake.apps.status_sample import STATUS_SIGNALS
from pedi_drake.benchmarks.machine import stamped
from pedi_drake.benchmarks.station import real_time_factor
from pedi_drake.control import whole_body_tick
from pedi_drake.control.whole_body_controller import WholeBodyController
from pedi_drake.diagram import MakePedipulationDiagram
from pedi_drake.estimation.kalman_estimator import KalmanEstimator
from pedi_drake.go1_driver import constants as c
from pedi_drake.go1_driver.command_sender import Go1CommandSender
from pedi_drake.go1_driver.hardware_run import hardware_run
from pedi_drake.go1_driver.hardware_station import hardware_link
from pedi_drake.go1_driver.safety import Go1SafetyFilter
from pedi_drake.go1_driver.status_receiver import Go1LcmReceiver
from pedi_drake.ik.leg_ik_system import LegIkSystem
from pedi_drake.measuring.callback_profile import wrapped_callbacks
from pedi_drake.mission import mission_manager
from pedi_drake.mission.mission_manager import MissionManager
from pedi_drake.mission.phases import RUNNERS
from pedi_drake.mission.progress import MissionProgress
from pedi_drake.run import simulate
from pedi_drake.runtime.wall_clock import WallClock
from pedi_drake.scenario import apply_scenario_text, load_scenario
from pedi_drake.suf.live_suf_system import LiveSufSystem

# The controller side's stages in the order of a tick, each with the event handlers (and the
# outputs computed every tick) of its systems.
STAGES = (
    ("receive", Go1LcmReceiver, ("_latch_tick",)),
    ("estimate", KalmanEstimator, ("_update",)),
    ("mission", MissionManager, ("_update", "_calc_references", "_calc_body", "_calc_legs")),
    ("suf", LiveSufSystem, ("_on_tick",)),
    ("ik", LegIkSystem, ("_update",)),
    ("control", WholeBodyController, ("_update",)),
    ("safety", Go1SafetyFilter, ("_update",)),
    ("send", Go1CommandSender, ("_publish",)),
)


# `--parts`: (label, owner, attribute) of what is timed, a part's callees included; the phase
# runners' steps are added by kind (`_parts`).
PARTS = (
    ("mission update (all of it)", MissionManager, "_update"),
    ("  read the inputs (the RobotView)", MissionManager, "_view"),
    ("  copy the progress", MissionProgress, "copy"),
    ("  the fall check", MissionManager, "_fell"),
    ("  store the outputs", MissionManager, "_store"),
    ("  pack new trajectories (reference table)", mission_manager, "reference_table"),
    ("  safety polygon and haptic feedback", MissionManager, "_set_polygon"),
    ("    the stance's safety polygon", mission_manager, "stance_safety_polygon"),
    ("mission references (every tick)", MissionManager, "_calc_references"),
    ("whole-body update (all of it)", WholeBodyController, "_update"),
    ("  the compiled tick", whole_body_tick, "whole_body_tick"),
)

_SUCCEEDED = EventStatus.Succeeded()
# `--framework-floor`: every handler of the controller side, a no-op.
NO_OPS = (
    (Go1LcmReceiver, "_latch_tick", lambda self, context, state: None),
    (KalmanEstimator, "_update", lambda self, context, state: None),
    (MissionManager, "_update", lambda self, context, state: None),
    (MissionManager, "_calc_references", lambda self, context, output: None),
    (LiveSufSystem, "_on_tick", lambda self, context, state: None),
    (LegIkSystem, "_update", lambda self, context, state: _SUCCEEDED),
    (WholeBodyController, "_update", lambda self, context, state: None),
    (Go1SafetyFilter, "_update", lambda self, context, state: None),
    (Go1CommandSender, "_publish", lambda self, context, state: _SUCCEEDED),
    (WallClock, "_calc", lambda self, context, output: None),
)


def _scenario(mission: str, period: float, lcm_url: str = "", scenario_text: str = "{}"):
    periods = f"whole_body: {{period: {period}}}, kalman: {{period: {period}}}"
    text = f"{{{periods}, go1_driver: {{safety: {{period: {period}}}}}}}"
    scenario = apply_scenario_text(load_scenario(scenario_text=text), scenario_text)
    scenario.mission, scenario.controller = mission, "whole_body"
    if lcm_url:
        scenario.lcm_buses["go1"].lcm_url = lcm_url
    # No watchdog may trip in an unpaced replay: it measures the computation, not the clock.
    scenario.go1_driver.safety.status_timeout = 1e9
    scenario.go1_driver.safety.command_timeout = 1e9
    scenario.go1_driver.shutdown_damping_duration = 0.0
    # An unpaced loop never sleeps: at real-time priority it would hold a core for the whole replay.
    scenario.go1_driver.realtime_priority = 0
    return scenario


def record_status(mission: str, period: float) -> tuple[np.ndarray, dict]:
    """(status samples (n, 50; apps.status_sample) at every control tick, the simulation's timing)."""
    scenario = _scenario(mission, period)
    scenario.simulation_duration = 60.0
    record = simulate(scenario=scenario, name=mission, quiet=True, replay=False)
    logs = record.logs
    times = logs["go1.position_measured"].times
    # The sample logged at t = 0 precedes the sensors' first update (all zeros): start a tick later.
    ticks = np.arange(period, times[-1], period)
    index = np.searchsorted(times, ticks - 1e-9)
    samples = np.concatenate([logs[name].data[:, index] for name in STATUS_SIGNALS], axis=0).T
    tick_ms = 1e3 * logs["controller.diagnostics"].data[2]
    tick_ms = tick_ms[tick_ms > 0]
    sim = {
        "sim_time_s": record.sim_time,
        "wall_time_s": record.wall_time,
        "real_time_factor": record.sim_time / record.wall_time,
        "controller_tick_ms": _distribution(tick_ms),
    }
    return samples, sim


def _distribution(x_ms: np.ndarray) -> dict:
    x = np.asarray(x_ms)
    return {
        "median": float(np.median(x)),
        "p99": float(np.percentile(x, 99)),
        "p99_9": float(np.percentile(x, 99.9)),
        "max": float(np.max(x)),
    }


class Replay:
    """The hardware diagram on an in-process bus, fed the recorded status tick by tick
    (`scenario_text`: YAML onto the scenario)."""

    def __init__(
        self,
        mission: str,
        period: float,
        samples: np.ndarray,
        scenario_text: str = "{}",
    ):
        self.period, self.samples = period, samples
        self.scenario = _scenario(mission, period, "memq://", scenario_text)
        self.built = MakePedipulationDiagram(self.scenario, hardware=True)
        self.diagram = self.built.diagram
        self.link = hardware_link(self.diagram)
        self.bus = self.link.transport
        self.simulator = Simulator(self.diagram)
        # As a run does (pedi_drake.run): the log never grows in a tick.
        self.built.reserve_logs(self.simulator.get_mutable_context(), len(samples) * period)
        self.manager = self.diagram.GetSubsystemByName("mission")
        # The commands are kept by the link, not taken from the bus: a subscriber there would be
        # handed every command in the next tick's read of the bus, work a hardware run does not do.
        self.link.keep_sent_messages()
        self._published = 0

    def _publish(self, k: int) -> None:
        """Puts tick k's status on the in-process bus, where the tick's receiver reads it (as a
        hardware run's loop reads the socket at the start of its tick: the tick's time includes it)."""
        leg, estimator = status_messages(self.samples[min(k, len(self.samples) - 1)], k)
        self.bus.publish(c.LEG_CONTROL_CHANNEL, leg.encode())
        self.bus.publish(c.STATE_ESTIMATOR_CHANNEL, estimator.encode())
        self._published += 1

    def _check_every_status_was_read(self) -> None:
        """Every replayed status was read (a tick that missed its own would have run on the last)."""
        for inbox in (self.link.leg_control, self.link.state_estimator):
            if inbox.received != self._published:
                counts = {inbox.channel: inbox.counts() for inbox in self.link.inboxes}
                raise RuntimeError(
                    f"{self._published} replayed statuses, {inbox.channel} read {inbox.received}: {counts}"
                )

    def sent_commands(self) -> np.ndarray:
        """(n, 60) the commands published so far, decoded from the wire."""
        decode = c.CHANNEL_TYPES[c.COMMAND_CHANNEL].decode
        return np.array([c.message_to_command(decode(data)) for data in self.link.sent_messages])

    def run(self, ticks: int, stage_times: dict | None = None) -> dict:
        """Times `ticks` ticks; returns tick times [ms] and what happened in each.

        The ticks run in one AdvanceTo, as in a hardware run (pedi_drake.run), with a Simulator
        monitor at the end of every step (a hardware run has one too) that publishes the next
        tick's status and stamps the times; the monitor's own work is left out of the tick. An
        AdvanceTo per tick would add work a hardware run does not do: at every AdvanceTo the
        Simulator looks up the witness functions of every system again, a Python call per
        Python system (it does so otherwise only after an unrestricted update, the mission's).
        """
        collections: list[float] = []

        def on_gc(phase, info) -> None:
            collections.append((time.perf_counter(), phase, info["generation"]))

        self.link.start()
        self._publish(0)
        self.simulator.Initialize()
        context = self.simulator.get_context()
        manager_context = self.manager.GetMyContextFromRoot(context)
        tick_ms = np.zeros(ticks)
        # The loop thread's own CPU time in the tick: wall time far above it means the thread was
        # waiting (preempted by other processes), not computing.
        cpu_ms = np.zeros(ticks)
        # Each tick's start on the link's clocks, for the time its command took to the wire.
        start_monotonic, start_cpu = np.zeros(ticks), np.zeros(ticks)
        phase_index = np.zeros(ticks, dtype=int)
        gc_generation = np.full(ticks, -1)
        tick = {"k": 0, "start": 0.0, "cpu_start": 0.0}

        def start_tick(k: int) -> None:
            self._publish(k + 1)
            collections.clear()
            if stage_times is not None:
                stage_times["tick"] = k
            tick["k"], tick["start"], tick["cpu_start"] = k, time.perf_counter(), time.thread_time()
            start_monotonic[k], start_cpu[k] = time.monotonic(), tick["cpu_start"]

        def end_of_step(root_context) -> EventStatus:
            cpu_end, end = time.thread_time(), time.perf_counter()
            k = tick["k"]
            # A step that ends between ticks (an update at a period that is not a multiple of the
            # tick's, the leg IK's) belongs to the tick that is running.
            if k >= ticks or root_context.get_time() < (k + 1) * self.period - 1e-9:
                return EventStatus.Succeeded()
            tick_ms[k] = 1e3 * (end - tick["start"])
            cpu_ms[k] = 1e3 * (cpu_end - tick["cpu_start"])
            phase_index[k] = self.manager.progress(manager_context).index
            starts = [g for _, p, g in collections if p == "start"]
            if starts:
                gc_generation[k] = max(starts)
            if k + 1 < ticks:
                start_tick(k + 1)
            else:
                tick["k"] = ticks
            return EventStatus.Succeeded()

        gc.callbacks.append(on_gc)
        self.simulator.set_monitor(end_of_step)
        receive_start = self.link.receive_cpu_time()
        try:
            start_tick(0)
            self.simulator.AdvanceTo(ticks * self.period)
            self.link.poll()  # the status published for the tick after the last
            self._check_every_status_was_read()
        finally:
            receive_cpu_s = self.link.receive_cpu_time() - receive_start
            self.simulator.clear_monitor()
            gc.callbacks.remove(on_gc)
            self.link.close()
        transition = np.zeros(ticks, dtype=bool)
        transition[1:] = phase_index[1:] != phase_index[:-1]
        to_wire_ms, to_wire_cpu_ms = self._to_wire(start_monotonic, start_cpu)
        return {
            "tick_ms": tick_ms,
            "cpu_ms": cpu_ms,
            "to_wire_ms": to_wire_ms,
            "to_wire_cpu_ms": to_wire_cpu_ms,
            "gc_generation": gc_generation,
            "transition": transition,
            "receive_thread_cpu_ms_per_tick": 1e3 * receive_cpu_s / ticks,
        }

    def _to_wire(self, start_monotonic: np.ndarray, start_cpu: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Each tick's time from its start (its status in the inbox) to its command's departure
        (the link's stamp) [ms], in wall and in the loop thread's CPU time; NaN for a tick that
        sent no command."""
        timing = self.link.loop_timing
        ticks = len(start_monotonic)
        wall, cpu = np.full(ticks, np.nan), np.full(ticks, np.nan)
        index = np.rint(np.asarray(timing.times) / self.period).astype(int)
        inside = (index >= 0) & (index < ticks)
        wall[index[inside]] = 1e3 * (np.asarray(timing.departures)[inside] - start_monotonic[index[inside]])
        cpu[index[inside]] = 1e3 * (np.asarray(timing.loop_cpu)[inside] - start_cpu[index[inside]])
        return wall, cpu


def _max_or_none(x: np.ndarray) -> float | None:
    return float(x.max()) if x.size else None


def _summary(run: dict, period_ms: float) -> dict:
    tick = run["tick_ms"]
    late = tick > period_ms
    gc_any = run["gc_generation"] >= 0
    worst = np.argsort(tick)[-10:][::-1]
    return {
        "ticks": int(tick.size),
        "tick_ms": _distribution(tick),
        "tick_cpu_ms": _distribution(run["cpu_ms"]),
        # From the status in the inbox to the command on the wire: the tick's latency.
        "to_wire_ms": _distribution(run["to_wire_ms"][np.isfinite(run["to_wire_ms"])]),
        "to_wire_cpu_ms": _distribution(run["to_wire_cpu_ms"][np.isfinite(run["to_wire_cpu_ms"])]),
        "ticks_without_their_command": int(np.count_nonzero(~np.isfinite(run["to_wire_ms"]))),
        "receive_thread_cpu_ms_per_tick": run["receive_thread_cpu_ms_per_tick"],
        "deadline_misses_per_10000": float(1e4 * np.count_nonzero(late) / tick.size),
        "ticks_with_gc": {f"gen{g}": int(np.count_nonzero(run["gc_generation"] == g)) for g in range(3)},
        "max_tick_with_full_gc_ms": float(tick[run["gc_generation"] == 2].max())
        if np.any(run["gc_generation"] == 2)
        else None,
        "max_tick_without_gc_or_transition_ms": float(tick[~gc_any & ~run["transition"]].max()),
        "max_tick_at_phase_transition_ms": _max_or_none(tick[run["transition"]]),
        "worst_ticks": [
            {
                "tick": int(k),
                "ms": float(tick[k]),
                "cpu_ms": float(run["cpu_ms"][k]),
                "gc_generation": int(run["gc_generation"][k]),
                "phase_transition": bool(run["transition"][k]),
            }
            for k in worst
        ],
    }


@contextlib.contextmanager
def stage_timers(ticks: int):
    """While active, systems built get their handlers timed: yields {stage: (ticks,) CPU ms}.

    The handlers are bound when a system declares its events and ports, so the classes' methods
    are wrapped for the block (the diagram must be built inside it) and restored after it.
    """
    times = {name: np.zeros(ticks) for name, _, _ in STAGES}
    times["tick"] = -1
    originals = []
    # Stages of the handlers running now: one that evaluates another's output (the controller
    # reading the mission's reference) is charged its own time only.
    running: list[str] = []

    def timed(stage: str, method):
        def wrapper(*args, **kwargs):
            start = time.thread_time()
            running.append(stage)
            try:
                return method(*args, **kwargs)
            finally:
                running.pop()
                k = times["tick"]
                if 0 <= k < ticks:
                    elapsed = 1e3 * (time.thread_time() - start)
                    times[stage][k] += elapsed
                    if running:
                        times[running[-1]][k] -= elapsed

        return wrapper

    for stage, cls, names in STAGES:
        for name in names:
            originals.append((cls, name, getattr(cls, name)))
            setattr(cls, name, timed(stage, getattr(cls, name)))
    try:
        yield times
    finally:
        for cls, name, method in originals:
            setattr(cls, name, method)


@contextlib.contextmanager
def callback_timers(ticks: int):
    """While active, systems built get every Python callback (pedi_drake.measuring.callback_profile.DECLARATIONS)
    timed: yields ({"System.port" or "System periodic ...": (ticks,) CPU ms}, the same of call
    counts), with "tick" to be set to the running tick (Replay.run does). A callback that
    evaluates another's output is charged its own time only. The timers add about a
    microsecond to each call.
    """
    times: dict = {"tick": -1}
    calls: dict = {}
    running: list[str] = []

    def timed(key: str, callback):
        times.setdefault(key, np.zeros(ticks))
        calls.setdefault(key, np.zeros(ticks, dtype=int))

        def wrapper(*args, **kwargs):
            start = time.thread_time()
            running.append(key)
            try:
                return callback(*args, **kwargs)
            finally:
                running.pop()
                k = times["tick"]
                if 0 <= k < ticks:
                    elapsed = 1e3 * (time.thread_time() - start)
                    times[key][k] += elapsed
                    calls[key][k] += 1
                    if running:
                        times[running[-1]][k] -= elapsed

        return wrapper

    with wrapped_callbacks(timed):
        yield times, calls


def _callback_table(times: dict, calls: dict, cpu_ms: np.ndarray) -> dict:
    """Per callback: calls per tick and CPU [ms] per tick; and what the ticks cost beyond them."""
    rows = {
        key: {"calls_per_tick": float(calls[key].mean()), "mean_ms": float(per_tick.mean()), **_distribution(per_tick)}
        for key, per_tick in times.items()
        if key != "tick"
    }
    rows = dict(sorted(rows.items(), key=lambda row: -row[1]["mean_ms"]))
    outside = cpu_ms - sum(per_tick for key, per_tick in times.items() if key != "tick")
    rows["(Drake and pybind outside Python callbacks)"] = {
        "calls_per_tick": 0.0,
        "mean_ms": float(outside.mean()),
        **_distribution(outside),
    }
    return rows


def costliest_ticks(times: dict, cpu_ms: np.ndarray, period: float, window: tuple[float, float] | None, count: int = 6):
    """The `count` ticks of the callbacks pass with the most CPU time, in the diagram-time
    `window` [s] (start, end) or over the whole run: per tick its time [s], CPU time [ms] and the
    callbacks that took more than 20 us of it, largest first [ms]."""
    ticks = np.arange(len(cpu_ms))
    if window is not None:
        ticks = ticks[(ticks * period >= window[0]) & (ticks * period < window[1])]
    costliest = ticks[np.argsort(cpu_ms[ticks])[::-1][:count]]
    rows = []
    for k in sorted(costliest):
        spent = {key: float(per_tick[k]) for key, per_tick in times.items() if key != "tick" and per_tick[k] > 0.02}
        rows.append(
            {
                "t": float(k * period),
                "cpu_ms": float(cpu_ms[k]),
                "callbacks_ms": dict(sorted(spent.items(), key=lambda item: -item[1])),
            }
        )
    return rows


def _parts() -> list[tuple[str, object, str]]:
    steps = [(f"  phase step: {kind.__name__}", runner, "step") for kind, runner in RUNNERS.items()]
    return [*PARTS[:4], *steps, *PARTS[4:]]


@contextlib.contextmanager
def part_timers():
    """While active, every part of `_parts()` is timed: yields {label: [CPU ms of each call]}."""
    times: dict[str, list[float]] = {}
    originals = []

    def timed(label: str, method):
        calls = times.setdefault(label, [])

        def wrapper(*args, **kwargs):
            start = time.thread_time()
            try:
                return method(*args, **kwargs)
            finally:
                calls.append(1e3 * (time.thread_time() - start))

        return wrapper

    for label, owner, name in _parts():
        originals.append((owner, name, owner.__dict__.get(name), getattr(owner, name)))
        setattr(owner, name, timed(label, getattr(owner, name)))
    try:
        yield times
    finally:
        for owner, name, own, _ in reversed(originals):
            if own is None:
                delattr(owner, name)  # an instance's: the class's method shows again
            else:
                setattr(owner, name, own)


def _parts_table(times: dict[str, list[float]], ticks: int) -> dict:
    return {
        label: {
            "calls_per_tick": len(calls) / ticks,
            "per_call_mean_ms": float(np.mean(calls)),
            "per_call_p99_ms": float(np.percentile(calls, 99)),
            "per_tick_mean_ms": float(np.sum(calls)) / ticks,
        }
        for label, calls in times.items()
        if calls
    }


@contextlib.contextmanager
def no_op_handlers():
    """While active, systems built get NO_OPS for their handlers (the diagram must be built inside)."""
    originals = [(cls, name, getattr(cls, name)) for cls, name, _ in NO_OPS]
    for cls, name, no_op in NO_OPS:
        setattr(cls, name, no_op)
    try:
        yield
    finally:
        for cls, name, method in originals:
            setattr(cls, name, method)


def record_reference(mission: str, period: float, ticks: int, path: Path) -> None:
    """Writes the status of the first `ticks` replayed ticks and the commands sent for them."""
    samples, _ = record_status(mission, period)
    samples = samples[: ticks + 1].astype(np.float32)
    replay = Replay(mission, period, samples.astype(float))
    replay.run(ticks)
    commands = replay.sent_commands().astype(np.float32)
    path.parent.mkdir(parents=True, exist_ok=True)
    np.savez_compressed(path, mission=mission, period=period, status=samples, commands=commands)
    print(f"wrote {path}: {ticks} ticks, {len(commands)} commands")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--mission", default="hit_target_front")
    parser.add_argument("--period", type=float, default=0.002, help="control period [s]")
    parser.add_argument("--baseline_duration", type=float, default=4.0, help="simulated seconds of the bare plant")
    parser.add_argument("--out", default="benchmarks/results/controller_latency.json")
    parser.add_argument("--record-reference", type=Path, help="write the reference ticks here and stop")
    parser.add_argument("--reference-ticks", type=int, default=4000)
    parser.add_argument("--callbacks", action="store_true", help="one more pass: every Python callback timed")
    parser.add_argument(
        "--window",
        help="with --callbacks: START:END [s] of diagram time whose costliest ticks are listed (default: all)",
    )
    parser.add_argument("--parts", action="store_true", help="one more pass: the parts of PARTS timed")
    parser.add_argument("--framework-floor", action="store_true", help="one more pass: every handler a no-op")
    args = parser.parse_args()
    window = None
    if args.window:
        try:
            window = tuple(float(x) for x in args.window.split(":"))
            if len(window) != 2 or window[0] >= window[1]:
                raise ValueError
        except ValueError:
            parser.error(f"--window: expected START:END in seconds with START < END, got {args.window!r}")
    if args.record_reference:
        record_reference(args.mission, args.period, args.reference_ticks, args.record_reference)
        return
    load_start = Path("/proc/loadavg").read_text().split()[:3] if Path("/proc/loadavg").exists() else None

    baseline_rtf = real_time_factor("station_fixed_cmd", args.baseline_duration)
    # Wall time of the bare plant per control period [ms].
    baseline_ms = 1e3 * args.period / baseline_rtf
    samples, sim = record_status(args.mission, args.period)
    ticks = len(samples) - 1
    period_ms = 1e3 * args.period

    default_gc = Replay(args.mission, args.period, samples).run(ticks)
    replay = Replay(args.mission, args.period, samples)
    with hardware_run(replay.diagram, shutdown_damping_duration=0.0):
        frozen_gc = replay.run(ticks)
    with stage_timers(ticks) as stage_times:
        timed = Replay(args.mission, args.period, samples)
    timed_run = timed.run(ticks, stage_times)
    stages = {}
    for name, _, _ in STAGES:
        per_tick = stage_times[name]
        stages[name] = {"mean_ms": float(per_tick.mean()), **_distribution(per_tick)}
    framework = timed_run["cpu_ms"] - sum(stage_times[name] for name, _, _ in STAGES)
    stages["framework"] = {"mean_ms": float(framework.mean()), **_distribution(framework)}
    callbacks, costliest = None, None
    if args.callbacks:
        with callback_timers(ticks) as (callback_times, callback_calls):
            timed = Replay(args.mission, args.period, samples)
        callback_cpu_ms = timed.run(ticks, callback_times)["cpu_ms"]
        callbacks = _callback_table(callback_times, callback_calls, callback_cpu_ms)
        costliest = costliest_ticks(callback_times, callback_cpu_ms, args.period, window)
    parts = None
    if args.parts:
        with part_timers() as part_times:
            Replay(args.mission, args.period, samples).run(ticks)
        parts = _parts_table(part_times, ticks)
    floor = None
    if args.framework_floor:
        with no_op_handlers():
            idle = Replay(args.mission, args.period, samples)
        floor = _distribution(idle.run(ticks)["cpu_ms"])

    rows = {"python_gc": _summary(default_gc, period_ms), "hardware_run_gc": _summary(frozen_gc, period_ms)}
    load_end = Path("/proc/loadavg").read_text().split()[:3] if Path("/proc/loadavg").exists() else None
    print(f"controller side of {args.mission} at {1 / args.period:.0f} Hz, {ticks} replayed ticks")
    print(f"load average (1, 5, 15 min) at the start {load_start}, at the end {load_end}")
    print(f"bare plant (station_fixed_cmd): {baseline_ms:.3f} ms per {period_ms:.1f} ms step (RTF {baseline_rtf:.2f})")
    header = f"{'pass':<18}{'median':>8}{'p99':>8}{'p99.9':>8}{'max':>9}{'miss/1e4':>10}{'median/plant':>14}"
    print(header + "  worst tick cause")
    for name, row in rows.items():
        t = row["tick_ms"]
        worst = row["worst_ticks"][0]
        cause = f"gc gen{worst['gc_generation']} " if worst["gc_generation"] >= 0 else ""
        cause += "phase transition " if worst["phase_transition"] else ""
        cause += f"(its CPU time {worst['cpu_ms']:.2f} ms)"
        print(
            f"{name:<18}{t['median']:8.3f}{t['p99']:8.3f}{t['p99_9']:8.3f}{t['max']:9.2f}"
            f"{row['deadline_misses_per_10000']:10.1f}{t['median'] / baseline_ms:14.2f}  {cause}"
        )
        cpu = row["tick_cpu_ms"]
        print(
            f"{'  CPU time':<18}{cpu['median']:8.3f}{cpu['p99']:8.3f}{cpu['p99_9']:8.3f}{cpu['max']:9.2f}"
            f"  (and the link's receive thread: {row['receive_thread_cpu_ms_per_tick']:.3f} ms a tick)"
        )
        wire = row["to_wire_ms"]
        print(
            f"{'  to the wire':<18}{wire['median']:8.3f}{wire['p99']:8.3f}{wire['p99_9']:8.3f}{wire['max']:9.2f}"
            f"{'':10}{wire['median'] / baseline_ms:14.2f}  (status in, command out; "
            f"{row['ticks_without_their_command']} ticks without)"
        )
    total = sum(stage["mean_ms"] for stage in stages.values())
    print("CPU time per tick by stage (timed pass) [ms]:")
    print(f"  {'stage':<12}{'mean':>8}{'median':>8}{'p99':>8}{'max':>8}{'share':>8}")
    for name, stage in stages.items():
        print(
            f"  {name:<12}{stage['mean_ms']:8.3f}{stage['median']:8.3f}{stage['p99']:8.3f}{stage['max']:8.2f}"
            f"{100 * stage['mean_ms'] / total:7.1f}%"
        )
    if callbacks is not None:
        print("CPU time per tick by Python callback (callbacks pass) [us]:")
        print(f"  {'callback':<58}{'calls':>7}{'mean':>8}{'median':>8}{'p99':>8}")
        for name, row in callbacks.items():
            print(
                f"  {name:<58}{row['calls_per_tick']:7.2f}{1e3 * row['mean_ms']:8.1f}"
                f"{1e3 * row['median']:8.1f}{1e3 * row['p99']:8.1f}"
            )
    if costliest is not None:
        where = f"between {window[0]:g} and {window[1]:g} s" if window else "of the run"
        print(f"The costliest ticks {where} (callbacks pass), with the callbacks over 20 us [ms]:")
        for row in costliest:
            spent = ", ".join(f"{name} {ms:.2f}" for name, ms in row["callbacks_ms"].items())
            print(f"  t = {row['t']:.3f} s: {row['cpu_ms']:.2f} ms ({spent})")
    if parts is not None:
        print("CPU time by part (parts pass; a part's callees included) [us]:")
        print(f"  {'part':<46}{'calls/tick':>11}{'per call':>10}{'p99':>8}{'per tick':>10}")
        for label, row in parts.items():
            print(
                f"  {label:<46}{row['calls_per_tick']:11.3f}{1e3 * row['per_call_mean_ms']:10.1f}"
                f"{1e3 * row['per_call_p99_ms']:8.1f}{1e3 * row['per_tick_mean_ms']:10.1f}"
            )
    if floor is not None:
        print(
            f"framework floor (every handler of the controller side a no-op): tick CPU median "
            f"{floor['median']:.3f} ms, p99 {floor['p99']:.3f}, max {floor['max']:.2f}"
        )
    sim_tick = sim["controller_tick_ms"]
    print(
        f"simulation: real-time factor {sim['real_time_factor']:.2f}; whole-body controller tick median "
        f"{sim_tick['median']:.3f} ms, p99 {sim_tick['p99']:.3f}, p99.9 {sim_tick['p99_9']:.3f}, "
        f"max {sim_tick['max']:.2f}"
    )
    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    machine = {"processor": platform.processor() or platform.machine(), "python": platform.python_version()}
    out.write_text(
        json.dumps(
            stamped(
                {
                    "mission": args.mission,
                    "period_s": args.period,
                    "machine": machine,
                    "loadavg_start": load_start,
                    "loadavg_end": load_end,
                    "bare_plant": {"real_time_factor": baseline_rtf, "ms_per_period": baseline_ms},
                    "replay": rows,
                    "stage_cpu_ms_per_tick": stages,
                    "callback_cpu_ms_per_tick": callbacks,
                    "costliest_ticks": costliest,
                    "costliest_ticks_window_s": window,
                    "part_cpu_ms": parts,
                    "framework_floor_cpu_ms": floor,
                    "simulation": sim,
                }
            ),
            indent=2,
        )
    )
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
