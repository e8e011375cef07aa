"""The live SUF's update spread over control ticks: what each kind of step costs, and what one
control tick pays for a range of per-tick budgets.

    python -m pedi_drake.benchmarks.live_suf_slices [--steps 320] [--tick-work 1 2 3 5 inf]
        [--out benchmarks/results/live_suf_slices.json]

On pedi_drake.benchmarks.live_suf's teleoperated path (paper 003's teleoperation stance, the FR
foot once round an 8 cm square), three kinds of update:

* warm: each stance from the previous stance's warm start (a run's updates along a smooth motion);
* cold: each stance without a warm start (a run's first update after the contact set changed);
* fallback: cold, with a budget of FALLBACK_LPS LPs that runs out (the single-direction SUF).

Every call of `LiveSuf.advance` (what a control tick of a LiveSufSystem makes) is timed in the
CPU time of the calling thread:

1. Steps: every update done one step per call (a budget of almost nothing), each call grouped by
   the work it was charged [LP] (pedi_drake.suf.warm_projection: 0.1 a vertex's or a facet's
   check, 0.2 a point joined to the hull or the first tetrahedron, 1 an LP, and their sums), the
   first call of an update (the rows, live.ROWS_WORK) and the last (the finishing step) apart; a
   call with no budget at all gives what a call costs that does nothing. Each group's median
   beyond that call, over an LP's, is what that work should be charged: how the constants were
   chosen.
2. Slices: every update done in calls of `tick_work` each: the CPU time of one call (one tick's
   share; median, p99, max) and the calls one update takes (median, max). Every sliced update's
   vector and warm start are compared with those of the update done in one call (`same`: equal
   bit for bit, the `slices` counter aside).

Prints tables and writes JSON.
"""

import argparse
import json
import math
import platform
import time
from pathlib import Path

import numpy as np

from pedi_drake.benchmarks.live_suf import stance_state, teleoperated_path
from pedi_drake.suf.live import DEFAULT_MAX_LPS, LiveSuf, LiveSufWorkspace, idle_vector, without_timing

# A budget of LPs that a cold projection of the teleoperation stance (20 to 30 LPs) runs out of.
FALLBACK_LPS = 10
PUSH = np.array([-1.0, 0.0, 0.0])  # a wall ahead pushes the foot back
LOADED = np.array([0.0, 1.0, 1.0, 1.0])  # FR lifted
# A budget below any step's work: one step per call.
_ONE_STEP = 1e-9


def _updates(live: LiveSuf, stances, warm_chain: bool) -> list[dict]:
    """Each stance's update inputs and its one-call result (the reference of the sliced ones)."""
    updates = []
    warm, vector = None, idle_vector()
    for stance in stances:
        base, q = stance_state(stance)
        start = {"warm": warm if warm_chain else None, "previous": vector, "base": base, "q": q}
        vector, warm = live.update(start["warm"], vector, base, q, LOADED, 0, PUSH)
        updates.append({**start, "vector": vector, "next_warm": warm})
    return updates


def _start(live: LiveSuf, update: dict) -> LiveSufWorkspace:
    work = live.new_workspace()
    work.set_warm_start(update["warm"])
    live.start(work, update["previous"], update["base"], update["q"], LOADED, 0, PUSH)
    return work


def _timed_call(live: LiveSuf, work: LiveSufWorkspace, budget: float) -> tuple[float, float]:
    """(the work it was charged [LP], CPU [us]) of one tick's call."""
    start = time.thread_time_ns()
    charged = live.advance(work, budget)
    return charged, 1e-3 * (time.thread_time_ns() - start)


def _same(work: LiveSufWorkspace, update: dict) -> bool:
    if not np.array_equal(without_timing(work.result), without_timing(update["vector"]), equal_nan=True):
        return False
    mine, theirs = work.warm_start(), update["next_warm"]
    if mine is None or theirs is None:
        return mine is None and theirs is None
    return all(np.array_equal(getattr(mine, f), getattr(theirs, f)) for f in ("directions", "active", "num_active"))


def _distribution(x) -> dict:
    x = np.asarray(x, float)
    return {"median": float(np.median(x)), "p99": float(np.percentile(x, 99)), "max": float(np.max(x))}


def step_costs(live: LiveSuf, updates: list[dict]) -> dict:
    """CPU [us] per call by what it did (see the module docstring, 1)."""
    groups: dict[str, list[float]] = {"nothing": [], "rows": [], "finish": []}
    for update in updates:
        work = _start(live, update)
        _, elapsed = _timed_call(live, work, 0.0)
        groups["rows"].append(elapsed)
        _, elapsed = _timed_call(live, work, 0.0)
        groups["nothing"].append(elapsed)
        while work.under_way:
            charged, elapsed = _timed_call(live, work, _ONE_STEP)
            groups.setdefault("finish" if not work.under_way else f"{charged:.1f}", []).append(elapsed)
    return {
        name: {"calls": len(times), "median_us": float(np.median(times)), "p90_us": float(np.percentile(times, 90))}
        for name, times in sorted(groups.items())
        if times
    }


def slice_costs(live: LiveSuf, updates: list[dict], tick_work: float) -> dict:
    """One tick's CPU [us] and the ticks per update with `tick_work` per tick (see 2)."""
    ticks_us, calls, same = [], [], True
    for update in updates:
        work = _start(live, update)
        count = 0
        while work.under_way:
            _, elapsed = _timed_call(live, work, tick_work)
            ticks_us.append(elapsed)
            count += 1
        calls.append(count)
        same = same and _same(work, update)
    return {
        "tick_us": _distribution(ticks_us),
        "ticks_per_update": {"median": float(np.median(calls)), "max": int(np.max(calls))},
        "same": bool(same),
    }


def run(steps: int, tick_works: list[float]) -> dict:
    stances = teleoperated_path(steps)
    live = LiveSuf(mu=0.6)
    tight = LiveSuf(mu=0.6, max_lps=FALLBACK_LPS)
    kinds = {
        "warm": _updates(live, stances, warm_chain=True),
        "cold": _updates(live, stances, warm_chain=False),
        "fallback": _updates(tight, stances, warm_chain=False),
    }
    solvers = {"warm": live, "cold": live, "fallback": tight}
    report = {"steps": steps, "lp_budget": DEFAULT_MAX_LPS, "fallback_lp_budget": FALLBACK_LPS}
    report["step_cost"] = {kind: step_costs(solvers[kind], updates) for kind, updates in kinds.items()}
    report["slices"] = {
        kind: {str(work): slice_costs(solvers[kind], updates, work) for work in tick_works}
        for kind, updates in kinds.items()
    }
    report["machine"] = f"{platform.machine()}, Python {platform.python_version()}"
    return report


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--steps", type=int, default=320, help="configurations along the lap")
    parser.add_argument("--tick-work", type=float, nargs="+", default=[1.0, 2.0, 3.0, 5.0, math.inf])
    parser.add_argument("--out", default="benchmarks/results/live_suf_slices.json")
    args = parser.parse_args()
    load = Path("/proc/loadavg").read_text().split()[:3] if Path("/proc/loadavg").exists() else None
    report = run(args.steps, args.tick_work)
    report["loadavg_start"] = load
    print(f"{args.steps} stances along the teleoperated path; load average at the start {load}")
    print("1. CPU per call by the work it was charged [us] (median / p90; calls):")
    kinds = list(report["step_cost"])
    groups = sorted({g for kind in kinds for g in report["step_cost"][kind]})
    print(f"  {'charged [LP]':<14}" + "".join(f"{kind:>24}" for kind in kinds))
    for group in groups:
        cells = []
        for kind in kinds:
            row = report["step_cost"][kind].get(group)
            cells.append(f"{row['median_us']:8.1f} / {row['p90_us']:6.1f} ({row['calls']:5d})" if row else "")
        print(f"  {group:<14}" + "".join(f"{cell:>24}" for cell in cells))
    print("2. One tick's share, by the work a tick may do [us of CPU]; ticks an update takes:")
    print(f"  {'kind':<10}{'tick_work':>10}{'median':>9}{'p99':>9}{'max':>9}{'ticks med':>11}{'max':>5}{'same':>6}")
    for kind, rows in report["slices"].items():
        for work, row in rows.items():
            tick = row["tick_us"]
            print(
                f"  {kind:<10}{work:>10}{tick['median']:9.1f}{tick['p99']:9.1f}{tick['max']:9.1f}"
                f"{row['ticks_per_update']['median']:11.1f}{row['ticks_per_update']['max']:5d}{row['same']!s:>6}"
            )
    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(json.dumps(report, indent=2))
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
