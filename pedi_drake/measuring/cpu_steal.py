"""CPU time the hypervisor took from this virtual machine: the `steal` of Linux's /proc/stat.

On a virtual machine the host may run something else on the physical core under one of the
guest's CPUs. The guest's threads do not run then, but unless the kernel accounts steal time
in the scheduler, a thread that was on that CPU is charged the stolen time as its own CPU time:
a tick of a few hundred microseconds can appear to have computed for milliseconds. The kernel
counts the stolen time per CPU (in clock ticks, USER_HZ) whether or not it charges it to threads;
the difference over a run says how much the host took.
"""

import os
from pathlib import Path

_CLOCK_TICKS = os.sysconf("SC_CLK_TCK") if hasattr(os, "sysconf") else 100
# Fields of a /proc/stat "cpu" line after its name: user nice system idle iowait irq softirq steal ...
_STEAL_FIELD = 7


def steal_seconds(stat: Path = Path("/proc/stat")) -> float | None:
    """CPU time stolen from all of this machine's CPUs since boot [s]; None where the kernel does
    not say (not Linux, or a kernel without the field)."""
    try:
        first = stat.read_text().splitlines()[0].split()
    except (OSError, IndexError):
        return None
    if first[0] != "cpu" or len(first) <= _STEAL_FIELD + 1:
        return None
    return int(first[_STEAL_FIELD + 1]) / _CLOCK_TICKS
