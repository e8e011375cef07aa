"""The machine's own floor for a wall-clock loop: how late an empty 2 ms loop wakes.

    python -m pedi_drake.benchmarks.wake_latency [--seconds 60] [--period 0.002] [--priority 50]
        [--load 2] [--out benchmarks/results/wake_latency.json]

A thread does nothing but sleep until its next deadline (k x period on the monotonic clock),
as the driver's loop does between ticks, and records how late it woke. Whatever makes it late is
the machine's (the kernel, other processes, the hypervisor under a virtual machine), not this
project's code, so its misses are a baseline for the driver's: `sil_floors` counts a tick late by
more than one period as a deadline miss, and so does this. Four conditions, `--seconds` each:
normal scheduling and SCHED_FIFO `--priority`, each alone and beside `--load` processes that
compute without pause at normal priority (a compiler, a browser, a second simulation).

Per condition: wakes, misses per 1000 (late by more than a period), wakes late by more than
5 ms per minute, the longest lateness, and the CPU time the hypervisor reports it took from this
machine's cores meanwhile (`steal` in /proc/stat; 0 on bare metal). Without the right to raise
priority (root, CAP_SYS_NICE or `ulimit -r`) the SCHED_FIFO conditions are reported as refused.
"""

import argparse
import json
import multiprocessing
import os
import platform
import time
from pathlib import Path

import numpy as np

from pedi_drake.realtime_priority import realtime_priority

LATE_REPORTED = 0.005  # [s] lateness counted per minute


def _busy() -> None:
    while True:
        pass


def _steal_seconds() -> float:
    """Steal time of all cores so far [s] (/proc/stat; 0 where there is none)."""
    path = Path("/proc/stat")
    if not path.exists():
        return 0.0
    fields = path.read_text().splitlines()[0].split()
    return int(fields[8]) / os.sysconf("SC_CLK_TCK") if len(fields) > 8 else 0.0


def empty_loop(seconds: float, period: float) -> np.ndarray:
    """Sleeps to each deadline k x `period` for `seconds`; returns each wake's lateness [s].

    A wake later than the next deadline goes straight on (as a paced simulator catches up), so
    one long stall is one late wake followed by on-time ones.
    """
    lateness = []
    start = time.monotonic()
    k = 1
    while True:
        deadline = start + k * period
        now = time.monotonic()
        if deadline > now:
            time.sleep(deadline - now)
            now = time.monotonic()
        lateness.append(now - deadline)
        if now - start >= seconds:
            return np.asarray(lateness)
        # The next deadline not yet passed: the loop does not replay the ticks it slept through.
        k = max(k + 1, int((now - start) / period) + 1)


def condition(seconds: float, period: float, priority: int, load: int) -> dict:
    """One condition: the empty loop at `priority` (0: normal) beside `load` busy processes."""
    busy = [multiprocessing.Process(target=_busy, daemon=True) for _ in range(load)]
    for process in busy:
        process.start()
    try:
        time.sleep(0.5 if load else 0.0)  # the load running before the clock starts
        steal = _steal_seconds()
        with realtime_priority(priority, who="wake_latency") as scheduling:
            if scheduling.startswith("refused"):
                return {"priority": priority, "load": load, "scheduling": scheduling}
            lateness = empty_loop(seconds, period)
        steal = _steal_seconds() - steal
    finally:
        for process in busy:
            process.terminate()
            process.join()
    minutes = seconds / 60.0
    misses = int(np.count_nonzero(lateness > period))
    return {
        "priority": priority,
        "load": load,
        "scheduling": scheduling,
        "wakes": len(lateness),
        "misses_per_1000": 1000.0 * misses / len(lateness),
        "late_over_5ms_per_minute": float(np.count_nonzero(lateness > LATE_REPORTED)) / minutes,
        "lateness_ms": {
            "median": float(1e3 * np.median(lateness)),
            "p99_9": float(1e3 * np.percentile(lateness, 99.9)),
            "max": float(1e3 * lateness.max()),
        },
        "steal_ms_per_minute": 1e3 * steal / minutes,
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--seconds", type=float, default=60.0, help="[s] per condition")
    parser.add_argument("--period", type=float, default=0.002, help="[s] the loop's period")
    parser.add_argument("--priority", type=int, default=50, help="SCHED_FIFO priority of the real-time conditions")
    parser.add_argument("--load", type=int, default=os.cpu_count() or 1, help="busy processes beside the loop")
    parser.add_argument("--out", default="benchmarks/results/wake_latency.json")
    args = parser.parse_args()
    report = {
        "machine": platform.machine(),
        "cores": os.cpu_count(),
        "load_at_start": os.getloadavg(),
        "seconds": args.seconds,
        "period_s": args.period,
        "conditions": [],
    }
    load = os.getloadavg()[0]
    print(f"an empty {1e3 * args.period:g} ms loop, {args.seconds:g} s per condition, load average {load:.2f}")
    print(
        f"{'scheduling':<22}{'busy':>5}{'wakes':>8}{'miss/1000':>11}{'>5 ms/min':>11}"
        f"{'median ms':>11}{'p99.9 ms':>10}{'max ms':>8}{'steal ms/min':>14}"
    )
    for priority in (0, args.priority):
        for load in (0, args.load):
            row = condition(args.seconds, args.period, priority, load)
            report["conditions"].append(row)
            if "wakes" not in row:
                print(f"{row['scheduling']:<22}{load:>5}  (not measured)")
                continue
            lateness = row["lateness_ms"]
            print(
                f"{row['scheduling']:<22}{load:>5}{row['wakes']:>8}{row['misses_per_1000']:>11.2f}"
                f"{row['late_over_5ms_per_minute']:>11.1f}{lateness['median']:>11.3f}{lateness['p99_9']:>10.2f}"
                f"{lateness['max']:>8.1f}{row['steal_ms_per_minute']:>14.0f}"
            )
    report["load_at_end"] = os.getloadavg()
    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(json.dumps(report, indent=2))
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
