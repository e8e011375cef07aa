"""Batch engines: Ray's cost per task, and a study on Ray against the same study in one process.

    python -m pedi_drake.benchmarks.batch [--trivial 200] [--missions a,b | --missions all]
        [--noise-seeds 1,2,3,4,5] [--out benchmarks/results/batch.json]

1. Overhead: `--trivial` no-op tasks on a local Ray (every core) and serially; Ray's cost per
   task is (wall time on Ray x workers - serial wall time) / tasks, its scheduling and transport
   beyond the task's own work (the first task's worker start-up excluded: the engine is started
   before the clock).
2. Speed-up: the mission benchmark's study (every listed mission, seed 0 without noise and the
   noise seeds with it) on Ray and then serially, in one run, and whether the two give the
   same rows (every column but the timing ones). Where a speed-up below the number of workers
   comes from, from each task's own wall time in both engines:
   - `two_at_once_slowdown`: the median over tasks of (its wall time on Ray / in the serial run),
     what running beside another simulation costs each one (shared caches, memory bandwidth and
     whatever the host shares between this machine's cores), not Ray;
   - `packing`: the tasks' wall times on Ray summed, over workers x the study's wall time on Ray:
     1.0 when no worker ever waits (start-up, the last tasks' tail, Ray's own work).
   speed-up = workers x packing / slowdown, give or take the serial run's own overhead.
"""

import argparse
import json
import os
import platform
import tempfile
import time
from pathlib import Path

import numpy as np
import ray

from pedi_drake.batch.engines import RayEngine, SerialEngine
from pedi_drake.batch.runner import run_study
from pedi_drake.batch.study import study_from_dict
from pedi_drake.batch.tasks import TIMING_COLUMNS
from pedi_drake.benchmarks.machine import stamped
from pedi_drake.benchmarks.missions import mission_study
from pedi_drake.mission.spec import shipped_missions

RESULT_TIMING_KEYS = ("wall_time_s", "real_time_factor", "controller_tick_ms")


def deterministic(row: dict) -> dict:
    """A row without what depends on the machine's load (wall times, tick times, worker pid)."""
    row = {k: v for k, v in row.items() if k not in TIMING_COLUMNS}
    if "result" in row:
        row["result"] = {k: v for k, v in row["result"].items() if k not in RESULT_TIMING_KEYS}
    return row


def differing_fields(rows_a: list[dict], rows_b: list[dict]) -> dict[str, int]:
    """For each field (`result.<key>` inside a run's result) that differs between the two engines'
    `deterministic` rows of one task, the number of tasks where it differs; a task missing from
    one side counts under `task_id`."""
    a = {r["task_id"]: deterministic(r) for r in rows_a}
    b = {r["task_id"]: deterministic(r) for r in rows_b}
    counts: dict[str, int] = {}
    for task_id in sorted(set(a) | set(b)):
        if task_id not in a or task_id not in b:
            counts["task_id"] = counts.get("task_id", 0) + 1
            continue
        flat_a, flat_b = _flat(a[task_id]), _flat(b[task_id])
        for field in sorted(set(flat_a) | set(flat_b)):
            if flat_a.get(field) != flat_b.get(field):
                counts[field] = counts.get(field, 0) + 1
    return counts


def _flat(row: dict) -> dict:
    flat = {k: v for k, v in row.items() if k != "result"}
    flat.update({f"result.{k}": v for k, v in row.get("result", {}).items()})
    return flat


def timed_study(study, engine) -> tuple[float, list[dict]]:
    with tempfile.TemporaryDirectory() as folder:
        start = time.perf_counter()
        rows = run_study(study, Path(folder), engine, quiet=True).rows
        return time.perf_counter() - start, rows


def overhead(count: int) -> dict:
    # Distinct tasks (a task's id comes from its settings): durations of 0 s, made unique.
    study = study_from_dict(
        {
            "name": "trivial",
            "kind": "noop",
            "factors": [{"name": "duration_s", "values": [1e-9 * k for k in range(count)]}],
        },
        "trivial",
    )
    workers = os.cpu_count()
    ray.init(num_cpus=workers, include_dashboard=False, logging_level="ERROR", object_store_memory=200 * 2**20)
    try:
        timed_study(study, RayEngine())  # warm: every worker started and the function exported
        on_ray, _ = timed_study(study, RayEngine())
    finally:
        ray.shutdown()
    serial, _ = timed_study(study, SerialEngine())
    per_task = (on_ray * workers - serial) / count
    return {
        "tasks": count,
        "workers": workers,
        "ray_s": on_ray,
        "serial_s": serial,
        "ray_overhead_per_task_s": per_task,
    }


def speed_up(missions: list[str], seeds: list[int]) -> dict:
    study = mission_study(missions, seeds)
    ray_time, ray_rows = timed_study(study, RayEngine())
    serial_time, serial_rows = timed_study(study, SerialEngine())
    differing = differing_fields(ray_rows, serial_rows)
    ray_task_s = {r["task_id"]: r["wall_time_s"] for r in ray_rows if "wall_time_s" in r}
    serial_task_s = {r["task_id"]: r["wall_time_s"] for r in serial_rows if "wall_time_s" in r}
    both = sorted(set(ray_task_s) & set(serial_task_s))
    workers = os.cpu_count()
    return {
        "tasks": len(study.tasks),
        "ray_s": ray_time,
        "serial_s": serial_time,
        "speed_up": serial_time / ray_time,
        "identical_rows": not differing,
        "differing_fields": differing,
        "succeeded_ray": sum(bool(r.get("success")) for r in ray_rows),
        "succeeded_serial": sum(bool(r.get("success")) for r in serial_rows),
        "workers": workers,
        "two_at_once_slowdown": float(np.median([ray_task_s[k] / serial_task_s[k] for k in both])),
        "packing": sum(ray_task_s.values()) / (workers * ray_time),
        "task_wall_s": {"ray": ray_task_s, "serial": serial_task_s},
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--trivial", type=int, default=200, help="no-op tasks for the overhead")
    parser.add_argument("--missions", default="all", help="missions of the speed-up study ('' to skip it)")
    parser.add_argument("--noise-seeds", default="1,2,3,4,5")
    parser.add_argument("--out", default="benchmarks/results/batch.json")
    args = parser.parse_args()
    load = os.getloadavg()
    report = {"machine": platform.machine(), "cores": os.cpu_count(), "load_at_start": load}
    report["overhead"] = o = overhead(args.trivial)
    print(f"{'':<28}{'tasks':>6}{'Ray s':>9}{'serial s':>10}{'result':>24}")
    print(
        f"{'trivial tasks (overhead)':<28}{o['tasks']:>6}{o['ray_s']:>9.2f}{o['serial_s']:>10.2f}"
        f"{1000 * o['ray_overhead_per_task_s']:>18.1f} ms/task"
    )
    missions = shipped_missions() if args.missions == "all" else [m for m in args.missions.split(",") if m]
    if missions:
        seeds = [int(s) for s in args.noise_seeds.split(",") if s]
        report["speed_up"] = s = speed_up(missions, seeds)
        print(
            f"{'mission study':<28}{s['tasks']:>6}{s['ray_s']:>9.1f}{s['serial_s']:>10.1f}"
            f"{s['speed_up']:>14.2f}x, rows {'identical' if s['identical_rows'] else 'DIFFER'}"
        )
        for field, tasks in s["differing_fields"].items():
            print(f"  {field} differs in {tasks} of {s['tasks']} tasks")
        print(
            f"  each task beside another: {s['two_at_once_slowdown']:.2f}x its serial wall time (median); "
            f"Ray's workers busy {100 * s['packing']:.1f} % of the study's wall time"
        )
    report["load_at_end"] = os.getloadavg()
    print(f"load average at start {load[0]:.2f}, at end {report['load_at_end'][0]:.2f} ({os.cpu_count()} cores)")
    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(json.dumps(stamped(report), indent=2) + "\n")
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
