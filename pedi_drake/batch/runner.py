"""Running a study: the tasks still missing from its folder, on an engine, with progress."""

import sys
import time
from pathlib import Path

from pedi_drake.apps.compile_kernels import compile_kernels, default_jobs
from pedi_drake.batch.results_file import ResultsFile, code_version
from pedi_drake.batch.study import Study


class Progress:
    """done / failed / remaining and an ETA: one redrawn line on a terminal, plain lines otherwise."""

    def __init__(self, total: int, stream=sys.stderr):
        self.total, self.done, self.failed = total, 0, 0
        self.stream, self.start = stream, time.perf_counter()
        self.tty = hasattr(stream, "isatty") and stream.isatty()

    def update(self, row: dict) -> None:
        self.done += 1
        self.failed += row.get("status") != "ok"
        elapsed = time.perf_counter() - self.start
        eta = elapsed / self.done * (self.total - self.done)
        line = (
            f"{self.done}/{self.total} done, {self.failed} not ok, {self.total - self.done} left, "
            f"ETA {eta:5.0f} s  (last: {row.get('status')} {row.get('reason', '')[:50]})"
        )
        if self.tty:
            self.stream.write("\r" + line[:120].ljust(120))
            if self.done == self.total:
                self.stream.write("\n")
        else:
            self.stream.write(line + "\n")
        self.stream.flush()


def run_study(study: Study, folder: Path, engine, *, resume: bool = False, quiet: bool = False) -> ResultsFile:
    """Runs the tasks of `study` that `folder` has no row for (all of them unless `resume`)."""
    results = ResultsFile(folder)
    if results.rows and not resume:
        raise FileExistsError(f"{folder}: holds results of an earlier run; use --resume or another --out")
    done = results.done_ids()
    todo = [task for task in study.tasks if task.task_id not in done]
    progress = Progress(len(todo)) if not quiet and todo else None

    def on_row(row: dict) -> None:
        results.append(row)
        if progress is not None:
            progress.update(row)

    if todo:
        if study.kind == "mission":
            # Compiled once here: workers starting together on an empty cache would each compile
            # the same kernels (see pedi_drake.apps.compile_kernels).
            compile_kernels(default_jobs())
        engine.run(todo, on_row, code_version())
    return results
