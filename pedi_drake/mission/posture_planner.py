"""The posture optimiser (pedi_drake.suf.posture) and the stop chooser (pedi_drake.suf.stop) run
off the control loop, in a worker process.

An optimisation takes about a second of CPU: far too long for a mission update (the manager
updates every 10 ms inside the controller's 2 ms ticks), and a thread would hold Python's lock
for milliseconds at a time against the control loop. So a phase that needs a posture asks for it
(`PosturePlanner.ask`), holds the robot where it stands, and takes the answer on a later update
(`answer`). The worker runs at a lower scheduling priority than the control loop.

Determinism: an answer is a pure function of its request (PostureRequest, plain values), and
the phase takes it no earlier than a fixed time after asking (`PLAN_LATENCY` of diagram time).
A lock-step simulation waits there for the worker (`answer(..., wait=True)`), so a simulated run
does not depend on how fast the machine is; a real-time run only polls, and the phase holds until
the answer is in.

One worker serves the whole process (`shared_planner`), started by the first mission that needs
it (in the MissionManager's constructor, so that its start-up is not in a tick) and
stopped at exit.
"""

import atexit
import concurrent.futures
import dataclasses
import multiprocessing
import os
import threading

from pedi_drake.suf.posture import Posture, PostureCase, PostureLimits, PostureResult, optimise_posture

# Diagram time between asking for a posture and taking the answer [s]: a bound on one
# optimisation beside a real-time run, so that lock-step simulations see the delay a real-time
# run would.
PLAN_LATENCY = 2.0
# Longest wait for an answer beyond PLAN_LATENCY [s] before the phase fails. Only a real-time run
# waits so: a lock-step simulation blocks for the worker. The robot holds still meanwhile, so the
# wait is not counted against the phase's timeout (MissionProgress.plan_wait); an optimisation
# takes a few seconds of CPU, more on a loaded machine or beside real-time loops.
PLAN_WAIT_LIMIT = 20.0
# Time the trunk takes to move to an optimal posture [s] (attitude changes of up to 0.2 rad).
POSTURE_DURATION = 1.5
# The worker's scheduling priority relative to the process that starts it (higher: nicer).
WORKER_NICENESS = 10


@dataclasses.dataclass(frozen=True)
class PostureRequest:
    """One optimisation: its arguments (see optimise_posture). A value: hashed, sent to the worker."""

    case: PostureCase
    start: Posture
    limits: PostureLimits = PostureLimits()
    method: str = "affine"
    # Coordinates (of pedi_drake.suf.posture.COORDINATES) kept at the start's values.
    fixed: tuple[str, ...] = ()

    def solve(self) -> PostureResult:
        return optimise_posture(self.case, self.start, self.limits, self.method, fixed=self.fixed)

    def __deepcopy__(self, memo) -> "PostureRequest":
        return self  # a value


def solve_request(request):
    """The answer to `request` (what the worker runs): a PostureRequest's optimal posture, or a
    pedi_drake.suf.stop.StopRequest's stop."""
    return request.solve()


def _start_worker() -> None:
    """Lowers the worker's priority and builds what every optimisation reuses (the Go1 plant)."""
    try:
        os.nice(WORKER_NICENESS)
    except OSError:  # not permitted here: the worker runs at the parent's priority
        pass
    from pedi_drake import robot

    robot.make_go1_plant()


class PosturePlanner:
    """Posture optimisations in one worker process, each request solved once (see the module docstring)."""

    def __init__(self):
        context = multiprocessing.get_context("spawn")  # no fork of a process with Drake's threads
        self._pool = concurrent.futures.ProcessPoolExecutor(1, mp_context=context, initializer=_start_worker)
        self._futures: dict[PostureRequest, concurrent.futures.Future] = {}
        self._lock = threading.Lock()
        # The worker starts with its first task: start it now, not in a mission update.
        self._pool.submit(int).result()

    def ask(self, request) -> None:
        """Starts solving `request` unless it is solved or being solved (returns at once)."""
        with self._lock:
            if request not in self._futures:
                self._futures[request] = self._pool.submit(solve_request, request)

    def answer(self, request, *, wait: bool):
        """The answer to `request` (asked before), None while it is being solved (unless `wait`:
        then it blocks until the answer is in). Re-raises the optimiser's error."""
        self.ask(request)
        future = self._futures[request]
        if not wait and not future.done():
            return None
        return future.result()

    def close(self) -> None:
        self._pool.shutdown(wait=False, cancel_futures=True)


_shared: PosturePlanner | None = None
_shared_lock = threading.Lock()


def shared_planner() -> PosturePlanner:
    """The process's planner, started on first use and stopped at exit."""
    global _shared
    with _shared_lock:
        if _shared is None:
            _shared = PosturePlanner()
            atexit.register(_shared.close)
        return _shared
