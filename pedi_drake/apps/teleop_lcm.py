"""A command-line operator: foot commands (foot_command_lcmt) on the scenario's LCM bus.

    python -m pedi_drake.apps.teleop_lcm [--scenario_file FILE --scenario_name NAME]
                                         [--scenario_text YAML] [--lcm_url URL] [--speed M_PER_S]
                                         [--rate HZ] [--frame trunk|world] [--script FILE]

In a terminal, keys set the command, which is sent `--rate` times a second until `q`:

    w / s   foot forward / back (+x / -x)     t      ask for the teleoperated foot
    a / d   foot left / right   (+y / -y)     g      ask for the autonomous mission (go)
    r / f   foot up / down      (+z / -z)     space  stop the foot (zero velocity)
    e       E-stop (latched by the robot)     q      quit (the robot sees the operator fall silent)
    1 / 2   ask for the HQP / paper 002's controller (a scenario with controller_switch runs both)

A velocity key holds its velocity (`--speed`, in `--frame`) until space or another velocity key:
a terminal reports key presses, not releases. Below the command, the line shows the controller's
latest haptic feedback (the scenario's `operator.feedback_channel`): the estimated force on the
driven foot, the balance bound's limit along it and the margin left, and the live SUF.

With `--script FILE`, or when stdin is not a terminal, the commands come from a script instead:
one step per line, `t_s mode vx vy vz` (time from the start [s], increasing; mode `none`,
`teleop`, `autonomous` or `estop`, or `hqp` / `paper002` to ask for a controller; the foot
velocity [m/s]) or `t_s friction mu` (the ground friction coefficient the controllers are to use,
in [0.05, 1.5], sent with the previous step's command), `#` starts a comment. Each step
holds until the next one's time; the app ends at the last step's time. A malformed script exits
with status 2 and names the file and line.

With `--lcm_log FILE` it plays a recorded or generated stream of messages instead (an LCM event
log, as lcm-logger writes: each event on its own channel at its time from the log's first event,
whatever its bytes; pedi_drake.operator.message_stream), e.g. the fuzzed operator of
`python -m pedi_drake.benchmarks.teleop`.

`--search_button HEADING_DEG` runs an operator program instead of a script: it waits for the
robot's offer of `--start_on_leg` (FR), then finds an E-stop button's cap by touch in front of the
foot and presses it (pedi_drake.operator.button_search), the robot facing HEADING_DEG (world yaw),
reading the haptic feedback as it goes.

`--start_on_feedback` waits (up to `--start_timeout` s) for the controller's first haptic
feedback message (the scenario's `operator.feedback_channel`) and plays the script or the log
on the controller's clock: the step or message of time t goes out when the controller's
diagram time is t (the feedback carries it), so an operator started before the controller still
acts at the moments it was written for. `--start_on_leg LEG` waits instead for the first
feedback that reports that foot driven (the robot offers it: a teleop_foot phase has begun) and
plays the script from then, its times counted from that moment, as an operator does at the end
of a mission whose length it cannot know.

The bus and channel are the scenario's (`operator.lcm_bus` in `lcm_buses`, `operator.channel`),
the ones `run_sim.py` with `operator: {source: lcm}` listens on.
"""

import argparse
import contextlib
import dataclasses
import math
import select
import sys
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np
from pydrake.lcm import DrakeLcm, DrakeLcmInterface

from pedi_drake.exceptions import PediError
from pedi_drake.friction import FRICTION_RANGE
from pedi_drake.go1_driver.lcmtypes import foot_feedback_lcmt
from pedi_drake.operator.button_search import ButtonSearch
from pedi_drake.operator.command import (
    CONTROLLER_NONE,
    CONTROLLER_PROJECTED_IMPEDANCE,
    CONTROLLER_WHOLE_BODY,
    FRAME_TRUNK,
    FRAME_WORLD,
    MODE_AUTONOMOUS,
    MODE_NONE,
    MODE_TELEOP,
)
from pedi_drake.operator.message_stream import play_messages, read_lcm_log
from pedi_drake.operator.scripted_operator import ScriptStep, foot_command_message, script_stream
from pedi_drake.robot import LEG_NAMES
from pedi_drake.scenario import load_scenario

SCRIPT_MODES = {
    "none": MODE_NONE,
    "teleop": MODE_TELEOP,
    "autonomous": MODE_AUTONOMOUS,
    "estop": MODE_NONE,
    "hqp": MODE_NONE,
    "paper002": MODE_NONE,
}
# Script words and keys that ask for a controller.
SCRIPT_CONTROLLERS = {"hqp": CONTROLLER_WHOLE_BODY, "paper002": CONTROLLER_PROJECTED_IMPEDANCE}
CONTROLLER_KEYS = {"1": CONTROLLER_WHOLE_BODY, "2": CONTROLLER_PROJECTED_IMPEDANCE}
# Key -> unit direction of the foot velocity (x forward, y left, z up).
VELOCITY_KEYS = {
    "w": (1.0, 0.0, 0.0),
    "s": (-1.0, 0.0, 0.0),
    "a": (0.0, 1.0, 0.0),
    "d": (0.0, -1.0, 0.0),
    "r": (0.0, 0.0, 1.0),
    "f": (0.0, 0.0, -1.0),
}
MODE_KEYS = {"t": MODE_TELEOP, "g": MODE_AUTONOMOUS}
DEFAULT_SPEED = 0.05  # [m/s]
DEFAULT_RATE = 50.0  # [Hz]: well above the operator input's 0.2 s hold-after silence


class ScriptError(PediError):
    """A script line that is not `t_s mode vx vy vz`."""


def _friction_step(words: list[str], steps: list[ScriptStep], where: str, line: str) -> ScriptStep:
    """The step of a `t_s friction mu` line: the previous step's command with the friction request."""
    try:
        t, mu = float(words[0]), float(words[2])
    except ValueError:
        raise ScriptError(f"{where}: time and friction coefficient must be numbers, got {line.strip()!r}") from None
    low, high = FRICTION_RANGE
    if not (math.isfinite(mu) and low <= mu <= high):
        raise ScriptError(f"{where}: the friction coefficient must be in [{low}, {high}], got {words[2]!r}")
    if not math.isfinite(t) or t < 0 or (steps and t <= steps[-1].start):
        raise ScriptError(f"{where}: times must be >= 0 s and increasing, got {t} after the previous step")
    previous = steps[-1] if steps else ScriptStep(t)
    return dataclasses.replace(previous, start=t, estop=False, friction_request=mu)


def parse_script(text: str, source: str = "<script>", frame: int = FRAME_TRUNK) -> list[ScriptStep]:
    """The steps of a script (see the module docstring); raises ScriptError naming `source` and the line."""
    steps: list[ScriptStep] = []
    for number, line in enumerate(text.splitlines(), start=1):
        words = line.split("#", 1)[0].split()
        if not words:
            continue
        where = f"{source}:{number}"
        if len(words) == 3 and words[1] == "friction":
            steps.append(_friction_step(words, steps, where, line))
            continue
        if len(words) != 5:
            raise ScriptError(f"{where}: expected 't_s mode vx vy vz' or 't_s friction mu', got {line.strip()!r}")
        try:
            t, vx, vy, vz = (float(words[k]) for k in (0, 2, 3, 4))
        except ValueError:
            raise ScriptError(f"{where}: time and velocities must be numbers, got {line.strip()!r}") from None
        if not all(math.isfinite(v) for v in (t, vx, vy, vz)):
            raise ScriptError(f"{where}: time and velocities must be finite, got {line.strip()!r}")
        if words[1] not in SCRIPT_MODES:
            raise ScriptError(f"{where}: mode must be one of {tuple(SCRIPT_MODES)}, got {words[1]!r}")
        if t < 0 or (steps and t <= steps[-1].start):
            raise ScriptError(f"{where}: times must be >= 0 s and increasing, got {t} after the previous step")
        steps.append(
            ScriptStep(
                t,
                (vx, vy, vz),
                mode_request=SCRIPT_MODES[words[1]],
                frame=frame,
                estop=words[1] == "estop",
                controller_request=SCRIPT_CONTROLLERS.get(words[1], CONTROLLER_NONE),
            )
        )
    if not steps:
        raise ScriptError(f"{source}: no steps")
    return steps


def play_script(
    steps: list[ScriptStep],
    lcm: DrakeLcmInterface,
    channel: str,
    rate: float,
    sleep: Callable[[float], None] = time.sleep,
    clock: Callable[[], float] = time.monotonic,
    start: float | None = None,
) -> int:
    """Publishes the script on `channel` at `rate` [Hz], each message at `start` (default: now) +
    its time on `clock` [s], to the last step's time; the number of messages."""
    messages = script_stream(steps, rate, steps[-1].start, channel)
    return play_messages(messages, lcm.Publish, clock() if start is None else start, sleep, clock)


def controller_clock_start(lcm: DrakeLcmInterface, channel: str, timeout: float) -> float | None:
    """The wall-clock time (time.monotonic) [s] at which the controller's diagram time was 0,
    from its first foot_feedback_lcmt on `channel`; None when none came within `timeout` [s]."""
    arrived = []

    def take(data: bytes) -> None:
        if not arrived:
            arrived.append((time.monotonic(), foot_feedback_lcmt.decode(data).timestamp_us * 1e-6))

    lcm.Subscribe(channel, take)
    deadline = time.monotonic() + timeout
    while not arrived and time.monotonic() < deadline:
        lcm.HandleSubscriptions(50)
    if not arrived:
        return None
    wall, diagram_time = arrived[0]
    return wall - diagram_time


def run_program(
    lcm: DrakeLcmInterface, channel: str, feedback_channel: str, leg: str, program, rate: float, start: float
) -> int:
    """Runs operator `program` (pedi_drake.operator.scripted_operator) at `rate` [Hz] from `start`
    (time.monotonic, the robot's offer of `leg`), reading the latest haptic feedback's force on
    `feedback_channel` before each command; the number of messages sent."""
    index = LEG_NAMES.index(leg)
    force: list[np.ndarray] = []

    def take(data: bytes) -> None:
        message = foot_feedback_lcmt.decode(data)
        if message.leg == index:
            force[:] = [np.array(message.force, float)]

    lcm.Subscribe(feedback_channel, take)
    state, sequence = program.initial_state(), 0
    while True:
        lcm.HandleSubscriptions(0)
        t = time.monotonic() - start
        step, state = program.command(state, t, force[0] if force else None)
        if step is None:
            return sequence
        sequence += 1
        lcm.Publish(channel, foot_command_message(step, t, sequence).encode())
        time.sleep(max(0.0, start + sequence / rate - time.monotonic()))


def offer_start(lcm: DrakeLcmInterface, channel: str, leg: str, timeout: float) -> float | None:
    """The wall-clock time (time.monotonic) [s] of the first foot_feedback_lcmt on `channel` that
    reports `leg` driven; None when none came within `timeout` [s]."""
    index = LEG_NAMES.index(leg)
    arrived = []

    def take(data: bytes) -> None:
        if not arrived and foot_feedback_lcmt.decode(data).leg == index:
            arrived.append(time.monotonic())

    lcm.Subscribe(channel, take)
    deadline = time.monotonic() + timeout
    while not arrived and time.monotonic() < deadline:
        lcm.HandleSubscriptions(50)
    return arrived[0] if arrived else None


class KeyboardOperator:
    """The command the keys have set so far (see the module docstring)."""

    def __init__(self, speed: float, frame: int):
        self.step = ScriptStep(0.0, frame=frame)
        self._speed = speed

    def press(self, key: str) -> bool:
        """Takes one key; False for quit."""
        step = self.step
        if key == "q":
            return False
        if key in VELOCITY_KEYS:
            self.step = dataclasses.replace(step, value=tuple(self._speed * np.array(VELOCITY_KEYS[key])))
        elif key == " ":
            self.step = dataclasses.replace(step, value=(0.0, 0.0, 0.0))
        elif key in MODE_KEYS:
            self.step = dataclasses.replace(step, mode_request=MODE_KEYS[key])
        elif key in CONTROLLER_KEYS:
            self.step = dataclasses.replace(step, controller_request=CONTROLLER_KEYS[key])
        elif key == "e":
            self.step = dataclasses.replace(step, value=(0.0, 0.0, 0.0), estop=True)
        return True


@contextlib.contextmanager
def _raw_terminal():
    """stdin unbuffered and without echo for the block (restored after, also on Ctrl-C)."""
    import termios
    import tty

    saved = termios.tcgetattr(sys.stdin)
    try:
        tty.setcbreak(sys.stdin.fileno())
        yield
    finally:
        termios.tcsetattr(sys.stdin, termios.TCSADRAIN, saved)


def feedback_text(message: foot_feedback_lcmt | None) -> str:
    """One line of what a foot_feedback_lcmt says: the driven foot's estimated force [N], the
    balance bound's limit along it and the margin left [N], the live SUF [N]."""
    if message is None:
        return "no feedback yet"
    if message.leg < 0:
        return "no foot driven"
    force = np.array(message.force, float)
    text = f"{LEG_NAMES[message.leg]} foot force {np.linalg.norm(force):5.1f} N {np.round(force, 1)}"
    if math.isfinite(message.force_limit):
        along = float(np.linalg.norm(force))
        text += f" | balance limit {message.force_limit:5.1f} N, margin {message.force_limit - along:5.1f} N"
    else:
        text += " | balance bound off"
    if math.isfinite(message.suf):
        text += f" | SUF {message.suf:5.1f} N"
    return text + (" | BOUND ACTING" if message.bound_active else "")


def run_keyboard(
    lcm: DrakeLcmInterface, channel: str, feedback_channel: str, rate: float, speed: float, frame: int
) -> int:
    """Sends the keys' command at `rate` [Hz] until `q`, showing the latest feedback on
    `feedback_channel`; the number of messages."""
    operator, count, start = KeyboardOperator(speed, frame), 0, time.monotonic()
    latest = []

    def take(data: bytes) -> None:
        latest[:] = [foot_feedback_lcmt.decode(data)]

    if feedback_channel:
        lcm.Subscribe(feedback_channel, take)
    print(__doc__.split("\n\n")[2], flush=True)
    with _raw_terminal():
        while True:
            ready, _, _ = select.select([sys.stdin], [], [], 1.0 / rate)
            if ready and not operator.press(sys.stdin.read(1)):
                return count
            lcm.HandleSubscriptions(0)
            t = time.monotonic() - start
            count += 1
            lcm.Publish(channel, foot_command_message(operator.step, t, count).encode())
            step = operator.step
            print(
                f"\rmode {step.mode_request} v {np.round(step.value, 3)} m/s estop {step.estop} | "
                f"{feedback_text(latest[0] if latest else None)}   ",
                end="",
                flush=True,
            )


def add_operator_bus_arguments(parser: argparse.ArgumentParser) -> None:
    """The flags that name the operator's bus: the scenario (file, name, text, as run_sim.py takes
    them) whose `operator:` and `lcm_buses:` it reads, or a URL."""
    parser.add_argument("--scenario_file", default=None, help="YAML file of named scenarios (default: the shipped one)")
    parser.add_argument("--scenario_name", default="default", help="scenario to read from --scenario_file")
    parser.add_argument("--scenario_text", default="{}", help="YAML mapping merged onto the scenario (as run_sim.py)")
    parser.add_argument("--lcm_url", default="", help="the bus URL (default: the scenario's operator bus)")


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    add_operator_bus_arguments(parser)
    parser.add_argument("--speed", type=float, default=DEFAULT_SPEED, help="foot speed of a key [m/s]")
    parser.add_argument("--rate", type=float, default=DEFAULT_RATE, help="messages a second [Hz]")
    parser.add_argument("--frame", choices=("trunk", "world"), default="trunk")
    parser.add_argument("--script", default="", help="script file (t_s mode vx vy vz per line)")
    parser.add_argument("--lcm_log", default="", help="an LCM event log of messages to play instead")
    parser.add_argument(
        "--start_on_feedback", action="store_true", help="play on the controller's clock, from its first feedback"
    )
    parser.add_argument(
        "--start_on_leg", choices=LEG_NAMES, default=None, help="play from the robot's offer of this foot"
    )
    parser.add_argument("--start_timeout", type=float, default=120.0, help="longest wait for that feedback [s]")
    parser.add_argument(
        "--search_button", type=float, default=None, help="find and press an E-stop button by touch, facing this [deg]"
    )
    args = parser.parse_args(argv)
    if not (math.isfinite(args.rate) and args.rate > 0 and math.isfinite(args.speed) and args.speed > 0):
        print("--rate and --speed must be finite numbers > 0", file=sys.stderr)
        return 2
    frame = FRAME_TRUNK if args.frame == "trunk" else FRAME_WORLD
    try:
        scenario = load_scenario(
            filename=args.scenario_file, scenario_name=args.scenario_name, scenario_text=args.scenario_text
        )
        config = scenario.operator
        url = args.lcm_url or scenario.lcm_buses[config.lcm_bus].lcm_url
        steps = messages = None
        if args.lcm_log:
            messages = read_lcm_log(Path(args.lcm_log))
            if not messages:
                raise ScriptError(f"{args.lcm_log}: no messages")
        elif args.search_button is None and (args.script or not sys.stdin.isatty()):
            source = args.script or "<stdin>"
            text = Path(args.script).read_text() if args.script else sys.stdin.read()
            steps = parse_script(text, source, frame)
    except (PediError, OSError, ValueError) as error:
        print(error, file=sys.stderr)
        return 2
    lcm = DrakeLcm(url)
    start = None
    if args.start_on_feedback:
        # A bus of its own, closed once the clock is known: this one, with no subscription, never
        # reads (and never queues) what the robot and the controller publish.
        start = controller_clock_start(DrakeLcm(url), config.feedback_channel, args.start_timeout)
        if start is None:
            print(f"no feedback on {config.feedback_channel} within {args.start_timeout} s", file=sys.stderr)
            return 1
    elif args.start_on_leg or args.search_button is not None:
        start = offer_start(DrakeLcm(url), config.feedback_channel, args.start_on_leg or "FR", args.start_timeout)
        if start is None:
            print(
                f"no offer of {args.start_on_leg} on {config.feedback_channel} within {args.start_timeout} s",
                file=sys.stderr,
            )
            return 1
    if args.search_button is not None:
        program = ButtonSearch(math.radians(args.search_button))
        leg = args.start_on_leg or "FR"
        count = run_program(lcm, config.channel, config.feedback_channel, leg, program, args.rate, start)
        print(f"sent {count} foot commands searching for the button on {config.channel} ({url})")
        return 0
    if messages is not None:
        count = play_messages(messages, lcm.Publish, time.monotonic() if start is None else start)
        print(f"sent {count} messages of {args.lcm_log} ({url})")
        return 0
    if steps is not None:
        count = play_script(steps, lcm, config.channel, args.rate, start=start)
    else:
        count = run_keyboard(lcm, config.channel, config.feedback_channel, args.rate, args.speed, frame)
    print(f"\nsent {count} foot commands on {config.channel} ({url})")
    return 0


if __name__ == "__main__":
    sys.exit(main())
