"""Compiles the kernels of the package's diagrams into numba's disk cache, once, in this process.

    python -m pedi_drake.apps.compile_kernels

Each system compiles its kernels in its constructor, so building the diagrams a run can have
(the simulation with either whole-body controller, and the controller side of a hardware run)
fills the cache for this version of the package (see `pedi_drake.runtime.jit`), which takes minutes of
CPU. Processes started afterwards load the kernels from the cache instead of compiling them.

Run it before starting several processes on an empty cache: test workers, or the workers of a
batch study (`pedi_drake.batch` does it before the first task). Otherwise every one of them
compiles the same kernels at the same time, each paying the minutes.

It builds the diagrams in two worker processes (`--jobs`; by default one per core, at most two),
which write one cache (`jit` locks its writes, and a kernel signature one worker is compiling the
other waits for and loads). The work divides where the variants need different kernels: a robot
with prongs has six contact points where the plain Go1 has four, which gives every controller's
tick a second signature, and the whole-body ticks are the largest compiles of all. The workers
start on those, and on the kernels every diagram shares, apart (`schedule`), then take the next
job as each finishes.

    python -m pedi_drake.apps.compile_kernels --profile

also prints what the time went to: every kernel compiled at the top level (called from Python,
not from another kernel), with the signatures it was compiled for and the seconds they took,
its callees' compilation included. Against an empty cache (`NUMBA_CACHE_DIR` set to a new
folder) that is the whole compile; against a filled one, nothing. The profile is of a compile in
this one process (`--jobs 1`), where each kernel is compiled once.
"""

import argparse
import collections
import concurrent.futures
import dataclasses
import logging
import multiprocessing
import os
import sys
import time
from collections.abc import Callable

from pedi_drake.go1_driver.pacing import spin_until
from pedi_drake.runtime import jit
from pedi_drake.scenario import load_scenario

_log = logging.getLogger(__name__)

# Controllers of the simulated diagrams; the hardware diagram runs the default one.
CONTROLLERS = ("whole_body", "projected_impedance")
# Missions whose controller side is also built as a hardware run (the software-in-the-loop ones).
HARDWARE_MISSIONS = ("hit_target_front", "prong_push_box")


def variants() -> list[tuple[str, str, bool]]:
    """(mission, controller, hardware) of every diagram built: every shipped mission with either
    controller, as each mission's robot variant (prongs) and task stack give its records other
    shapes, and so its kernels other signatures; and the hardware runs' controller side."""
    from pedi_drake.mission.spec import shipped_missions

    built = [(mission, controller, False) for mission in shipped_missions() for controller in CONTROLLERS]
    return built + [(mission, "whole_body", True) for mission in HARDWARE_MISSIONS]


def uses_prongs(mission: str) -> bool:
    """Whether the shipped `mission` runs the robot variant with prongs (more contact points)."""
    from pedi_drake.mission.spec import load_mission

    robot = load_mission(mission).robot
    return robot is not None and robot.prongs is not None


@dataclasses.dataclass(frozen=True)
class Job:
    """One job of a compile worker: build the diagram of a `variants` entry, or only its whole-body
    controller (`controller_only`), which compiles that controller's tick and nothing else."""

    mission: str
    controller: str
    hardware: bool = False
    controller_only: bool = False


def schedule(built: list[tuple[str, str, bool]]) -> list[Job]:
    """The jobs that build `built` (`variants`), in the order the workers take them.

    A controller's tick has one signature per contact count (a robot with prongs has more), and
    the ticks are the largest compiles; every diagram also needs the same set of smaller kernels
    (the estimator's, the station's, the live SUF's), about as long to compile as a whole-body
    tick. Two workers that both started on diagrams would need those at the same moment, and one
    would wait for the other's (`jit` lets one process compile a signature and the others load
    it). So one worker starts on the whole-body tick of the plain Go1 alone while the other builds
    the first diagram of paper 002's controller (the shared kernels, then that tick); the other
    ticks follow alone, then every diagram, which then loads what it needs."""
    firsts: dict[tuple[int, bool], tuple[str, str, bool]] = {}
    for variant in built:
        mission, controller, hardware = variant
        if not hardware:
            firsts.setdefault((CONTROLLERS.index(controller), uses_prongs(mission)), variant)
    (whole_body, whole_body_prongs), (impedance, impedance_prongs) = (
        [firsts[(k, prongs)] for prongs in (False, True)] for k in range(len(CONTROLLERS))
    )
    leading = [
        Job(*whole_body, controller_only=True),
        Job(*impedance),
        Job(*whole_body_prongs, controller_only=True),
        Job(*impedance_prongs, controller_only=True),
    ]
    return leading + [Job(*variant) for variant in built if variant != impedance]


def run_job(job: Job) -> float:
    """Runs one `schedule` job, compiling what the cache lacks; returns the wall time [s]."""
    if not job.controller_only:
        return build_variant(job.mission, job.controller, job.hardware)
    from pedi_drake.diagram import apply_mission, whole_body_controller
    from pedi_drake.mission.spec import load_mission

    start = time.perf_counter()
    whole_body_controller(apply_mission(load_scenario(), load_mission(job.mission)), job.controller)
    return time.perf_counter() - start


def build_variant(mission: str, controller: str, hardware: bool) -> float:
    """Builds one diagram of `variants`, compiling what the cache lacks; returns the wall time [s]."""
    from pedi_drake.diagram import MakePedipulationDiagram

    start = time.perf_counter()
    scenario = load_scenario()
    scenario.mission, scenario.controller = mission, controller
    if hardware:
        scenario.lcm_buses["go1"].lcm_url = "memq://"  # in-process: nothing goes on the network
        spin_until(0)  # the loop's busy wait (go1_driver.wait: spin), built outside the diagram
    MakePedipulationDiagram(scenario, hardware=hardware)
    return time.perf_counter() - start


def default_jobs() -> int:
    """Worker processes for `compile_kernels`: two where there are two cores (see the module)."""
    return max(1, min(2, os.cpu_count() or 1))


def compile_kernels(jobs: int = 1) -> float:
    """Builds every `variants` diagram (compiling what the cache lacks) in `jobs` processes, this
    one if 1; returns the wall time [s]."""
    start = time.perf_counter()
    if not jit.ENABLED:
        return 0.0
    if jobs < 1:
        raise ValueError(f"jobs: expected at least 1 worker process, got {jobs}")
    if jobs == 1 or not jit.CACHE_WRITES_LOCKED:
        for variant in variants():
            build_variant(*variant)
        return time.perf_counter() - start
    # Fresh interpreters: a forked copy of a process that has already compiled would share its
    # numba and LLVM state.
    context = multiprocessing.get_context("spawn")
    with concurrent.futures.ProcessPoolExecutor(max_workers=jobs, mp_context=context) as pool:
        # One variant at a time (futures are taken in the order submitted), so a worker that
        # finishes early takes the next instead of waiting behind a share fixed in advance.
        futures = [pool.submit(run_job, job) for job in schedule(variants())]
        for future in futures:
            future.result()
    return time.perf_counter() - start


@dataclasses.dataclass
class KernelCompile:
    """What compiling one kernel from the top level cost (`compile_profile`)."""

    kernel: str  # module.qualified_name
    signatures: int  # argument-type signatures compiled
    seconds: float  # [s] of wall time, its callees' compilation included


def compile_profile(work: Callable[[], object]) -> list[KernelCompile]:
    """Runs `work()` recording numba's compile events; returns each kernel compiled at the top
    level (not from inside another kernel's compilation), costliest first. Needs numba."""
    from numba.core import event

    with event.install_recorder("numba:compile") as recorder:
        work()
    open_starts: list[float] = []
    totals: dict[str, list] = collections.defaultdict(lambda: [0, 0.0])
    for stamp, ev in recorder.buffer:
        if ev.is_start:
            open_starts.append(stamp)
            continue
        start = open_starts.pop()
        if not open_starts:
            function = ev.data["dispatcher"].py_func
            entry = totals[f"{function.__module__}.{function.__qualname__}"]
            entry[0] += 1
            entry[1] += stamp - start
    rows = [KernelCompile(name, count, seconds) for name, (count, seconds) in totals.items()]
    return sorted(rows, key=lambda row: -row.seconds)


def print_profile(rows: list[KernelCompile]) -> None:
    total = sum(row.seconds for row in rows)
    print(f"{'seconds':>8}  {'share':>6}  {'signatures':>10}  kernel (compiled from Python; callees included)")
    for row in rows:
        share = row.seconds / total if total else 0.0
        print(f"{row.seconds:8.1f}  {share:6.1%}  {row.signatures:10d}  {row.kernel}")
    print(f"{total:8.1f}  in all, {len(rows)} kernels")


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter, allow_abbrev=False
    )
    parser.add_argument(
        "--profile", action="store_true", help="print the compile time of every kernel (compiles in this process)"
    )
    parser.add_argument(
        "--jobs",
        type=int,
        default=None,
        help=f"worker processes (default {default_jobs()} here; 1 with --profile): see above",
    )
    args = parser.parse_args(argv)
    jobs = args.jobs if args.jobs is not None else (1 if args.profile else default_jobs())
    if jobs < 1:
        parser.error(f"--jobs: expected at least 1, got {jobs}")
    if args.profile and jobs != 1:
        parser.error("--profile records the compile in this process: use it with --jobs 1")
    logging.basicConfig(level=logging.INFO, format="%(message)s")
    state = "compiled" if jit.ENABLED else "not compiled (numba missing or PEDI_DRAKE_JIT=0)"
    if args.profile and jit.ENABLED:
        wall: list[float] = []
        print_profile(compile_profile(lambda: wall.append(compile_kernels())))
        seconds = wall[0]
    else:
        seconds = compile_kernels(jobs)
    workers = f"{jobs} processes" if jobs > 1 and jit.CACHE_WRITES_LOCKED else "1 process"
    print(f"pedi_drake kernels {state} in {seconds:.1f} s ({workers}), cache {jit.cache_root()}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
