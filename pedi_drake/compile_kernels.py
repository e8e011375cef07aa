"""Compiles the kernels of the package's diagrams into numba's disk cache, once, in this process.

    python -m pedi_drake.compile_kernels

Each system compiles its kernels in its constructor, so building the diagrams a run can have
(the simulation with either whole-body controller, and the controller side of a hardware run)
fills the cache for this version of the package (see `pedi_drake.jit`): a few minutes of CPU on
a 2-core machine. Processes started afterwards load the kernels in milliseconds.

Run it before starting several processes on an empty cache: test workers, or the workers of a
batch study (`pedi_drake.batch` does it in its own process before the first task). Otherwise
every one of them compiles the same kernels at the same time, each paying the minutes, and
numba's cache is not made for concurrent writers: a worker that loads a kernel while another
writes it can fail with "no compiled object yet for <Library ...>" (seen with two study workers
beside two test workers on one fresh cache).

    python -m pedi_drake.compile_kernels --profile

also prints what the time went to: every kernel compiled at the top level (called from Python,
not from another kernel), with the signatures it was compiled for and the seconds they took,
its callees' compilation included. Against an empty cache (`NUMBA_CACHE_DIR` set to a new
folder) that is the whole compile; against a filled one, nothing.
"""

import argparse
import collections
import dataclasses
import logging
import sys
import time
from collections.abc import Callable

from pedi_drake import jit
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


def compile_kernels() -> float:
    """Builds every `variants` diagram (compiling what the cache lacks); returns the wall time [s]."""
    from pedi_drake.diagram import MakePedipulationDiagram

    start = time.perf_counter()
    if not jit.ENABLED:
        return 0.0
    for mission, controller, hardware in variants():
        scenario = load_scenario()
        scenario.mission, scenario.controller = mission, controller
        if hardware:
            scenario.lcm_buses["go1"].lcm_url = "memq://"  # in-process: nothing goes on the network
        MakePedipulationDiagram(scenario, hardware=hardware)
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
    parser.add_argument("--profile", action="store_true", help="print the compile time of every kernel")
    args = parser.parse_args(argv)
    logging.basicConfig(level=logging.INFO, format="%(message)s")
    state = "compiled" if jit.ENABLED else "not compiled (numba missing or PEDI_DRAKE_JIT=0)"
    if args.profile and jit.ENABLED:
        wall: list[float] = []
        print_profile(compile_profile(lambda: wall.append(compile_kernels())))
        seconds = wall[0]
    else:
        seconds = compile_kernels()
    print(f"pedi_drake kernels {state} in {seconds:.1f} s, cache {jit.cache_folder()}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
