"""The live SUF's update and the control tick: five ways of running it, side by side.

    python -m pedi_drake.benchmarks.suf_offload [--mission hit_target_front] [--runs 2]
        [--designs none unrestricted one_tick slices thread] [--out benchmarks/results/suf_offload.json]

Each run is a software-in-the-loop run (`apps.sil`, as pedi_drake.benchmarks.sil_floors: the
simulator bridge in its own process, the controller side here, both at real time) with the live
SUF done one way:

* none: no live SUF (`live_suf: {enabled: false}`), the baseline;
* unrestricted: `UnrestrictedLiveSuf`, the live SUF as it was before its work was spread over
  ticks (kept here only): one unrestricted update per period doing the whole update, the warm
  start a value in its abstract state;
* one_tick: the shipped LiveSufSystem with a `tick_work` no update reaches (1.0e+9): the whole
  update in its start's tick, as a discrete update;
* slices: the shipped LiveSufSystem, each update spread over the control ticks after its start,
  at most `live_suf.tick_work` per tick (pedi_drake.suf.live_suf_system);
* thread: `ThreadedLiveSuf`, a prototype kept here only: at each start tick the update handed to
  a worker thread one period before is collected (waited for if it is still running) and
  published, and the next one is handed over; the worker runs at nice WORKER_NICE. In a
  simulation that sequence would be deterministic too (collected a period later, whatever the
  machine's speed).

The designs take turns run by run, so the machine's other load falls on each alike. Per run:
success, the loop's deadline misses per 1000 ticks and the longest miss, its lateness (p99,
max), the control ticks an update took (its publication's age in ticks), and the load average.
Prints a table and writes JSON.

    python -m pedi_drake.benchmarks.suf_offload --replay [--runs 2]

instead replays the mission's recorded status through the controller side, unpaced, as
pedi_drake.benchmarks.controller_latency does (its `Replay`, heap frozen as in a hardware run), once
per design and run: the CPU time of the live SUF's handler in a tick (on the loop's thread: for
`thread`, what the hand-over costs), overall and, where it ran, by the tick's place in the
manager's period (0 ms: the manager's update, 4 ms: the live SUF's start), the whole tick's CPU
time by its place, and the whole tick's wall and CPU time. Less at the mercy of the machine's
other load than the runs at real time; it does not see what a worker thread costs the loop by
sharing its core.
"""

import argparse
import concurrent.futures
import contextlib
import dataclasses
import json
import math
import os
import platform
import threading
import time
from pathlib import Path

import numpy as np
from pydrake.common.value import AbstractValue
from pydrake.systems.framework import LeafSystem

from pedi_drake import diagram as diagram_module
from pedi_drake.benchmarks.controller_latency import Replay, record_status
from pedi_drake.benchmarks.sil_floors import one_run
from pedi_drake.estimation.base_state import BASE_STATE_SIZE
from pedi_drake.go1_driver.hardware_run import hardware_run
from pedi_drake.suf.live import DEFAULT_MAX_LPS, LiveSuf, LiveSufWorkspace, idle_vector
from pedi_drake.suf.live_suf_system import SUF_REQUEST_SIZE, LiveSufSystem, slot_at
from pedi_drake.suf.warm_projection import WarmStart

DESIGNS = ("none", "unrestricted", "one_tick", "slices", "thread")
# Nice value of the prototype's worker thread: below the control loop's share of the CPU.
WORKER_NICE = 10
# The mission manager's period [s] (the replay's ticks are grouped by their place in it).
MANAGER_PERIOD = 0.01


def _lower_priority() -> None:
    os.setpriority(os.PRIO_PROCESS, threading.get_native_id(), WORKER_NICE)


def _advance_whole(live, work: LiveSufWorkspace) -> np.ndarray:
    live.advance(work)
    return work.result.copy()


class ThreadedLiveSuf(LiveSufSystem):
    """The worker-thread design (see the module docstring): a prototype for this benchmark. The
    update handed over is kept on the workspace (`pending`), which the worker changes meanwhile."""

    def __init__(self, prongs, *, mu, period, offset, tick, tick_work, max_lps=DEFAULT_MAX_LPS):
        super().__init__(prongs, mu=mu, period=period, offset=offset, tick=tick, tick_work=math.inf, max_lps=max_lps)
        self._worker = concurrent.futures.ThreadPoolExecutor(max_workers=1, initializer=_lower_priority)

    def _on_tick(self, context, discrete_state) -> None:
        # Only the start slots: the whole update runs on the worker.
        if slot_at(context.get_time(), *self._schedule) != "start":
            return
        work = context.get_abstract_state(self._workspace).get_value()
        pending = getattr(work, "pending", None)
        previous = np.array(context.get_discrete_state(self._suf).get_value())
        if pending is not None:
            previous = pending.result()  # handed over a period ago; waits if it is still running
            discrete_state.get_mutable_vector(self._suf).SetFromVector(previous)
            work.pending = None
        if not self._start_update(context, work, previous):
            if pending is None:
                discrete_state.get_mutable_vector(self._suf).SetFromVector(idle_vector(previous))
            return
        work.pending = self._worker.submit(_advance_whole, self._live, work)


@dataclasses.dataclass(frozen=True)
class _WarmValue:
    """UnrestrictedLiveSuf's abstract state: the warm start of its next update, a value."""

    warm: WarmStart | None = None

    def __deepcopy__(self, memo) -> "_WarmValue":
        return self  # a value: an update stores a new one


class UnrestrictedLiveSuf(LeafSystem):
    """The live SUF before its work was spread over ticks (see the module docstring): a copy kept
    for this benchmark, with the shipped system's ports."""

    def __init__(self, prongs, *, mu, period, offset, tick, tick_work, max_lps=DEFAULT_MAX_LPS):
        super().__init__()
        self._live = LiveSuf(prongs, mu=mu, max_lps=max_lps)
        self._base_state = self.DeclareVectorInputPort("base_state", BASE_STATE_SIZE)
        self._position = self.DeclareVectorInputPort("position_measured", 12)
        self._contacts = self.DeclareVectorInputPort("contact_set", self._live.num_contacts)
        self._request = self.DeclareVectorInputPort("suf_request", SUF_REQUEST_SIZE)
        self._memory = self.DeclareAbstractState(AbstractValue.Make(_WarmValue()))
        self._suf = self.DeclareDiscreteState(idle_vector())
        self.DeclarePeriodicUnrestrictedUpdateEvent(period, offset, self._slice)
        self.DeclareStateOutputPort("suf", self._suf)

    def _slice(self, context, state) -> None:
        request = np.asarray(self._request.Eval(context))
        previous = context.get_discrete_state(self._suf).get_value()
        leg = int(round(request[0]))
        if leg < 0:
            state.get_mutable_discrete_state(self._suf).SetFromVector(idle_vector(previous))
            return
        memory = context.get_abstract_state(self._memory).get_value()
        vector, warm = self._live.update(
            memory.warm,
            previous,
            np.asarray(self._base_state.Eval(context)),
            np.asarray(self._position.Eval(context)),
            np.asarray(self._contacts.Eval(context)),
            leg,
            request[1:4],
        )
        state.get_mutable_discrete_state(self._suf).SetFromVector(vector)
        state.get_mutable_abstract_state(self._memory).set_value(_WarmValue(warm))


# The live SUF system each design builds (None: the shipped one) and its scenario text.
_DESIGN_SETUP = {
    "none": (None, "{live_suf: {enabled: false}}"),
    "unrestricted": (UnrestrictedLiveSuf, "{}"),
    "one_tick": (None, "{live_suf: {tick_work: 1.0e+9}}"),
    "slices": (None, "{}"),
    "thread": (ThreadedLiveSuf, "{}"),
}


@contextlib.contextmanager
def _design(name: str):
    """(scenario text) with the diagram building the live SUF of design `name`."""
    system, scenario_text = _DESIGN_SETUP[name]
    original = diagram_module.LiveSufSystem
    if system is not None:
        diagram_module.LiveSufSystem = system
    try:
        yield scenario_text
    finally:
        diagram_module.LiveSufSystem = original


@contextlib.contextmanager
def _handler_timer(ticks: int):
    """While active, the live SUF systems built get their handler timed in the loop thread's CPU
    time: yields {"suf": (ticks,) [ms], "tick": the running tick, set by Replay.run}."""
    times = {"suf": np.zeros(ticks), "tick": -1}
    handlers = ((LiveSufSystem, "_on_tick"), (ThreadedLiveSuf, "_on_tick"), (UnrestrictedLiveSuf, "_slice"))
    originals = [(cls, name, getattr(cls, name)) for cls, name in handlers]

    def timed(method):
        def wrapper(*args, **kwargs):
            start = time.thread_time()
            try:
                return method(*args, **kwargs)
            finally:
                if 0 <= times["tick"] < ticks:
                    times["suf"][times["tick"]] += 1e3 * (time.thread_time() - start)

        return wrapper

    for cls, name, method in originals:
        setattr(cls, name, timed(method))
    try:
        yield times
    finally:
        for cls, name, method in originals:
            setattr(cls, name, method)


def _percentiles(x_ms: np.ndarray) -> dict:
    return {
        "mean": float(np.mean(x_ms)),
        "p99": float(np.percentile(x_ms, 99)),
        "p99_9": float(np.percentile(x_ms, 99.9)),
        "max": float(np.max(x_ms)),
    }


def replay_designs(mission: str, runs: int, designs: list[str]) -> list[dict]:
    """The replayed ticks of each design, `runs` times (see the module docstring)."""
    period = 0.002
    samples, _ = record_status(mission, period)
    ticks = len(samples) - 1
    rows = []
    for run in range(runs):
        for design in designs:
            with _design(design) as scenario_text, _handler_timer(ticks) as times:
                replay = Replay(mission, period, samples, scenario_text=scenario_text)
                with hardware_run(replay.diagram, shutdown_damping_duration=0.0):
                    result = replay.run(ticks, times)
            phase = np.arange(ticks) % round(MANAGER_PERIOD / period)
            slices = times["suf"] > 0.0
            row = {
                "design": design,
                "run": run,
                "suf_cpu_ms": _percentiles(times["suf"]),
                "suf_cpu_ms_by_phase": {
                    f"{1e3 * period * p:.0f}ms": _percentiles(times["suf"][slices & (phase == p)])
                    for p in np.unique(phase)
                    if np.any(slices & (phase == p))
                },
                "tick_cpu_ms_by_phase": {
                    f"{1e3 * period * p:.0f}ms": _percentiles(result["cpu_ms"][phase == p]) for p in np.unique(phase)
                },
                "tick_ms": _percentiles(result["tick_ms"]),
                "tick_cpu_ms": _percentiles(result["cpu_ms"]),
                "load": Path("/proc/loadavg").read_text().split()[:3] if Path("/proc/loadavg").exists() else None,
            }
            rows.append(row)
            suf, tick, cpu = row["suf_cpu_ms"], row["tick_ms"], row["tick_cpu_ms"]
            phases = " ".join(
                f"{name} {value['mean']:.3f}/{value['p99']:.3f}" for name, value in row["tick_cpu_ms_by_phase"].items()
            )
            handler = " ".join(
                f"{name} {value['mean']:.3f}/{value['p99']:.3f}" for name, value in row["suf_cpu_ms_by_phase"].items()
            )
            print(
                f"{design:<12} run {run}: SUF handler CPU mean {suf['mean']:.3f} p99 {suf['p99']:.3f} max "
                f"{suf['max']:.3f}; tick CPU p99.9 {cpu['p99_9']:.3f} max {cpu['max']:.2f}, wall p99.9 "
                f"{tick['p99_9']:.3f} max {tick['max']:.2f}; tick CPU mean/p99 by phase: {phases}; the SUF "
                f"handler's where it ran: {handler} [ms]; "
                f"load {row['load']}",
                flush=True,
            )
    return rows


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--mission", default="hit_target_front")
    parser.add_argument("--runs", type=int, default=2)
    parser.add_argument("--designs", nargs="+", default=list(DESIGNS), choices=DESIGNS)
    parser.add_argument("--work", default="out/suf_offload", help="folder of the runs' outputs")
    parser.add_argument("--out", default="benchmarks/results/suf_offload.json")
    parser.add_argument("--replay", action="store_true", help="replayed ticks, unpaced (see above)")
    args = parser.parse_args()
    if args.replay:
        rows = replay_designs(args.mission, args.runs, args.designs)
        out = Path(args.out)
        out.parent.mkdir(parents=True, exist_ok=True)
        out.write_text(json.dumps({"mission": args.mission, "mode": "replay", "runs": rows}, indent=2))
        print(f"wrote {out}")
        return
    rows = []
    for run in range(args.runs):
        for design in args.designs:
            with _design(design) as scenario_text:
                row = one_run(args.mission, "default", Path(args.work) / f"{design}_{run}", scenario_text)
            row["design"] = design
            rows.append(row)
            late, suf = row["lateness_ms"], row["live_suf"] or {}
            print(
                f"{design:<12} run {run}: {'ok  ' if row['success'] else 'FAIL'} misses "
                f"{row['deadline_misses_per_1000']:.2f}/1000 (longest {row['longest_miss_ms']:.1f} ms), lateness "
                f"p99 {late['p99']:.2f} max {late['max']:.2f} ms, SUF ticks median {suf.get('ticks_median')} max "
                f"{suf.get('ticks_max')}, load {row['load_before']} -> {row['load_after']}",
                flush=True,
            )
    print(f"{'design':<13}{'successes':>10}{'misses/1000':>22}{'longest miss [ms]':>19}{'SUF ticks max':>15}")
    summary = {}
    for design in args.designs:
        mine = [row for row in rows if row["design"] == design]
        rates = [row["deadline_misses_per_1000"] for row in mine]
        summary[design] = {
            "successes": sum(row["success"] for row in mine),
            "runs": len(mine),
            "misses_per_1000": rates,
            "longest_miss_ms": max(row["longest_miss_ms"] for row in mine),
            "suf_ticks_max": max((row["live_suf"] or {}).get("ticks_max") or 0 for row in mine),
        }
        row = summary[design]
        successes = f"{row['successes']}/{row['runs']}"
        print(
            f"{design:<13}{successes:>10}{', '.join(f'{r:.2f}' for r in rates):>22}"
            f"{row['longest_miss_ms']:19.1f}{row['suf_ticks_max']:15d}"
        )
    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    machine = {"processor": platform.processor() or platform.machine(), "cpus": os.cpu_count()}
    report = {"mission": args.mission, "machine": machine, "summary": summary, "runs": rows}
    out.write_text(json.dumps(report, indent=2))
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
