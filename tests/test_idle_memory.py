"""pedi_drake.benchmarks.idle_memory: the timed pass over a buffer's pages after an idle time."""

import mmap

from pedi_drake.benchmarks.idle_memory import run


def test_a_pass_writes_every_page_of_the_buffer_once_without_faulting_it_in():
    rows = run(megabytes=4, idle_times=[0.0, 0.01], rounds=1)
    assert [row["idle_s"] for row in rows] == [0.0, 0.01]
    for row in rows:
        assert row["pages"] == (4 << 20) // mmap.PAGESIZE
        # The pages are the process's own before the pass, and so is the array of times: the few
        # faults left are the interpreter's own first touches, not one per page of the buffer.
        assert row["page_faults"] < row["pages"] // 8
        assert 0.0 < row["median_us"] <= 1e3 * row["longest_ms"]
        assert row["very_slow_per_100mb"] <= row["slow_per_100mb"]
