"""Engines that run a study's tasks: Ray (this machine's cores, or a cluster) or one process.

Both call `on_row(row)` as each task finishes, in completion order. With Ray, each task is a
remote function call in a worker process; a worker that dies (killed, out of memory) is an
infrastructure failure that Ray retries up to `max_retries` times, while a task's own failure
(a mission that fails, an exception, a timeout) is already a row and is never retried.

Ray is given the tasks longest first (`longest_first`): with more tasks than workers, the last
ones to start are then the shortest, so the workers run out of work at nearly the same time
instead of one waiting through the tail of a long task. The serial engine keeps the study's order.
"""

import os
from collections.abc import Callable, Iterable

from pedi_drake.batch.study import Task
from pedi_drake.batch.tasks import expected_cost, run_task

ENGINES = ("ray", "serial")


class SerialEngine:
    """Every task in this process, one after the other (for debugging and machines without Ray)."""

    name = "serial"

    def run(self, tasks: Iterable[Task], on_row: Callable[[dict], None], code_version: str) -> None:
        for task in tasks:
            on_row(run_task(task, code_version))


class RayEngine:
    """Tasks as Ray remote calls: an embedded local Ray by default, a running cluster by address.

    `address`: a Ray cluster's address (`ray://host:10001` or `host:6379`); None starts a local
    Ray on this machine (unless the RAY_ADDRESS variable names a cluster, as Ray itself reads it).
    `num_cpus`: workers of a local Ray (default: every core). One task takes one CPU.
    """

    name = "ray"

    def __init__(self, address: str | None = None, num_cpus: int | None = None, max_retries: int = 2):
        self.address, self.num_cpus, self.max_retries = address, num_cpus, max_retries

    def run(self, tasks: Iterable[Task], on_row: Callable[[dict], None], code_version: str) -> None:
        import ray  # the optional `batch` extra: the serial engine works without it

        started_here = not ray.is_initialized()
        if started_here:
            options = {"include_dashboard": False, "logging_level": "ERROR", "log_to_driver": False}
            if self.address is None and not os.environ.get("RAY_ADDRESS"):
                # A local Ray: small object store (rows are small) and every core unless told.
                options |= {"num_cpus": self.num_cpus or os.cpu_count(), "object_store_memory": 200 * 2**20}
            ray.init(address=self.address, **options)
        remote = ray.remote(num_cpus=1, max_retries=self.max_retries, retry_exceptions=False)(run_task)
        pending = {remote.remote(task, code_version): task for task in longest_first(tasks)}
        try:
            while pending:
                ready, _ = ray.wait(list(pending), num_returns=1, timeout=1.0)
                for ref in ready:
                    task = pending.pop(ref)
                    try:
                        row = ray.get(ref)
                    except ray.exceptions.RayError as error:  # the worker died more than max_retries times
                        row = crashed_row(task, code_version, f"worker lost after {self.max_retries} retries: {error}")
                    on_row(row)
        finally:
            for ref in pending:
                ray.cancel(ref, force=True)
            if started_here:
                ray.shutdown()


def longest_first(tasks: Iterable[Task]) -> list[Task]:
    """The tasks by expected cost, the longest first; tasks of equal cost keep their order."""
    return sorted(tasks, key=expected_cost, reverse=True)


def crashed_row(task: Task, code_version: str, reason: str) -> dict:
    """The row of a task whose process never returned."""
    return {
        "study": task.study,
        "task_id": task.task_id,
        "index": task.index,
        "code_version": code_version,
        **{f"factor.{name}": value for name, value in task.factors.items()},
        "status": "crashed",
        "reason": reason[:500],
    }


def make_engine(name: str, *, address: str | None = None, num_cpus: int | None = None, max_retries: int = 2):
    """The engine `name` (ENGINES)."""
    if name == "serial":
        return SerialEngine()
    return RayEngine(address=address, num_cpus=num_cpus, max_retries=max_retries)
