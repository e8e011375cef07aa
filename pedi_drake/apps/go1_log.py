"""Record Go1 LCM traffic to an lcm-logger file, or plot one.

    python -m pedi_drake.apps.go1_log record --out run.lcmlog [--lcm_url URL] [--duration S]
    python -m pedi_drake.apps.go1_log plot run.lcmlog --out DIR

The files are standard LCM event logs: `lcm-logger`, `lcm-logplayer` and `lcm-spy` read them.
"""

import argparse
import math
import sys
import threading
from pathlib import Path

from pedi_drake.go1_driver.constants import DEFAULT_GO1_LCM_URL
from pedi_drake.go1_driver.log import read_go1_log, record_log
from pedi_drake.runtime.interrupt import ctrl_c_raises
from pedi_drake.viz.log_plots import plot_go1_log


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    commands = parser.add_subparsers(dest="command", required=True)
    record = commands.add_parser("record", help="record LCM traffic to an lcm-logger file")
    record.add_argument("--out", required=True)
    record.add_argument("--lcm_url", default=DEFAULT_GO1_LCM_URL)
    record.add_argument("--duration", type=float, default=math.inf, help="seconds (default: until Ctrl-C)")
    record.add_argument("--channels", default=".*", help="channel regex")
    plot = commands.add_parser("plot", help="plot joint targets vs measured from a log")
    plot.add_argument("log")
    plot.add_argument("--out", required=True, help="output folder for the PNG files")
    args = parser.parse_args(argv)
    if args.command == "record":
        ctrl_c_raises()  # Ctrl-C ends the recording
        ready = threading.Event()
        threading.Thread(target=lambda: ready.wait() and print("recording", flush=True), daemon=True).start()
        try:
            count = record_log(args.lcm_url, args.out, duration=args.duration, channels=args.channels, ready=ready)
        except KeyboardInterrupt:
            return 0
        print(f"recorded {count} events to {args.out}")
        return 0
    for path in plot_go1_log(read_go1_log(args.log), Path(args.out)):
        print(path)
    return 0


if __name__ == "__main__":
    sys.exit(main())
