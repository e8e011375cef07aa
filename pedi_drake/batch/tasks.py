"""Running one task of a study, in whatever process the engine chose: the task builds and runs
its own diagram (a Drake diagram is not shared across processes) and returns one result row.

A task never raises: a mission that fails, a run that falls, an exception or a timeout each
become a row with `status` and `reason`, so a study never loses its other rows. Only the death
of the process itself (an infrastructure failure) is left to the engine, which retries it.
"""

import functools
import os
import signal
import time
import traceback

from pedi_drake.batch.study import Task, scenario_for, suf_design_for
from pedi_drake.evaluation.judge import judge_run
from pedi_drake.exceptions import ConfigError
from pedi_drake.mission.spec import load_mission
from pedi_drake.run import simulate
from pedi_drake.suf.design import best_feet, evaluate

# Columns whose values depend on the machine's load, not on the task: left out when two
# engines' rows are compared.
TIMING_COLUMNS = ("wall_time_s", "real_time_factor", "controller_tick_median_ms", "worker_pid")


def expected_cost(task: Task) -> float:
    """How long `task` should take, roughly and relative to the study's other tasks: a mission
    task's planned simulated time [s] (its mission's phase durations), 1 for any other task, 0
    when it cannot be told (a task whose mission does not load fails on its own, with a reason)."""
    if task.kind != "mission":
        return 1.0
    mission = task.settings.get("mission")
    if not isinstance(mission, str):
        duration = task.settings.get("simulation_duration")
        return float(duration) if isinstance(duration, int | float) else 0.0
    return _planned_seconds(mission)


@functools.lru_cache(maxsize=256)
def _planned_seconds(mission: str) -> float:
    try:
        return load_mission(mission).planned_duration()
    except (ConfigError, OSError):
        return 0.0


class TaskTimeout(Exception):
    """The task ran past its wall-time budget."""


def _raise_timeout(signum, frame):
    raise TaskTimeout()


def run_task(task: Task, code_version: str = "") -> dict:
    """Runs `task` and returns its row (never raises for the task's own failures)."""
    row = {
        "study": task.study,
        "task_id": task.task_id,
        "index": task.index,
        "code_version": code_version,
        **{f"factor.{name}": value for name, value in task.factors.items()},
        "status": "error",
        "reason": "",
        "worker_pid": os.getpid(),
    }
    start = time.perf_counter()
    # A wall-clock alarm in the task's own process: it interrupts a simulation that hangs as
    # well as one that is merely slow. Tasks run in their worker's main thread.
    previous = signal.signal(signal.SIGALRM, _raise_timeout)
    signal.setitimer(signal.ITIMER_REAL, task.timeout)
    try:
        row.update(_RUNNERS[task.kind](task))
    except TaskTimeout:
        row.update(status="timeout", reason=f"ran past the task timeout of {task.timeout:g} s")
    except Exception as error:  # a bug or a bad configuration: a row with the reason
        lines = traceback.format_exception_only(type(error), error)
        row.update(status="error", reason="".join(lines).strip()[:500])
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0.0)
        signal.signal(signal.SIGALRM, previous)
    row["wall_time_s"] = time.perf_counter() - start
    return row


def _mission_row(task: Task) -> dict:
    scenario = scenario_for(task)
    record = simulate(scenario=scenario, name=task.study, quiet=True, replay=False)
    result = judge_run(record)
    errors = [row["error"] for row in result["foot_errors_m"] if row["error"] is not None]
    tick = result.get("controller_tick_ms") or {}
    return {
        "status": "ok" if result["success"] else "failed",
        "reason": result["reason"],
        "success": bool(result["success"]),
        "fell": bool(result["fell"]),
        "foot_error_max_m": max(errors) if errors else None,
        "max_base_drift_m": result["max_base_drift_m"],
        "real_time_factor": result["real_time_factor"],
        "controller_tick_median_ms": tick.get("median"),
        "result": result,
    }


def _suf_row(task: Task) -> dict:
    design = suf_design_for(task)
    if design.optimise_feet:
        point = best_feet(design.trunk_height, design.prongs, method=design.method)
        suf, feet_x, feet_y = point.suf, point.feet_x, point.feet_y
    else:
        suf = evaluate(design.trunk_height, design.feet_x, design.feet_y, design.prongs, method=design.method)
        feet_x, feet_y = design.feet_x, design.feet_y
    return {"status": "ok", "success": suf > 0.0, "suf_n": suf, "feet_x_m": feet_x, "feet_y_m": feet_y}


def _noop_row(task: Task) -> dict:
    """A task that only waits `duration_s`: it measures an engine's own overhead per task."""
    time.sleep(float(task.settings.get("duration_s", 0.0)))
    return {"status": "ok", "success": True}


_RUNNERS = {"mission": _mission_row, "suf": _suf_row, "noop": _noop_row}
