"""A fuzzed operator: a seeded stream of foot_command_lcmt messages, most of them broken, sent to a
teleoperated foot (judged by pedi_drake.evaluation.teleop_violations).

`fuzz_stream(seed, count)` (on missions/operator/teleop_foot_wall.yaml: the lifted foot has a
rigid wall within reach, so the force bound has something to act on) asks for the teleoperated
foot with heartbeats (HEARTBEAT_RATE) until FUZZ_START, then sends `count` messages at FUZZ_RATE,
each of a kind drawn with the weights of KINDS:

  valid       what a careless operator sends, changed every 0.2 to 1 s: a foot velocity (trunk or
              world frame, any direction, up to twice the speed bound), a push forward into the
              wall (up to twice the speed bound), a foot position (either frame, anywhere within
              25 cm of the working position: often outside the workspace or inside the wall) or a
              stop; mode teleop, none or semi-autonomous (which this mission does not serve)
                                                                                     -> taken
  huge        that command with 1e2 to 1e308 (either sign) in some of its values    -> taken
  nonfinite   NaN, inf or -inf in some value                                         -> nonfinite
  stale       an earlier taken message sent again, or a new one numbered like the newest taken
              one, or stamped before it                                              -> out_of_order
  ahead       stamped 1 s to 11 days ahead, or numbered 1e7 to 1e15 ahead            -> stamp_ahead
  wrong_code  a mode, frame or kind outside its set                                  -> out_of_range
  truncated   a message cut short or padded                                          -> wrong_size
  foreign     random bytes, or another type's message, of the right size           -> wrong_fingerprint

Then it asks for the autonomous mode (heartbeats again), and the mission puts the leg back. The
E-stop flag is never set: a fuzzed E-stop is an E-stop, which damps the motors, by design.
`FuzzStream.expected` is how many messages of each reject reason (pedi_drake.go1_driver.link)
the operator input must count and `taken` how many it must take, `sent` the messages by kind.
"""

import dataclasses

import numpy as np

from pedi_drake.go1_driver.lcmtypes import foot_command_lcmt, rc_command_lcmt
from pedi_drake.operator.command import (
    FRAME_TRUNK,
    FRAME_WORLD,
    KIND_POSITION,
    KIND_VELOCITY,
    MODE_AUTONOMOUS,
    MODE_NONE,
    MODE_SEMI_AUTONOMOUS,
    MODE_TELEOP,
)
from pedi_drake.operator.command import (
    KINDS as COMMAND_KINDS,
)
from pedi_drake.operator.message_stream import TimedMessage

MISSION = "operator/teleop_foot_wall"
# Of the tests and, unless told otherwise, the benchmark: a draw whose careless operator meets the
# workspace, speed and force bounds alike (the tests check that each had work to do).
SEED = 6104
FUZZ_COUNT = 10_000
FUZZ_RATE = 1000.0  # [Hz]
HEARTBEAT_RATE = 100.0  # [Hz]
# Diagram times [s]: the mission's teleop phase starts at about 4.8 s (stand up, shift, lift).
FUZZ_START = 5.5
# After the fuzz: the autonomous request for this long [s], then the leg is put back and the robot
# lies down (SETTLE [s]).
ASK_AUTONOMOUS_FOR = 0.5
SETTLE = 6.0
# The kinds of message and their weights (module docstring).
KINDS = {
    "valid": 0.45,
    "huge": 0.10,
    "nonfinite": 0.10,
    "stale": 0.08,
    "ahead": 0.05,
    "wrong_code": 0.08,
    "truncated": 0.08,
    "foreign": 0.06,
}
# The reject reason each broken kind must be counted under (valid and huge ones are taken).
REASON_OF_KIND = {
    "nonfinite": "nonfinite",
    "stale": "out_of_order",
    "ahead": "stamp_ahead",
    "wrong_code": "out_of_range",
    "truncated": "wrong_size",
    "foreign": "wrong_fingerprint",
}
TAKEN_KINDS = ("heartbeat", "valid", "huge")
# The careless operator's commands: speeds up to twice the bound [m/s], positions within this of
# the lift's working position (FR, 15 cm under the hip, trunk frame [m]) [m].
MAX_SPEED = 0.2
WORKING_POSITION_B = np.array([0.19, -0.13, -0.15])
POSITION_SPREAD = 0.25
# [m] where the trunk stands once FR is lifted (shifted over the other three feet), for world targets.
LIFTED_TRUNK_W = np.array([-0.035, 0.05, 0.28])
# Shares of the careless operator's commands: velocity, push into the wall, position, stop.
COMMAND_SHARES = (0.35, 0.2, 0.35, 0.1)
_ENCODED_SIZE = len(foot_command_lcmt().encode())


@dataclasses.dataclass
class FuzzStream:
    """The messages, and what the operator input must make of them."""

    messages: list[TimedMessage]
    sent: dict[str, int]  # messages by kind (KINDS, and "heartbeat")
    expected: dict[str, int]  # rejections by reason
    taken: int  # messages the input must take
    fuzz_start: float  # [s] diagram time
    fuzz_end: float  # [s]
    end: float  # [s] the stream's last message

    @property
    def simulation_duration(self) -> float:
        return self.end + SETTLE


@dataclasses.dataclass
class _Command:
    mode_request: int
    frame: int
    kind: int
    value: np.ndarray


class _Sender:
    """The fuzzing operator's own clock and sequence numbers, and what it sent."""

    def __init__(self, channel: str):
        self.channel = channel
        self.sequence = 0
        self.messages: list[TimedMessage] = []
        self.taken: list[tuple[float, int, bytes]] = []  # (time, sequence, bytes) of each taken message
        self.sent: dict[str, int] = {}

    def message(self, command: _Command, t: float, sequence: int | None = None, stamp_t: float | None = None):
        """A foot_command_lcmt of `command` numbered next (or `sequence`), stamped `t` (or `stamp_t`)."""
        if sequence is None:
            self.sequence += 1
            sequence = self.sequence
        message = foot_command_lcmt()
        message.timestamp_us = int(round((t if stamp_t is None else stamp_t) * 1e6))
        message.sequence = int(sequence)
        message.mode_request, message.frame, message.kind = command.mode_request, command.frame, command.kind
        message.value = [float(v) for v in command.value]
        message.estop = 0
        return message

    def send(self, kind: str, t: float, data: bytes, stamp: tuple[float, int] | None = None) -> None:
        self.messages.append(TimedMessage(t, self.channel, data))
        self.sent[kind] = self.sent.get(kind, 0) + 1
        if kind in TAKEN_KINDS:
            self.taken.append((stamp[0], stamp[1], data))


def _careless_command(rng: np.random.Generator) -> _Command:
    """A new command of the careless operator (module docstring: valid)."""
    mode = int(rng.choice([MODE_TELEOP, MODE_NONE, MODE_SEMI_AUTONOMOUS], p=[0.8, 0.15, 0.05]))
    frame = int(rng.choice([FRAME_TRUNK, FRAME_WORLD]))
    kind = rng.choice(len(COMMAND_SHARES), p=COMMAND_SHARES)
    if kind == 0:
        direction = rng.normal(size=3)
        value = rng.uniform(0.0, MAX_SPEED) * direction / np.linalg.norm(direction)
        return _Command(mode, frame, KIND_VELOCITY, value)
    if kind == 1:  # forward, within about 35 degrees
        direction = np.array([1.0, 0.0, 0.0]) + rng.uniform(-0.35, 0.35, 3)
        value = rng.uniform(0.5 * MAX_SPEED, MAX_SPEED) * direction / np.linalg.norm(direction)
        return _Command(mode, frame, KIND_VELOCITY, value)
    if kind == 2:
        p_B = WORKING_POSITION_B + rng.uniform(-POSITION_SPREAD, POSITION_SPREAD, 3)
        return _Command(mode, frame, KIND_POSITION, p_B if frame == FRAME_TRUNK else p_B + LIFTED_TRUNK_W)
    return _Command(mode, frame, KIND_VELOCITY, np.zeros(3))


def _some(rng: np.random.Generator) -> np.ndarray:
    """A non-empty random subset of the three values (a boolean mask)."""
    mask = rng.random(3) < 0.5
    mask[rng.integers(3)] = True
    return mask


def _wrong_code(rng: np.random.Generator, command: _Command) -> _Command:
    field = rng.integers(3)
    codes = [command.mode_request, command.frame, command.kind]
    known = ({MODE_NONE, MODE_AUTONOMOUS, MODE_TELEOP, MODE_SEMI_AUTONOMOUS}, {0, 1}, set(COMMAND_KINDS))[field]
    while codes[field] in known:
        codes[field] = int(rng.integers(-128, 128))  # int8 on the wire
    return _Command(codes[0], codes[1], codes[2], command.value)


def fuzz_stream(seed: int, count: int = FUZZ_COUNT, channel: str = "operator_foot_command") -> FuzzStream:
    """The fuzzing operator's messages (module docstring), drawn from `seed`."""
    rng = np.random.default_rng(seed)
    sender = _Sender(channel)
    teleop = _Command(MODE_TELEOP, FRAME_TRUNK, KIND_VELOCITY, np.zeros(3))

    def heartbeat(t: float, command: _Command) -> None:
        message = sender.message(command, t)
        sender.send("heartbeat", t, message.encode(), (t, message.sequence))

    for t in np.arange(int(np.floor(FUZZ_START * HEARTBEAT_RATE))) / HEARTBEAT_RATE:
        heartbeat(float(t), teleop)
    kinds = list(KINDS)
    weights = np.array(list(KINDS.values()))
    # The careless operator draws from a generator of its own: how the broken messages are drawn
    # (their bytes follow the message's size) leaves the path the foot is driven along unchanged.
    careless = np.random.default_rng([seed, 1])
    command, next_change = _careless_command(careless), FUZZ_START
    for n in range(count):
        t = FUZZ_START + n / FUZZ_RATE
        if t >= next_change:
            command, next_change = _careless_command(careless), t + careless.uniform(0.2, 1.0)
        kind = kinds[rng.choice(len(kinds), p=weights / weights.sum())]
        if kind == "valid":
            message = sender.message(command, t)
        elif kind == "huge":
            value = command.value.copy()
            mask = _some(rng)
            value[mask] = rng.choice([-1.0, 1.0], mask.sum()) * 10.0 ** rng.uniform(2.0, 308.0, mask.sum())
            message = sender.message(dataclasses.replace(command, value=value), t)
        elif kind == "nonfinite":
            value = command.value.copy()
            mask = _some(rng)
            value[mask] = rng.choice([np.nan, np.inf, -np.inf], mask.sum())
            message = sender.message(dataclasses.replace(command, value=value), t)
        elif kind == "stale":
            t_newest, sequence_newest, _ = sender.taken[-1]
            variant = rng.integers(3)
            if variant == 0:  # an earlier message again, bytes and all
                sender.send(kind, t, sender.taken[rng.integers(len(sender.taken))][2])
                continue
            if variant == 1:  # numbered like the newest taken one
                message = sender.message(command, t, sequence=sequence_newest - rng.integers(0, 100))
            else:  # stamped before the newest taken one
                message = sender.message(command, t, stamp_t=t_newest - rng.uniform(0.001, 5.0))
        elif kind == "ahead":
            if rng.random() < 0.5:
                message = sender.message(command, t, stamp_t=t + 10.0 ** rng.uniform(0.0, 6.0))
            else:
                message = sender.message(command, t, sequence=sender.sequence + int(10.0 ** rng.uniform(7.0, 15.0)))
        elif kind == "wrong_code":
            message = sender.message(_wrong_code(rng, command), t)
        elif kind == "truncated":
            data = sender.message(command, t).encode()
            if rng.random() < 0.5:
                data = data[: rng.integers(0, len(data))]
            else:
                data = data + rng.bytes(int(rng.integers(1, 17)))
            sender.send(kind, t, data)
            continue
        else:  # foreign
            if rng.random() < 0.5:
                data = rng.bytes(_ENCODED_SIZE)
            else:
                data = (rc_command_lcmt().encode() + rng.bytes(_ENCODED_SIZE))[:_ENCODED_SIZE]
            sender.send(kind, t, data)
            continue
        sender.send(kind, t, message.encode(), (message.timestamp_us * 1e-6, message.sequence))
    fuzz_end = FUZZ_START + count / FUZZ_RATE
    autonomous = _Command(MODE_AUTONOMOUS, FRAME_TRUNK, KIND_VELOCITY, np.zeros(3))
    beats = np.arange(int(np.floor(ASK_AUTONOMOUS_FOR * HEARTBEAT_RATE)) + 1) / HEARTBEAT_RATE
    for t in fuzz_end + beats:
        heartbeat(float(t), autonomous)
    expected = {reason: 0 for reason in REASON_OF_KIND.values()}
    for kind, reason in REASON_OF_KIND.items():
        expected[reason] += sender.sent.get(kind, 0)
    return FuzzStream(
        messages=sender.messages,
        sent=dict(sender.sent),
        expected={reason: n for reason, n in expected.items() if n},
        taken=sum(sender.sent.get(kind, 0) for kind in TAKEN_KINDS),
        fuzz_start=FUZZ_START,
        fuzz_end=fuzz_end,
        end=sender.messages[-1].t,
    )
