"""How a hardware run's loop waits for its next period: the OS's timer, or a busy wait.

`go1_driver.wait` chooses. With "sleep" the Simulator paces the loop itself: before each step it
sleeps until the step's wall-clock time. With "spin" the loop's thread busy-waits instead, in
compiled code that releases the interpreter's lock (`spin_until`), so the driver's link thread
still runs meanwhile; `SpinPacedMonitor` does it at the end of every simulator step, from the
Simulator's monitor, which is where the next step would otherwise sleep. "auto" (the default)
spins where nothing else of the run needs the core (`loop_wait`).

Why a loop would burn a core to wait. A thread that sleeps gives up its CPU, and the CPU goes
idle; its wake-up at the deadline then waits on everything between the timer and the thread
running again. On a virtual machine that is the host (an idle virtual CPU is
handed back to it and must be scheduled again) and the guest's scheduler (which may queue the
woken loop behind the simulator bridge on one CPU while the other sits idle). A thread that
spins keeps its CPU busy and is running when its deadline comes (docs/real_time.md says how to
compare the two at real time beside the bridge). The price is a whole core for as
long as the loop runs, which a run with other work of its own may not want to pay: hence the
choice, and what "auto" leaves to sleeping.
"""

import time

from pydrake.systems.framework import EventStatus

from pedi_drake.runtime.jit import ENABLED, kernel

WAITS = ("auto", "sleep", "spin")
NANOSECONDS_PER_SECOND = 1_000_000_000
_CLOCK_MONOTONIC = 1  # Linux's clock id, the clock of time.monotonic()


def wait_problem(wait: object) -> str | None:
    """What is wrong with `wait` as a `go1_driver.wait` setting (None: nothing)."""
    return None if wait in WAITS else f"must be one of {list(WAITS)}, got {wait!r}"


def loop_wait(wait: str, *, realtime_priority: int, work_beside_loop: bool) -> str:
    """The wait a loop set to `wait` does: "sleep" or "spin".

    "auto" spins unless the loop runs at a real-time priority (the kernel throttles a real-time
    thread that never sleeps: by default it gets at most 0.95 s of every second, then stops for
    the rest) or the run has work of its own beside the loop (`work_beside_loop`: an operator's
    input, the posture planner's worker), which on a machine of two cores needs the core a
    spinning loop would take.
    """
    if wait != "auto":
        return wait
    return "sleep" if realtime_priority > 0 or work_beside_loop else "spin"


def monotonic_ns() -> int:
    """The monotonic clock [ns], as time.monotonic_ns(); compiled code reads it without Python."""
    return time.monotonic_ns()


if ENABLED:
    from llvmlite import ir
    from numba import types
    from numba.core import cgutils
    from numba.extending import intrinsic, overload

    @intrinsic
    def _clock_gettime_monotonic(typingctx):
        """clock_gettime(CLOCK_MONOTONIC) as an int64 of nanoseconds, called straight from compiled
        code (a C call the linker resolves in the process's libc, so the kernel can be cached)."""

        def codegen(context, builder, signature, args):
            i64 = ir.IntType(64)
            timespec = ir.LiteralStructType([i64, i64])  # tv_sec, tv_nsec (64-bit Linux)
            reading = cgutils.alloca_once(builder, timespec)
            function_type = ir.FunctionType(ir.IntType(32), [ir.IntType(32), timespec.as_pointer()])
            clock_gettime = cgutils.get_or_insert_function(builder.module, function_type, "clock_gettime")
            builder.call(clock_gettime, [ir.Constant(ir.IntType(32), _CLOCK_MONOTONIC), reading])
            seconds = builder.load(cgutils.gep_inbounds(builder, reading, 0, 0))
            nanoseconds = builder.load(cgutils.gep_inbounds(builder, reading, 0, 1))
            return builder.add(builder.mul(seconds, ir.Constant(i64, NANOSECONDS_PER_SECOND)), nanoseconds)

        return types.int64(), codegen

    @overload(monotonic_ns)
    def _monotonic_ns_compiled():
        return lambda: _clock_gettime_monotonic()


@kernel
def spin_until(deadline_ns: int) -> int:
    """Busy-waits until the monotonic clock reads `deadline_ns` [ns]; returns that reading [ns].

    Compiled, it holds neither the interpreter's lock nor anything else while it waits."""
    while True:
        now = monotonic_ns()
        if now >= deadline_ns:
            return now


class SpinPacedMonitor:
    """A Simulator monitor that runs `monitor`, then busy-waits until the wall-clock time of the
    context's time at `realtime_rate` (the Simulator's own target rate must then be 0).

    The schedule is anchored at the first call (the Simulator's Initialize), as the Simulator
    anchors its own. `link` (a Go1Link, optional) is told the CPU time spent waiting, so that its
    report still tells a stalled loop that computed from one that waited.
    """

    def __init__(self, monitor, realtime_rate: float, link=None):
        if not realtime_rate > 0.0:
            raise ValueError(f"SpinPacedMonitor: realtime_rate must be positive, got {realtime_rate}")
        self._monitor, self._rate, self._link = monitor, float(realtime_rate), link
        self._anchor_ns: int | None = None
        self._anchor_time = 0.0
        spin_until(0)  # compiled (or loaded) now, not at the first tick

    def __call__(self, context):
        status = self._monitor(context)
        t = context.get_time()
        if self._anchor_ns is None:
            self._anchor_ns, self._anchor_time = time.monotonic_ns(), t
            return status
        if status.severity() in (EventStatus.Severity.kReachedTermination, EventStatus.Severity.kFailed):
            return status  # the run ends here: nothing to wait for
        deadline = self._anchor_ns + round((t - self._anchor_time) / self._rate * NANOSECONDS_PER_SECOND)
        cpu = time.thread_time()
        spin_until(deadline)
        if self._link is not None:
            self._link.busy_wait_cpu += time.thread_time() - cpu
        return status
