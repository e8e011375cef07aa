"""A publisher of malformed Go1 status messages, to try a driver's input checks at real time.

    python -m pedi_drake.apps.status_flood --lcm_url URL [--start_after 3] [--duration 1]
        [--rate 500] [--wait 120] [--out flood.json] [--hold]

Waits for the controller's first command on the bus (so that the driver has joined it), then
`--start_after` seconds more, then for `--duration` seconds publishes, on every status channel a
Go1 driver subscribes to (leg_control_data, state_estimator_data, rc_command), `--rate` messages a
second of each kind of FLOOD_KINDS: one whose fingerprint is wrong, one cut to half its size, one
whose float fields are all NaN. Prints one line and writes to `--out` (JSON) what it sent (counts
by channel and kind) and when (the wall clock, time.time(), of the first and the last message).
With `--hold` it then idles until SIGTERM or SIGINT instead of exiting: on a machine with few
cores, a process's exit (tens of milliseconds of the interpreter tearing down) is work that
would land in the run under test.

A driver must turn every one of them away, counted by channel and reason (`driver.messages` in a
hardware run's result.json), without latching damping and without a tick past its period
(`python -m pedi_drake.apps.sil --flood_at S` judges a run so). rc_command's float fields are
the remote's sticks, which the driver does not read: its NaN messages are valid to it (received,
not rejected); `expected_rejections` says so.

Exit codes: 0 sent (with `--hold`: and then stopped); 1 no command on the bus within `--wait`
seconds; 2 bad input; 130 stopped (Ctrl-C) before the flood ended.
"""

import argparse
import json
import math
import signal
import sys
import time
from pathlib import Path

import lcm

from pedi_drake.go1_driver import constants as c
from pedi_drake.scenario import lcm_url_is_valid

# The kinds of malformed message, named as the driver's rejection reasons.
FLOOD_KINDS = ("wrong_fingerprint", "wrong_size", "nonfinite")


def malformed(channel: str, kind: str) -> bytes:
    """One message of `kind` (FLOOD_KINDS) for a status `channel`: a default message of the
    channel's type with its fingerprint's first byte flipped, cut to half its size, or with
    every float field NaN."""
    message = c.CHANNEL_TYPES[channel]()
    if kind == "nonfinite":
        for name, typename in zip(message.__slots__, message.__typenames__, strict=True):
            if typename == "float":
                value = getattr(message, name)
                setattr(message, name, [float("nan")] * len(value) if isinstance(value, list) else float("nan"))
        return message.encode()
    data = bytearray(message.encode())
    if kind == "wrong_fingerprint":
        data[0] ^= 0xFF
        return bytes(data)
    if kind == "wrong_size":
        return bytes(data[: len(data) // 2])
    raise ValueError(f"malformed: kind must be one of {FLOOD_KINDS}, got {kind!r}")


def number_problem(flag: str, value: float, *, may_be_zero: bool) -> str | None:
    """Why `value` cannot be given to `flag` (a finite number above 0, or from 0 with
    `may_be_zero`), as a message naming both; None when it can."""
    if math.isfinite(value) and (value >= 0.0 if may_be_zero else value > 0.0):
        return None
    return f"{flag}: must be a finite number {'of 0 or more' if may_be_zero else 'above 0'}, got {value}"


def expected_rejections(sent: dict[str, dict[str, int]]) -> dict[str, dict[str, int]]:
    """{channel: {reason: count}} a driver should report for a flood that `sent` {channel: {kind:
    count}}: every message, by its kind, except rc_command's NaN ones (the sticks are not read)."""
    return {
        channel: {
            kind: n for kind, n in kinds.items() if n and not (channel == c.RC_COMMAND_CHANNEL and kind == "nonfinite")
        }
        for channel, kinds in sent.items()
    }


def flood(bus: lcm.LCM, duration: float, rate: float) -> dict:
    """Publishes the flood on `bus` for `duration` [s] at `rate` [1/s] per channel and kind, on
    an absolute schedule (duration * rate messages of each, rounded, at least one); returns
    {"sent": {channel: {kind: count}}, "first_wall", "last_wall"}."""
    messages = {channel: {kind: malformed(channel, kind) for kind in FLOOD_KINDS} for channel in c.STATUS_CHANNELS}
    sent = {channel: dict.fromkeys(FLOOD_KINDS, 0) for channel in c.STATUS_CHANNELS}
    first_wall = time.time()
    start = time.monotonic()
    # round(duration * rate) of each, the k-th at start + k / rate.
    for k in range(max(1, round(duration * rate))):
        pause = start + k / rate - time.monotonic()
        if pause > 0.0:
            time.sleep(pause)
        for channel, kinds in messages.items():
            for kind, data in kinds.items():
                bus.publish(channel, data)
                sent[channel][kind] += 1
    return {"sent": sent, "first_wall": first_wall, "last_wall": time.time()}


def wait_for_command(bus: lcm.LCM, timeout: float) -> bool:
    """True once a command is on `bus`; False when none came within `timeout` [s]."""
    seen = []
    subscription = bus.subscribe(c.COMMAND_CHANNEL, lambda _channel, _data: seen.append(True))
    deadline = time.monotonic() + timeout
    try:
        while not seen and time.monotonic() < deadline:
            bus.handle_timeout(100)
    finally:
        bus.unsubscribe(subscription)
    return bool(seen)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--lcm_url", required=True, help="the Go1 bus, udpm://GROUP:PORT?ttl=N")
    parser.add_argument("--start_after", type=float, default=3.0, help="after the first command [s]")
    parser.add_argument("--duration", type=float, default=1.0, help="of the flood [s]")
    parser.add_argument("--rate", type=float, default=500.0, help="messages a second per channel and kind")
    parser.add_argument("--wait", type=float, default=120.0, help="for the first command [s]")
    parser.add_argument("--out", default=None, help="JSON file of what was sent")
    parser.add_argument("--hold", action="store_true", help="after the flood, idle until SIGTERM or SIGINT")
    args = parser.parse_args(argv)
    for name in ("start_after", "duration", "rate", "wait"):
        problem = number_problem(f"--{name}", getattr(args, name), may_be_zero=name in ("start_after", "wait"))
        if problem is not None:
            print(f"status_flood: {problem}", file=sys.stderr)
            return 2
    if not lcm_url_is_valid(args.lcm_url):
        print(f"status_flood: --lcm_url: expected 'udpm://GROUP:PORT', got {args.lcm_url!r}", file=sys.stderr)
        return 2
    # Listening and publishing on two instances: once subscribed, an LCM instance's receive thread
    # reads every datagram on the group until the instance is closed, work the machine would
    # spend beside the run under test.
    listener = lcm.LCM(args.lcm_url)
    heard = wait_for_command(listener, args.wait)
    del listener
    if not heard:
        print(f"status_flood: no command on {args.lcm_url} within {args.wait:g} s", file=sys.stderr)
        return 1
    time.sleep(args.start_after)
    record = flood(lcm.LCM(args.lcm_url), args.duration, args.rate)
    stop_signals = {signal.SIGTERM, signal.SIGINT}
    if args.hold:  # held pending from now on, so that a stop sent meanwhile is not lost
        signal.pthread_sigmask(signal.SIG_BLOCK, stop_signals)
    record.update(duration=args.duration, rate=args.rate)
    total = sum(sum(kinds.values()) for kinds in record["sent"].values())
    took = record["last_wall"] - record["first_wall"]
    print(f"status_flood: sent {total} malformed messages in {took:.2f} s", flush=True)
    if args.out is not None:
        Path(args.out).write_text(json.dumps(record, indent=2))
    if args.hold:
        signal.sigwait(stop_signals)
    return 0


if __name__ == "__main__":
    try:
        sys.exit(main())
    except KeyboardInterrupt:  # Ctrl-C before or during the flood: stopped, nothing written
        sys.exit(130)
