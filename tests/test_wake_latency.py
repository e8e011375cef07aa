"""The machine-floor probe of benchmarks/wake_latency: an empty loop's lateness per deadline."""

import multiprocessing

import numpy as np
import pytest

from pedi_drake.benchmarks.wake_latency import condition, iterations_for, paced_loop


@pytest.mark.wall_clock
def test_the_empty_loop_wakes_once_per_deadline_and_reports_how_late():
    lateness = paced_loop(0.3, 0.01)["lateness"]
    # One wake per 10 ms deadline (a few fewer if the machine held the thread past some).
    assert 20 <= len(lateness) <= 31
    assert np.all(lateness >= 0.0)
    assert np.median(lateness) < 0.005


@pytest.mark.wall_clock
def test_a_condition_beside_a_busy_process_is_measured_and_the_process_stopped():
    row = condition(0.2, 0.01, priority=0, load=1, work_iterations=iterations_for(0.001))
    assert row["scheduling"] == "normal scheduling" and row["load"] == 1
    assert row["ticks"] >= 10
    # The fixed work was charged about the millisecond it was calibrated to.
    assert 0.3 < row["work_cpu_ms"]["median"] < 3.0
    assert 0.0 <= row["misses_per_1000"] <= 1000.0
    assert row["lateness_ms"]["max"] >= row["lateness_ms"]["median"] >= 0.0
    assert not multiprocessing.active_children()
