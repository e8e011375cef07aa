"""Timing a diagram's Python callbacks: which system's handler or output took a loop's time.

Drake calls a Python system's event handlers and output calculations through the callbacks it was
given when the system declared them. While `wrapped_callbacks(wrap)` is active, every callback
declared through one of DECLARATIONS (by any LeafSystem built meanwhile) is replaced by
`wrap(key, callback)`, key naming the system's class and the port or event kind ("MissionManager
references", "WholeBodyController PeriodicDiscreteUpdate"): build the diagram inside it.

`slow_calls(threshold)` uses it to keep only what a run at real time needs to explain its late
ticks: every call that took more than `threshold` of the loop thread's CPU time, with the diagram
time it ran at and the page faults the loop thread took in it, and every garbage collection that
took more than `threshold` of wall time. A call costs a microsecond or two more timed; nothing is
kept for the calls under the threshold.
(`pedi_drake.benchmarks.controller_latency --callbacks` times every call of a replay, tick by tick.)
"""

import contextlib
import dataclasses
import gc
import resource
import time
from collections.abc import Callable

from pydrake.systems.framework import LeafSystem

# LeafSystem declarations whose callback is wrapped: (position, keyword) of the callback argument.
DECLARATIONS = {
    "DeclareVectorOutputPort": (2, "calc"),
    "DeclareAbstractOutputPort": (2, "calc"),
    "DeclarePeriodicDiscreteUpdateEvent": (2, "update"),
    "DeclarePeriodicUnrestrictedUpdateEvent": (2, "update"),
    "DeclarePeriodicPublishEvent": (2, "publish"),
}


@contextlib.contextmanager
def wrapped_callbacks(wrap: Callable[[str, Callable], Callable]):
    """While active, the callbacks of DECLARATIONS are declared as `wrap(key, callback)`."""

    def declaring(method: str, declare):
        position, keyword = DECLARATIONS[method]
        what = method.removeprefix("Declare").removesuffix("Event")

        def declare_wrapped(system, *args, **kwargs):
            label = args[0] if method.endswith("OutputPort") else what
            key = f"{type(system).__name__} {label}"
            if len(args) > position and callable(args[position]):
                args = (*args[:position], wrap(key, args[position]), *args[position + 1 :])
            elif callable(kwargs.get(keyword)):
                kwargs[keyword] = wrap(key, kwargs[keyword])
            return declare(system, *args, **kwargs)

        return declare_wrapped

    originals = {method: getattr(LeafSystem, method) for method in DECLARATIONS}
    for method, declare in originals.items():
        setattr(LeafSystem, method, declaring(method, declare))
    try:
        yield
    finally:
        for method, declare in originals.items():
            setattr(LeafSystem, method, declare)


@dataclasses.dataclass
class SlowCalls:
    """What `slow_calls` kept: calls [(t [s], key, CPU ms, wall ms, page faults)] and collections
    [(t [s] of the last call before it, or None before any call, generation, wall ms)]."""

    threshold_s: float
    calls: list[tuple[float, str, float, float, int]] = dataclasses.field(default_factory=list)
    collections: list[tuple[float | None, int, float]] = dataclasses.field(default_factory=list)
    # The diagram time of the last call that started: when a collection ran (None: before any call,
    # while the diagram was built).
    last_time: float | None = None

    def summary(self, count: int = 20) -> dict:
        """The `count` costliest calls (by CPU time) and collections, for a result file."""
        calls = sorted(self.calls, key=lambda call: -call[2])[:count]
        collections = sorted(self.collections, key=lambda collection: -collection[2])[:count]
        return {
            "threshold_ms": 1e3 * self.threshold_s,
            "calls_over_threshold": len(self.calls),
            "costliest_calls": [
                {"t": t, "callback": key, "cpu_ms": cpu, "wall_ms": wall, "page_faults": faults}
                for t, key, cpu, wall, faults in calls
            ],
            "collections_over_threshold": len(self.collections),
            "longest_collections": [
                {"t": t, "generation": generation, "wall_ms": wall} for t, generation, wall in collections
            ],
        }


@contextlib.contextmanager
def slow_calls(threshold: float):
    """While active, systems built get their callbacks timed, and collections are watched: yields
    the SlowCalls that fills as the diagram runs. Build and run the diagram inside it. `threshold` [s]."""
    record = SlowCalls(threshold)
    clock, cpu_clock = time.perf_counter, time.thread_time

    def thread_faults() -> int:
        # Minor and major: a first touch of memory the hypervisor had taken back is a minor fault
        # that can cost a loop more than its computation.
        usage = resource.getrusage(resource.RUSAGE_THREAD)
        return usage.ru_minflt + usage.ru_majflt

    def wrap(key: str, callback):
        def timed(*args, **kwargs):
            context = args[0]
            record.last_time = context.get_time()
            faults_start, cpu_start, wall_start = thread_faults(), cpu_clock(), clock()
            try:
                return callback(*args, **kwargs)
            finally:
                cpu = cpu_clock() - cpu_start
                if cpu > threshold:
                    wall = clock() - wall_start
                    faults = thread_faults() - faults_start
                    record.calls.append((record.last_time, key, 1e3 * cpu, 1e3 * wall, faults))

        return timed

    collection_start = [0.0]

    def on_collection(phase: str, info: dict) -> None:
        if phase == "start":
            collection_start[0] = clock()
            return
        elapsed = clock() - collection_start[0]
        if elapsed > threshold:
            record.collections.append((record.last_time, int(info["generation"]), 1e3 * elapsed))

    gc.callbacks.append(on_collection)
    try:
        with wrapped_callbacks(wrap):
            yield record
    finally:
        gc.callbacks.remove(on_collection)
