"""The machine's own floor for a wall-clock loop: how late a 2 ms loop of fixed work runs.

    python -m pedi_drake.benchmarks.wake_latency [--seconds 60] [--period 0.002] [--work 0]
        [--priority 50] [--load 2] [--out benchmarks/results/wake_latency.json]

A thread sleeps until its next deadline (k x period on the monotonic clock), as the driver's loop
does between ticks, then does `--work` ms of fixed pure computation (none by default), and
records when the tick ended; its lateness is measured as the driver's report measures a
command's, against the earliest tick so far. Whatever makes it late is the machine's (the
kernel, other processes, the hypervisor under a virtual machine), not this project's code, so
its misses are a baseline for the driver's: `sil_floors` counts a command later than one period
as a deadline miss, and so does this. Four conditions, `--seconds` each: normal scheduling and SCHED_FIFO
`--priority`, each alone and beside `--load` processes that compute without pause at normal
priority (a compiler, a browser, a second simulation).

Per condition: ticks, misses per 1000 (later than a period), ticks later than 5 ms per minute,
the lateness (median, p99.9, longest), the CPU time the thread was charged for the fixed work
(the same every tick on a machine that gives the thread its core; a tick charged much more is
time the thread's clock counted but the work did not need), and the CPU time the hypervisor
reports it took from this machine's cores meanwhile (`steal` in /proc/stat; 0 on bare metal).
Without the right to raise priority (root, CAP_SYS_NICE or `ulimit -r`) the SCHED_FIFO
conditions are reported as refused.
"""

import argparse
import json
import math
import multiprocessing
import os
import platform
import time
from pathlib import Path

import numpy as np

from pedi_drake.benchmarks.machine import stamped
from pedi_drake.go1_driver.link import distribution_ms, lateness_against_earliest
from pedi_drake.measuring.cpu_steal import steal_seconds
from pedi_drake.runtime.realtime_priority import realtime_priority

LATE_REPORTED = 0.005  # [s] lateness counted per minute


def _busy() -> None:
    while True:
        pass


def spin(iterations: int) -> int:
    """A fixed amount of pure computation (no memory traffic to speak of, no system calls)."""
    total = 0
    for i in range(iterations):
        total += i
    return total


def iterations_for(seconds: float) -> int:
    """How many `spin` iterations take `seconds` of CPU time on this machine now (best of five)."""
    if seconds <= 0.0:
        return 0
    trial = 100_000
    best = math.inf
    for _ in range(5):
        start = time.thread_time()
        spin(trial)
        best = min(best, time.thread_time() - start)
    return max(1, int(trial * seconds / best))


def paced_loop(seconds: float, period: float, work_iterations: int = 0) -> dict[str, np.ndarray]:
    """Sleeps to each deadline k x `period` for `seconds`, then computes `work_iterations` of `spin`.

    Returns per tick [s]: `lateness` (the end of the tick's work against its deadline, the
    driver's measure of a command's departure), `work_cpu` and `work_wall` (the thread's CPU time
    and the wall time of the fixed work: on a machine that gives the thread its core, they are
    equal and the same every tick). A tick later than the next deadline is followed straight
    away by the next (as a paced simulator catches up), so one long stall is one late tick
    followed by on-time ones.
    """
    lateness, work_cpu, work_wall = [], [], []
    start = time.monotonic()
    k = 1
    while True:
        deadline = start + k * period
        now = time.monotonic()
        if deadline > now:
            time.sleep(deadline - now)
        cpu, wall = time.thread_time(), time.monotonic()
        spin(work_iterations)
        now = time.monotonic()
        work_cpu.append(time.thread_time() - cpu)
        work_wall.append(now - wall)
        lateness.append(now - deadline)
        if now - start >= seconds:
            return {
                "lateness": np.asarray(lateness),
                "work_cpu": np.asarray(work_cpu),
                "work_wall": np.asarray(work_wall),
            }
        # The next deadline not yet passed: the loop does not replay the ticks it slept through.
        k = max(k + 1, int((now - start) / period) + 1)


def condition(seconds: float, period: float, priority: int, load: int, work_iterations: int = 0) -> dict:
    """One condition: the paced loop at `priority` (0: normal) beside `load` busy processes."""
    busy = [multiprocessing.Process(target=_busy, daemon=True) for _ in range(load)]
    for process in busy:
        process.start()
    try:
        time.sleep(0.5 if load else 0.0)  # the load running before the clock starts
        steal = steal_seconds() or 0.0
        with realtime_priority(priority, who="wake_latency") as scheduling:
            if scheduling.startswith("refused"):
                return {"priority": priority, "load": load, "scheduling": scheduling}
            ticks = paced_loop(seconds, period, work_iterations)
        steal = (steal_seconds() or 0.0) - steal
    finally:
        for process in busy:
            process.terminate()
            process.join()
    minutes = seconds / 60.0
    # As the driver's report measures a command's lateness.
    lateness = lateness_against_earliest(ticks["lateness"])
    misses = int(np.count_nonzero(lateness > period))
    return {
        "priority": priority,
        "load": load,
        "scheduling": scheduling,
        "ticks": len(lateness),
        "misses_per_1000": 1000.0 * misses / len(lateness),
        "late_over_5ms_per_minute": float(np.count_nonzero(lateness > LATE_REPORTED)) / minutes,
        "lateness_ms": distribution_ms(lateness),
        "work_cpu_ms": distribution_ms(ticks["work_cpu"]),
        "work_wall_ms": distribution_ms(ticks["work_wall"]),
        "steal_ms_per_minute": 1e3 * steal / minutes,
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--seconds", type=float, default=60.0, help="[s] per condition")
    parser.add_argument("--period", type=float, default=0.002, help="[s] the loop's period")
    parser.add_argument("--work", type=float, default=0.0, help="[ms] of fixed computation a tick (0: an empty loop)")
    parser.add_argument("--priority", type=int, default=50, help="SCHED_FIFO priority of the real-time conditions")
    parser.add_argument("--load", type=int, default=os.cpu_count() or 1, help="busy processes beside the loop")
    parser.add_argument("--out", default="benchmarks/results/wake_latency.json")
    args = parser.parse_args()
    work_iterations = iterations_for(1e-3 * args.work)
    report = {
        "machine": platform.machine(),
        "cores": os.cpu_count(),
        "load_at_start": os.getloadavg(),
        "seconds": args.seconds,
        "period_s": args.period,
        "work_ms": args.work,
        "work_iterations": work_iterations,
        "conditions": [],
    }
    what = f"{args.work:g} ms of fixed computation a tick" if args.work > 0 else "nothing a tick"
    load = os.getloadavg()[0]
    print(f"a {1e3 * args.period:g} ms loop doing {what}, {args.seconds:g} s per condition, load average {load:.2f}")
    print(
        f"{'scheduling':<20}{'busy':>5}{'ticks':>7}{'miss/1000':>10}{'>5 ms/min':>10}{'late med':>9}"
        f"{'p99.9':>7}{'max':>6}{'work CPU med':>13}{'max':>6}{'steal/min':>10}"
    )
    for priority in (0, args.priority):
        for load in (0, args.load):
            row = condition(args.seconds, args.period, priority, load, work_iterations)
            report["conditions"].append(row)
            if "ticks" not in row:
                print(f"{row['scheduling']:<20}{load:>5}  (not measured)")
                continue
            late, cpu = row["lateness_ms"], row["work_cpu_ms"]
            print(
                f"{row['scheduling']:<20}{load:>5}{row['ticks']:>7}{row['misses_per_1000']:>10.2f}"
                f"{row['late_over_5ms_per_minute']:>10.1f}{late['median']:>9.3f}{late['p99_9']:>7.2f}{late['max']:>6.1f}"
                f"{cpu['median']:>13.3f}{cpu['max']:>6.2f}{row['steal_ms_per_minute']:>10.0f}"
            )
    print("(lateness and work CPU in ms; steal: ms of the cores' time the hypervisor took per minute)")
    report["load_at_end"] = os.getloadavg()
    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(json.dumps(stamped(report), indent=2))
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
