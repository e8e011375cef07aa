"""A haptic device operating the teleoperated foot over LCM, at real time: the simulated spring device.

    python -m pedi_drake.apps.haptic_device [--scenario_file FILE --scenario_name NAME]
        [--scenario_text YAML] [--lcm_url URL] [--rate HZ] [--push X Y Z] [--push_at S]
        [--release_at S] [--duration S] [--start_on_feedback] [--start_timeout S]

Runs a DeviceAdapter (pedi_drake.operator.haptic_device) on the scenario's operator bus with a
SpringDevice: a simulated hand holds the handle at its centre, pushes it to `--push` [m] from
`--push_at` seconds on, and lets go of the button (the autonomous mission again) at
`--release_at`. Every second a line shows the handle's offset and the force the foot's feedback
renders on it, so one can watch the hand being pushed back when the foot meets something. The
times count from the start, or with `--start_on_feedback` on the controller's clock (from its
first feedback message, as `pedi_drake.apps.teleop_lcm` does). With the controller in another
terminal:

    python run_sim.py --mission operator/teleop_foot_wall --scenario_text "{operator: {source: lcm}}"
    python -m pedi_drake.apps.haptic_device --scenario_text "{operator: {source: lcm}}" --start_on_feedback

A real device takes the spring device's place: a class with the `HapticDevice` methods `read()`
and `render(force)` over the device's own driver, given to `DeviceAdapter` in a loop like
`run` below. Bad arguments exit 2 naming them.
"""

import argparse
import math
import sys
import time

import numpy as np
from pydrake.lcm import DrakeLcm

from pedi_drake.apps.teleop_lcm import add_operator_bus_arguments, controller_clock_start
from pedi_drake.exceptions import PediError
from pedi_drake.operator.haptic_device import DeviceAdapter, SpringDevice
from pedi_drake.scenario import load_scenario


def run(
    adapter: DeviceAdapter, device: SpringDevice, args, start: float, clock=time.monotonic, sleep=time.sleep
) -> int:
    """Steps the device and the adapter at `args.rate` from the clock's `start` [s] until
    `args.duration` [s]; the number of cycles run."""
    period = 1.0 / args.rate
    cycles = int(max(0.0, clock() - start) / period)
    next_print = math.floor(cycles * period)
    while (t := clock() - start) < args.duration:
        device.hand_target = np.asarray(args.push if t >= args.push_at else (0.0, 0.0, 0.0), float)
        device.button = t < args.release_at
        device.step(period)
        adapter.step(t)
        cycles += 1
        if t >= next_print:
            print(
                f"t {t:6.2f} s  handle {np.round(1000 * device.offset, 1)} mm  rendered "
                f"{np.round(device.rendered, 1)} N  button {'held' if device.button else 'released'}",
                flush=True,
            )
            next_print += 1.0
        sleep(max(0.0, start + cycles * period - clock()))
    return cycles


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    add_operator_bus_arguments(parser)
    parser.add_argument("--rate", type=float, default=100.0, help="device cycles per second [Hz]")
    parser.add_argument("--push", type=float, nargs=3, default=[0.03, 0.0, 0.0], help="where the hand pushes [m]")
    parser.add_argument("--push_at", type=float, default=7.0, help="when the hand starts pushing [s]")
    parser.add_argument("--release_at", type=float, default=15.0, help="when the hand lets go of the button [s]")
    parser.add_argument("--duration", type=float, default=20.0, help="how long the device runs [s]")
    parser.add_argument(
        "--start_on_feedback", action="store_true", help="count time on the controller's clock, from its first feedback"
    )
    parser.add_argument("--start_timeout", type=float, default=120.0, help="longest wait for that feedback [s]")
    args = parser.parse_args(argv)
    numbers = {"--rate": args.rate, "--push_at": args.push_at, "--release_at": args.release_at}
    numbers["--duration"] = args.duration
    for flag, value in numbers.items():
        if not (math.isfinite(value) and value >= 0 and (flag != "--rate" or value > 0)):
            print(f"{flag}: must be a finite number >= 0 (--rate > 0), got {value}", file=sys.stderr)
            return 2
    if not all(math.isfinite(v) and abs(v) <= 0.1 for v in args.push):
        print(f"--push: a handle offset within 0.1 m on each axis, got {args.push}", file=sys.stderr)
        return 2
    try:
        scenario = load_scenario(
            filename=args.scenario_file, scenario_name=args.scenario_name, scenario_text=args.scenario_text
        )
    except (PediError, OSError, ValueError) as error:
        print(error, file=sys.stderr)
        return 2
    config = scenario.operator
    url = args.lcm_url or scenario.lcm_buses[config.lcm_bus].lcm_url
    start = time.monotonic()
    if args.start_on_feedback:
        start = controller_clock_start(DrakeLcm(url), config.feedback_channel, args.start_timeout)
        if start is None:
            print(f"no feedback on {config.feedback_channel} within {args.start_timeout} s", file=sys.stderr)
            return 1
    device = SpringDevice()
    adapter = DeviceAdapter(device, DrakeLcm(url), config.channel, config.feedback_channel)
    cycles = run(adapter, device, args, start)
    print(f"ran {cycles} device cycles on {config.channel} / {config.feedback_channel} ({url})")
    return 0


if __name__ == "__main__":
    sys.exit(main())
