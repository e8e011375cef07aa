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


def main() -> int:
    logging.basicConfig(level=logging.INFO, format="%(message)s")
    seconds = compile_kernels()
    state = "compiled" if jit.ENABLED else "not compiled (numba missing or PEDI_DRAKE_JIT=0)"
    print(f"pedi_drake kernels {state} in {seconds:.1f} s, cache {jit.cache_folder()}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
