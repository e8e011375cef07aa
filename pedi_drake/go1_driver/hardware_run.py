"""The guard around the loop of a hardware run: damping on every exit, SIGTERM like Ctrl-C, no full
garbage collections during the loop.

    with hardware_run(diagram, realtime_rate=1.0):
        simulator.Initialize()
        simulator.AdvanceTo(duration)

On leaving the block, by the end of the run, Ctrl-C, SIGTERM or an exception, the driver's link
puts damping (kp 0, kd > 0, tau 0) on the wire for `shutdown_damping_duration` and only then
stops its receive thread; the robot-side bridge holds that last command. SIGTERM's default
action would end the process without unwinding, so while the block runs (and nobody else handles
SIGTERM) it raises KeyboardInterrupt instead, the way Ctrl-C does.

The heap that exists when the loop starts (Drake, the diagram, numpy, the mission) is frozen out
of the garbage collector (gc.freeze): a full collection walks the whole heap, which takes many
control periods, so without it the loop misses deadlines whenever one runs.
Only objects made during the loop are then collected, in sub-millisecond young collections.

Every thread of the process runs under SCHED_FIFO at the driver's `realtime_priority` while the
block runs, where the OS allows it (see pedi_drake.runtime.realtime_priority); the link's report says
which scheduling the loop had.

The interpreter's thread switch interval is shortened (SWITCH_INTERVAL) while the loop runs: the
link's thread needs the GIL to stamp messages while a tick runs late, and by default a thread
computing in Python keeps it for 5 ms at a time.
"""

import contextlib
import gc
import signal
import sys
import threading

from pydrake.systems.framework import Diagram

from pedi_drake.go1_driver.hardware_station import hardware_link
from pedi_drake.runtime.realtime_priority import realtime_priority

# [s] how long a thread computing in Python may keep the GIL while another waits for it.
SWITCH_INTERVAL = 0.0005


def _raise_interrupt(signum, frame) -> None:
    raise KeyboardInterrupt(f"signal {signum}")


@contextlib.contextmanager
def hardware_run(diagram: Diagram, *, realtime_rate: float = 1.0, shutdown_damping_duration: float | None = None):
    """Runs the block as the loop of a hardware run of `diagram` (see the module docstring); yields the link."""
    link = hardware_link(diagram)
    if link is None:
        raise ValueError("hardware_run: the diagram has no Go1 hardware station")
    link.realtime_rate = realtime_rate
    duration = shutdown_damping_duration
    if duration is None:
        duration = link.config.shutdown_damping_duration
    in_main = threading.current_thread() is threading.main_thread()
    previous = signal.getsignal(signal.SIGTERM) if in_main else None
    if in_main and previous in (signal.SIG_DFL, None):
        signal.signal(signal.SIGTERM, _raise_interrupt)
    gc.collect()
    gc.freeze()
    switch_interval = sys.getswitchinterval()
    sys.setswitchinterval(SWITCH_INTERVAL)
    try:
        with realtime_priority(link.config.realtime_priority, who="Go1 driver loop") as link.scheduling:
            try:
                yield link
            finally:
                link.hold_damping(duration)
    finally:
        link.close()
        sys.setswitchinterval(switch_interval)
        gc.unfreeze()
        if in_main and previous in (signal.SIG_DFL, None):
            signal.signal(signal.SIGTERM, previous or signal.SIG_DFL)
