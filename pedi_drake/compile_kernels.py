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
"""

import logging
import sys
import time

from pedi_drake import jit
from pedi_drake.scenario import load_scenario

_log = logging.getLogger(__name__)

# The diagrams built: (controller, hardware). The mission brings the mission manager's kernels.
VARIANTS = (("whole_body", False), ("projected_impedance", False), ("whole_body", True))
MISSION = "hit_target_front"


def compile_kernels() -> float:
    """Builds every VARIANTS diagram (compiling what the cache lacks); returns the wall time [s]."""
    from pedi_drake.diagram import MakePedipulationDiagram

    start = time.perf_counter()
    if not jit.ENABLED:
        return 0.0
    for controller, hardware in VARIANTS:
        scenario = load_scenario()
        scenario.mission, scenario.controller = MISSION, controller
        if hardware:
            scenario.lcm_buses["go1"].lcm_url = "memq://"  # in-process: nothing goes on the network
        MakePedipulationDiagram(scenario, hardware=hardware)
    return time.perf_counter() - start


def main() -> int:
    logging.basicConfig(level=logging.INFO, format="%(message)s")
    seconds = compile_kernels()
    state = "compiled" if jit.ENABLED else "not compiled (numba missing or PEDI_DRAKE_JIT=0)"
    print(f"pedi_drake kernels {state} in {seconds:.1f} s, cache {jit.cache_folder()}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
