"""A stand-in for the robot side in its own process, lighter than the simulator bridge: publishes
standing status at 500 Hz, records every command it receives, and can flood malformed messages.

    python tests/go1_fake_robot.py URL OUT.npz [--flood_at S] [--flood_duration S] [--flood_rate HZ]
        [--silent_at S]

Prints "publishing" once running. Writes OUT.npz on SIGTERM/SIGINT: the arrival times
(time.monotonic) and the 60-vectors of the received commands, the status send times, and what
it flooded (counts by channel and kind). The flood sends, per channel and at `flood_rate` each,
the malformed messages of `pedi_drake.apps.status_flood` (a wrong fingerprint, truncated, NaN
float fields) from the same loop as the status.
"""

import argparse
import json
import signal
import sys
import threading
import time

import lcm
import numpy as np

from pedi_drake import robot
from pedi_drake.apps.status_flood import FLOOD_KINDS, malformed
from pedi_drake.go1_driver import constants as c
from pedi_drake.go1_driver.lcmtypes import leg_control_data_lcmt, state_estimator_lcmt


def status_messages() -> tuple[bytes, bytes]:
    leg = leg_control_data_lcmt()
    leg.q = robot.STANDING_Q.tolist()
    estimator = state_estimator_lcmt()
    estimator.quat = [1.0, 0.0, 0.0, 0.0]
    estimator.aBody = [0.0, 0.0, 9.81]
    estimator.contact_estimate = [300.0] * 4
    return leg.encode(), estimator.encode()


def main() -> int:
    parser = argparse.ArgumentParser()
    parser.add_argument("url")
    parser.add_argument("out")
    # After the first command, so that the driver has certainly joined the bus when the flood starts.
    parser.add_argument("--flood_at", type=float, default=None, help="start of the flood after the first command [s]")
    parser.add_argument("--flood_duration", type=float, default=1.0)
    parser.add_argument("--flood_rate", type=float, default=500.0, help="messages per second per channel and kind")
    parser.add_argument("--silent_at", type=float, default=None, help="stop publishing status after this long [s]")
    args = parser.parse_args()
    bus = lcm.LCM(args.url)
    commands: list[np.ndarray] = []
    arrivals: list[float] = []

    def on_command(_channel, data) -> None:
        arrivals.append(time.monotonic())
        commands.append(c.message_to_command(c.CHANNEL_TYPES[c.COMMAND_CHANNEL].decode(data)))

    bus.subscribe(c.COMMAND_CHANNEL, on_command).set_queue_capacity(10000)
    stop = threading.Event()
    signal.signal(signal.SIGTERM, lambda *_: stop.set())
    signal.signal(signal.SIGINT, lambda *_: stop.set())
    leg, estimator = status_messages()
    flooded = {channel: dict.fromkeys(FLOOD_KINDS, 0) for channel in c.STATUS_CHANNELS}
    sends: list[float] = []
    print("publishing", flush=True)
    start = time.monotonic()
    next_status = start
    next_flood = flood_end = None
    while not stop.is_set():
        now = time.monotonic()
        if args.flood_at is not None and next_flood is None and arrivals:
            next_flood = arrivals[0] + args.flood_at
            flood_end = next_flood + args.flood_duration
        silent = args.silent_at is not None and now > start + args.silent_at
        if now >= next_status and not silent:
            bus.publish(c.LEG_CONTROL_CHANNEL, leg)
            bus.publish(c.STATE_ESTIMATOR_CHANNEL, estimator)
            sends.append(now)
            next_status += c.BRIDGE_PERIOD
        if next_flood is not None and now >= next_flood and now < flood_end:
            for channel in c.STATUS_CHANNELS:
                for kind in FLOOD_KINDS:
                    bus.publish(channel, malformed(channel, kind))
                    flooded[channel][kind] += 1
            next_flood += 1.0 / args.flood_rate
        if silent:
            next_status = now + c.BRIDGE_PERIOD  # keep receiving commands at the same pace
        wake = min(next_status, next_flood if next_flood is not None and next_flood < flood_end else next_status)
        try:
            bus.handle_timeout(max(0, int(1000 * (wake - time.monotonic()))))
        except OSError:  # the wait was interrupted by a signal (EINTR): look at `stop` again
            pass
    while bus.handle_timeout(0) > 0:
        pass
    np.savez(
        args.out,
        arrivals=np.array(arrivals),
        commands=np.array(commands).reshape(-1, 60),
        status_sends=np.array(sends),
        flooded=json.dumps(flooded),
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
