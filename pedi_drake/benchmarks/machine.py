"""What every benchmark's JSON says about where and when it ran: the machine and the date.

A figure without its machine is not comparable with any other, so each benchmark that feeds
docs/numbers.md (`pedi_drake.benchmarks.report`) passes its report through `stamped` before
writing it: the CPU model, the logical cores, Python's version, the date and the command line.
"""

import datetime
import os
import platform
import sys
from pathlib import Path


def cpu_model() -> str:
    """The processor's marketing name from /proc/cpuinfo (Linux), else what `platform` knows."""
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or platform.machine()


def machine() -> dict:
    """The machine a benchmark runs on: CPU model, logical cores, OS and Python."""
    return {
        "cpu_model": cpu_model(),
        "cores": os.cpu_count(),
        "system": f"{platform.system()} {platform.release()}",
        "python": platform.python_version(),
    }


def command_line(argv: list[str] | None = None) -> str:
    """The command that ran this process, as `python -m package.module args` when run with -m."""
    argv = list(sys.argv if argv is None else argv)
    if not argv:
        return "python"
    first = Path(argv[0])
    parts = first.with_suffix("").parts
    if "pedi_drake" in parts and first.suffix == ".py":
        module = ".".join(parts[parts.index("pedi_drake") :])
        return " ".join(["python -m", module, *argv[1:]])
    return " ".join(["python", *argv])


def stamped(report: dict) -> dict:
    """`report` with `machine` (merged into any machine facts it has), `date` (ISO, no time of
    day) and `command` added, for a benchmark's JSON file."""
    earlier = report.get("machine", {})
    if not isinstance(earlier, dict):  # a benchmark that wrote the processor's name alone
        earlier = {"processor": earlier}
    return {
        **report,
        "machine": {**earlier, **machine()},
        "date": datetime.date.today().isoformat(),
        "command": command_line(),
    }
