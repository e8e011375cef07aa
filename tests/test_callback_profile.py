"""pedi_drake.measuring.callback_profile: what a run at real time keeps to explain its late ticks."""

import gc
import mmap
import time

import numpy as np
from pydrake.systems.analysis import Simulator
from pydrake.systems.framework import DiagramBuilder, LeafSystem

from pedi_drake.measuring.callback_profile import slow_calls

PERIOD = 0.002  # [s]
SLOW_AT = 0.010  # [s] the tick whose update computes for BUSY
COLLECT_AT = 0.020  # [s] the tick whose update runs a full collection over a large heap
BUSY = 0.010  # [s] of CPU time
FRESH_PAGES = 256  # pages of new memory the slow update touches (4 KiB each)


class _Ticker(LeafSystem):
    def __init__(self):
        super().__init__()
        self.DeclareDiscreteState(1)
        self.DeclarePeriodicDiscreteUpdateEvent(PERIOD, 0.0, self._update)

    def _update(self, context, discrete_state) -> None:
        t = context.get_time()
        if abs(t - SLOW_AT) < 1e-9:
            # A mapping of its own: every page is new to the process, a fault at its first touch.
            with mmap.mmap(-1, FRESH_PAGES * mmap.PAGESIZE) as fresh:
                np.frombuffer(fresh, dtype=np.uint8)[:: mmap.PAGESIZE] = 1
            end = time.thread_time() + BUSY
            while time.thread_time() < end:
                pass
        if abs(t - COLLECT_AT) < 1e-9:
            gc.collect()
        discrete_state.get_mutable_vector().SetAtIndex(0, context.get_discrete_state_vector()[0] + 1)


def test_the_slow_call_and_the_collection_are_kept_with_their_diagram_time():
    # A heap a full collection takes milliseconds to walk (kept alive through the run).
    heap = [[k] for k in range(400_000)]
    with slow_calls(threshold=0.002) as record:
        builder = DiagramBuilder()
        builder.AddNamedSystem("ticker", _Ticker())
        simulator = Simulator(builder.Build())
        simulator.AdvanceTo(0.03)
    calls = [(t, key) for t, key, *_ in record.calls]
    assert (SLOW_AT, "_Ticker PeriodicDiscreteUpdate") in [(round(t, 6), key) for t, key in calls]
    slow = next(call for call in record.calls if round(call[0], 6) == SLOW_AT)
    assert slow[2] >= 1e3 * BUSY
    # The faults counted are the loop thread's, in this call (the first touch of each page).
    assert FRESH_PAGES <= slow[4] < FRESH_PAGES + 50
    # The collection's own time is not the update's: the update over it is kept too, with its time.
    collections = [(round(t, 6), generation) for t, generation, _ in record.collections]
    assert (COLLECT_AT, 2) in collections
    summary = record.summary(count=1)
    assert summary["costliest_calls"][0]["callback"] == "_Ticker PeriodicDiscreteUpdate"
    assert summary["calls_over_threshold"] == len(record.calls)
    assert len(heap) == 400_000


def test_calls_under_the_threshold_are_not_kept():
    with slow_calls(threshold=1.0) as record:
        builder = DiagramBuilder()
        builder.AddNamedSystem("ticker", _Ticker())
        simulator = Simulator(builder.Build())
        simulator.AdvanceTo(0.012)
    # The busy tick's 10 ms is under a 1 s threshold.
    assert record.calls == []
    assert record.last_time is not None and record.last_time <= 0.012
