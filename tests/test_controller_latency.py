"""The controller-latency benchmark's report of its costliest ticks."""

import numpy as np

from pedi_drake.benchmarks.controller_latency import costliest_ticks


def test_costliest_ticks_in_a_window_name_the_callbacks_that_took_the_time():
    cpu_ms = np.array([0.3, 2.0, 0.4, 0.9, 0.5, 0.2])
    times = {
        "tick": 5,
        "A update": np.array([0.1, 1.5, 0.2, 0.01, 0.3, 0.1]),
        "B publish": np.array([0.1, 0.3, 0.1, 0.8, 0.1, 0.05]),
    }
    rows = costliest_ticks(times, cpu_ms, period=0.002, window=(0.004, 0.010), count=2)
    # Tick 1 (the run's costliest) is before the window; ticks 3 and 4 are its costliest, in time order.
    assert [row["t"] for row in rows] == [0.006, 0.008]
    assert rows[0]["cpu_ms"] == 0.9
    assert rows[0]["callbacks_ms"] == {"B publish": 0.8}  # A's 10 us is under the 20 us shown
    assert list(rows[1]["callbacks_ms"]) == ["A update", "B publish"]
    assert [row["t"] for row in costliest_ticks(times, cpu_ms, 0.002, None, count=1)] == [0.002]
