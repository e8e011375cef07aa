"""Real-time scheduling for a wall-clock loop: every thread of this process under SCHED_FIFO.

A 2 ms control loop on a general-purpose kernel is late whenever the scheduler gives its core to
something else: another process, a compiler, a browser. Under SCHED_FIFO a thread runs until it
blocks or a higher real-time priority wants the core; ordinary processes wait. Robot software
does the same (ros2_control's controller manager asks for SCHED_FIFO priority 50 and warns when
the OS refuses). What it changes for the driver's loop is in go1_driver/README.md.

Every thread of the process is raised, not only the caller: the driver's receive thread must
stamp status messages promptly, and the threads share the GIL, so a normal-priority thread
holding it would stall the loop behind the machine's other work.

Linux's real-time throttling (`kernel.sched_rt_runtime_us` of every `kernel.sched_rt_period_us`,
by default 0.95 s of each second) leaves the rest of the machine a share should a loop spin, but
it also stops, for the rest of the second, real-time threads that need more than that: a
simulator bridge that needs most of a core is stopped for tens of milliseconds once a second,
long enough for the driver's status watchdog to latch (docs/real_time.md). `rt_throttling()` reads the
limit; raising a thread warns once while it is on. `sysctl -w kernel.sched_rt_runtime_us=-1`
lifts it, which a robot computer dedicated to its loops can afford and a shared desktop cannot.

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


def rt_throttling(kernel_settings: Path = Path("/proc/sys/kernel")) -> float | None:
    """The share of each period that Linux lets real-time threads run (0.95 by default), or None
    when the kernel does not throttle them (or does not say); `kernel_settings`: where the
    kernel's sched_rt_runtime_us and sched_rt_period_us are read."""
    try:
        runtime = int((kernel_settings / "sched_rt_runtime_us").read_text())
        period = int((kernel_settings / "sched_rt_period_us").read_text())
    except (OSError, ValueError):
        return None
    return None if runtime < 0 or period <= 0 else runtime / period


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
    share = rt_throttling()
    if raised and share is not None:
        _log.warning(
            "%s: SCHED_FIFO %d; Linux stops real-time threads for the rest of each second once they ran %.2f of it"
            " (kernel.sched_rt_runtime_us): a loop that needs more is stopped for tens of ms",
            who,
            priority,
            share,
        )
    try:
        yield granted
    finally:
        _restore(raised)


def _restore(previous: dict[int, tuple[int, int]]) -> None:
    """Puts each thread of `previous` ({thread id: (policy, priority)}) back to its scheduling."""
    for tid, (policy, priority) in previous.items():
        with contextlib.suppress(ProcessLookupError, PermissionError):
            os.sched_setscheduler(tid, policy, os.sched_param(priority))
