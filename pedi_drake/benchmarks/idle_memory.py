"""What touching memory costs after it lay idle: the first touch of a page a loop has not used for a while.

    python -m pedi_drake.benchmarks.idle_memory [--megabytes 256] [--idle 0.002 0.5 5 20]
        [--rounds 2] [--out benchmarks/results/idle_memory.json]

A buffer of `--megabytes` is written once (every page is the process's own from then on), then,
for each `--idle` time [s], left alone that long and written again one byte a page, each write
timed. The process takes no page fault in those writes (counted: `page_faults`), so on bare metal
each costs what a cached or main-memory write costs, well under a microsecond. Under a hypervisor
that takes back memory its guest has not touched lately, a write to such a page waits for the
host to give it back, and the guest charges that wait to the writing thread as its CPU time: a
loop that returns to code or data it left seconds ago (a mission's next phase) computes slowly
for as long as that takes. Per idle time: the writes over 10 us and over 100 us per 100 MB, the
longest, and the whole pass's wall and CPU time.
"""

import argparse
import json
import mmap
import platform
import resource
import time
from pathlib import Path

import numpy as np

SLOW = 10e-6  # [s] a write counted as slow
VERY_SLOW = 100e-6  # [s]


def _faults() -> int:
    usage = resource.getrusage(resource.RUSAGE_SELF)
    return usage.ru_minflt + usage.ru_majflt


def timed_pass(pages: np.ndarray, times: np.ndarray) -> None:
    """Writes one byte of each page of `pages` (a uint8 view, one row a page), each write's time
    [s] into `times` (made before the pass, so that the pass touches no memory new to it)."""
    clock = time.perf_counter
    for k in range(len(pages)):
        start = clock()
        pages[k, 0] += 1
        times[k] = clock() - start


def run(megabytes: int, idle_times: list[float], rounds: int) -> list[dict]:
    """One row per (idle time, round): what the pass after that idle time cost."""
    # A mapping of its own, in pages of the base size (numpy would ask for huge pages for an array
    # this large, which the host may treat otherwise).
    buffer = mmap.mmap(-1, megabytes << 20)
    pages = np.frombuffer(buffer, dtype=np.uint8).reshape(-1, mmap.PAGESIZE)
    pages[:, 0] = 1  # every page the process's own before any pass is timed
    times = np.full(len(pages), 0.0)  # written, so that its pages are the process's too
    per_100mb = 100 / megabytes
    rows = []
    for idle in idle_times:
        for round_index in range(rounds):
            time.sleep(idle)
            faults, cpu, wall = _faults(), time.process_time(), time.perf_counter()
            timed_pass(pages, times)
            wall, cpu = time.perf_counter() - wall, time.process_time() - cpu
            rows.append(
                {
                    "idle_s": idle,
                    "round": round_index,
                    "pages": len(pages),
                    "page_faults": _faults() - faults,
                    "slow_per_100mb": per_100mb * int(np.count_nonzero(times > SLOW)),
                    "very_slow_per_100mb": per_100mb * int(np.count_nonzero(times > VERY_SLOW)),
                    "longest_ms": 1e3 * float(times.max()),
                    "median_us": 1e6 * float(np.median(times)),
                    "pass_wall_ms": 1e3 * wall,
                    "pass_cpu_ms": 1e3 * cpu,
                }
            )
    del pages  # the view, before the mapping it points into is closed
    buffer.close()
    return rows


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--megabytes", type=int, default=256)
    parser.add_argument("--idle", type=float, nargs="+", default=[0.002, 0.5, 5.0, 20.0], help="idle times [s]")
    parser.add_argument("--rounds", type=int, default=2, help="passes after each idle time")
    parser.add_argument("--out", default="benchmarks/results/idle_memory.json")
    args = parser.parse_args()
    if args.megabytes < 1 or args.rounds < 1 or any(idle < 0 for idle in args.idle):
        parser.error("--megabytes and --rounds must be at least 1, --idle times not negative")
    rows = run(args.megabytes, args.idle, args.rounds)
    print(f"{args.megabytes} MB written one byte a page after each idle time")
    print(
        f"{'idle [s]':>9} {'faults':>7} {'>10us/100MB':>12} {'>100us/100MB':>13} {'longest [ms]':>13} "
        f"{'median [us]':>12} {'pass wall/CPU [ms]':>19}"
    )
    for row in rows:
        print(
            f"{row['idle_s']:9.3f} {row['page_faults']:7d} {row['slow_per_100mb']:12.1f} "
            f"{row['very_slow_per_100mb']:13.1f} {row['longest_ms']:13.3f} {row['median_us']:12.3f} "
            f"{row['pass_wall_ms']:9.1f}/{row['pass_cpu_ms']:.1f}"
        )
    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    result = {"machine": platform.machine(), "megabytes": args.megabytes, "rows": rows}
    out.write_text(json.dumps(result, indent=2))
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
