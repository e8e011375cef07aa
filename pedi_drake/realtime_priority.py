"""Real-time scheduling for a wall-clock loop: every thread of this process under SCHED_FIFO.

A 2 ms control loop on a general-purpose kernel is late whenever the scheduler gives its core to
something else: another process, a compiler, a browser. Under SCHED_FIFO a thread runs until it
blocks or a higher real-time priority wants the core; ordinary processes wait. Robot software
does the same (ros2_control's controller manager asks for SCHED_FIFO priority 50 and warns when
the OS refuses). What it did to this project's loop, measured, is in go1_driver/README.md.

Every thread of the process is raised, not only the caller: the driver's receive thread must
stamp status messages promptly, and the threads share the GIL, so a normal-priority thread
holding it would stall the loop behind the machine's other work. Linux's real-time throttling
(`/proc/sys/kernel/sched_rt_runtime_us`, by default 95 % of each second) still leaves the rest of
the machine a share should the loop ever spin.

It needs the right to raise priority (root, CAP_SYS_NICE, or an RLIMIT_RTPRIO of at least the
priority: `ulimit -r`). Without it the loop runs at normal priority and says so; nothing fails.
"""

import contextlib
import logging
import os
from pathlib import Path

_log = logging.getLogger(__name__)

# Highest SCHED_FIFO priority Linux accepts.
MAX_PRIORITY = 99


def priority_problem(priority: object) -> str | None:
    """What is wrong with `priority` as a `realtime_priority` setting (None: nothing)."""
    if isinstance(priority, bool) or not isinstance(priority, int) or not 0 <= priority <= MAX_PRIORITY:
        return f"must be an integer from 0 (normal scheduling) to {MAX_PRIORITY}, got {priority!r}"
    return None


def _thread_ids() -> list[int]:
    """The Linux thread ids of this process."""
    return sorted(int(entry.name) for entry in Path("/proc/self/task").iterdir())


@contextlib.contextmanager
def realtime_priority(priority: int, *, who: str):
    """Runs the block with every thread of this process under SCHED_FIFO at `priority` (0: no change).

    Yields what was granted, for the run's report: "SCHED_FIFO <priority>", "normal scheduling"
    (priority 0) or "refused: <reason>". Threads are restored to their scheduling on leaving.
    `who` names the loop in the warning when the OS refuses.
    """
    problem = priority_problem(priority)
    if problem is not None:
        raise ValueError(f"{who}: realtime_priority {problem}")
    if priority == 0:
        yield "normal scheduling"
        return
    if not hasattr(os, "sched_setscheduler"):
        yield "refused: this OS has no SCHED_FIFO"
        return
    raised: dict[int, tuple[int, int]] = {}
    granted = f"SCHED_FIFO {priority}"
    for tid in _thread_ids():
        try:
            previous = (os.sched_getscheduler(tid), os.sched_getparam(tid).sched_priority)
            os.sched_setscheduler(tid, os.SCHED_FIFO, os.sched_param(priority))
            raised[tid] = previous
        except ProcessLookupError:
            continue  # the thread ended meanwhile
        except PermissionError as error:
            granted = f"refused: {error.strerror} (needs root, CAP_SYS_NICE or ulimit -r {priority})"
            _log.warning("%s: real-time priority %s; the loop runs at normal priority", who, granted)
            _restore(raised)  # all or none: a thread left at normal priority would hold up the others
            raised.clear()
            break
    try:
        yield granted
    finally:
        _restore(raised)


def _restore(previous: dict[int, tuple[int, int]]) -> None:
    """Puts each thread of `previous` ({thread id: (policy, priority)}) back to its scheduling."""
    for tid, (policy, priority) in previous.items():
        with contextlib.suppress(ProcessLookupError, PermissionError):
            os.sched_setscheduler(tid, policy, os.sched_param(priority))
