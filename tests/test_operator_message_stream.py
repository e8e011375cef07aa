"""An operator's stream of raw messages: kept in an LCM event log, played in lock step by a
MessagePlayer at its diagram times, played on the wall clock, and aligned to a controller's clock
by its first feedback message or to the robot's offer of a foot."""

import threading
import time

import numpy as np
import pytest
from pydrake.lcm import DrakeLcm
from pydrake.systems.analysis import Simulator

from pedi_drake.apps.teleop_lcm import controller_clock_start, offer_start
from pedi_drake.go1_driver.lcmtypes import foot_command_lcmt
from pedi_drake.operator.feedback import feedback_message, feedback_vector
from pedi_drake.operator.message_stream import (
    MessagePlayer,
    TimedMessage,
    play_messages,
    read_lcm_log,
    write_lcm_log,
)
from pedi_drake.operator.scripted_operator import ScriptedOperator, ScriptStep

STREAM = [
    TimedMessage(0.0, "a", b"\x00\x01"),
    TimedMessage(0.0015, "b", b""),  # an empty message is a message too (a truncated one)
    TimedMessage(0.0100, "a", bytes(range(60))),
]


def test_an_lcm_log_keeps_times_channels_and_bytes(tmp_path):
    assert read_lcm_log(write_lcm_log(STREAM, tmp_path / "stream.lcmlog")) == STREAM


def test_the_player_publishes_each_message_once_at_its_diagram_time():
    lcm = DrakeLcm("memq://")
    received = []
    for channel in ("a", "b"):
        lcm.Subscribe(channel, lambda data, channel=channel: received.append((channel, data)))
    player = MessagePlayer(lcm, STREAM, period=0.002)
    simulator = Simulator(player)
    simulator.Initialize()
    simulator.AdvanceTo(0.005)
    lcm.HandleSubscriptions(0)
    assert received == [("a", STREAM[0].data), ("b", b"")]
    simulator.AdvanceTo(0.1)
    lcm.HandleSubscriptions(0)
    assert len(received) == 3 and player.sent(simulator.get_context()) == 3


def test_the_wall_clock_player_sends_in_order_at_start_plus_the_time():
    clock = [100.0]
    waits, sent = [], []

    def sleep(seconds: float) -> None:
        waits.append(seconds)
        clock[0] += seconds

    def publish(channel: str, data: bytes) -> None:
        sent.append((clock[0], channel))

    count = play_messages(STREAM, publish, 100.0, sleep, lambda: clock[0])
    assert count == 3 and [channel for _, channel in sent] == ["a", "b", "a"]
    assert [t for t, _ in sent] == pytest.approx([100.0, 100.0015, 100.01])


def test_the_operator_takes_the_controllers_clock_from_its_feedback():
    lcm = DrakeLcm("memq://")
    message = feedback_message(feedback_vector(-1, None, 0.0, 0.0, 0, False), 12.5, 1).encode()
    # The controller's feedback at its diagram time 12.5 s, once the operator listens.
    threading.Timer(0.2, lambda: lcm.Publish("feedback", message)).start()
    before = time.monotonic()
    start = controller_clock_start(lcm, "feedback", timeout=2.0)
    assert before - 12.5 <= start <= time.monotonic() - 12.5
    assert controller_clock_start(DrakeLcm("memq://"), "feedback", timeout=0.1) is None


def _feedback(leg: int, t: float) -> bytes:
    return feedback_message(feedback_vector(leg, None, 0.0, 0.0, 0, False), t, 1).encode()


def test_the_operator_app_starts_when_the_robot_offers_it_the_foot():
    lcm = DrakeLcm("memq://")
    # Feedback of no driven foot first (the robot walking), then of FR driven (its teleop phase).
    threading.Timer(0.1, lambda: lcm.Publish("feedback", _feedback(-1, 40.0))).start()
    threading.Timer(0.3, lambda: lcm.Publish("feedback", _feedback(0, 41.0))).start()
    before = time.monotonic()
    start = offer_start(lcm, "feedback", "FR", timeout=2.0)
    assert before + 0.25 <= start <= time.monotonic()
    other = DrakeLcm("memq://")
    threading.Timer(0.05, lambda: other.Publish("feedback", _feedback(1, 3.0))).start()
    assert offer_start(other, "feedback", "FR", timeout=0.3) is None


def test_the_scripted_operator_waits_for_the_offer_and_counts_its_script_from_it():
    lcm = DrakeLcm("memq://")
    steps = [ScriptStep(0.0, (0.0, 0.0, 0.0)), ScriptStep(0.105, (0.0, 0.0, 0.05))]
    operator = ScriptedOperator(lcm, steps, period=0.01, start_on_leg="FR", feedback_channel="feedback")
    commands = []
    lcm.Subscribe("operator_foot_command", lambda data: commands.append(foot_command_lcmt.decode(data)))
    simulator = Simulator(operator)
    simulator.Initialize()
    lcm.Publish("feedback", _feedback(-1, 0.2))
    lcm.HandleSubscriptions(0)
    simulator.AdvanceTo(0.5)
    lcm.HandleSubscriptions(0)
    assert commands == [], "silent until the robot offers the foot"
    lcm.Publish("feedback", _feedback(0, 0.5))
    lcm.HandleSubscriptions(0)
    simulator.AdvanceTo(0.65)
    lcm.HandleSubscriptions(0)
    times = [c.timestamp_us * 1e-6 for c in commands]
    assert times[0] == pytest.approx(0.5, abs=1e-9)
    # The script's step at 0.105 s goes out at the first update 0.105 s or more after the offer.
    lifted = [t for t, c in zip(times, commands, strict=True) if c.value[2] > 0.0]
    assert lifted[0] == pytest.approx(0.61, abs=1e-9) and all(t < 0.61 for t in times if t not in lifted)


class _CountingProgram:
    """A program whose state counts its commands and whose command carries the force it was given."""

    @staticmethod
    def initial_state() -> int:
        return 0

    @staticmethod
    def command(state: int, t: float, force_W):
        if state >= 3:
            return None, state
        felt = 0.0 if force_W is None else float(force_W[2])
        return ScriptStep(t, (0.0, 0.0, felt)), state + 1


def test_the_scripted_operator_runs_a_program_on_the_feedback_it_feels():
    lcm = DrakeLcm("memq://")
    operator = ScriptedOperator(
        lcm, program=_CountingProgram(), period=0.01, start_on_leg="FR", feedback_channel="feedback"
    )
    commands = []
    lcm.Subscribe("operator_foot_command", lambda data: commands.append(foot_command_lcmt.decode(data)))
    simulator = Simulator(operator)
    simulator.Initialize()
    pushed = feedback_message(feedback_vector(0, np.array([0.0, 0.0, 7.5]), 15.0, 0.0, 0, False), 0.1, 1)
    lcm.Publish("feedback", pushed.encode())
    lcm.HandleSubscriptions(0)
    simulator.AdvanceTo(0.2)
    lcm.HandleSubscriptions(0)
    # Three commands, each with the force the program felt; then the program is over (silent).
    assert [c.value[2] for c in commands] == [7.5, 7.5, 7.5]
    with pytest.raises(ValueError, match="give start_on_leg"):
        ScriptedOperator(lcm, program=_CountingProgram())
