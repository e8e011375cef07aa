"""The operator input: valid foot commands and remote messages come through; malformed ones are
dropped and counted by reason; the heartbeat ages; the E-stop latches."""

import math
import os
import time

import numpy as np
import pytest
from pydrake.lcm import DrakeLcm
from pydrake.systems.analysis import Simulator

from pedi_drake.go1_driver.lcmtypes import foot_command_lcmt, rc_command_lcmt
from pedi_drake.operator.command import FRAME_WORLD, KIND_POSITION, MODE_AUTONOMOUS, MODE_TELEOP, OperatorCommand
from pedi_drake.operator.config import OperatorConfig
from pedi_drake.operator.operator_input import SENDER_TAKEOVER_SILENCE, OperatorInput
from pedi_drake.operator.scripted_operator import ScriptStep, foot_command_message

CHANNEL = "operator_foot_command"


PERIOD = 0.01  # [s]


def _make(source: str):
    """(bus, system, simulator): the input alone, its periodic update run by a Simulator."""
    lcm = DrakeLcm("memq://")
    system = OperatorInput(OperatorConfig(source=source, period=PERIOD), lcm)
    simulator = Simulator(system)
    simulator.Initialize()
    return lcm, system, simulator


def _tick(system, simulator, t: float) -> OperatorCommand:
    """The command at `t` [s], after the updates up to `t` (the last one within a period of it)."""
    simulator.AdvanceTo(t)
    return OperatorCommand.from_vector(system.get_output_port().Eval(simulator.get_context()))


def test_a_foot_command_comes_through_and_then_ages():
    lcm, system, context = _make("lcm")
    assert math.isinf(_tick(system, context, 0.0).age)
    step = ScriptStep(0.0, (0.1, -0.2, 0.3), mode_request=MODE_TELEOP, frame=FRAME_WORLD, kind=KIND_POSITION)
    lcm.Publish(CHANNEL, foot_command_message(step, 0.0, 1).encode())
    command = _tick(system, context, 0.5)
    assert (command.mode_request, command.frame, command.kind) == (MODE_TELEOP, FRAME_WORLD, KIND_POSITION)
    np.testing.assert_allclose(command.value, [0.1, -0.2, 0.3])
    # Taken in by the first update after it was sent (t = 0.01 s): 0.49 s old at t = 0.5 s.
    assert command.age == pytest.approx(0.5 - PERIOD) and command.received == 1 and not command.estop
    assert _tick(system, context, 0.8).age == pytest.approx(0.3 + command.age, abs=1e-9)


def _valid() -> foot_command_lcmt:
    return foot_command_message(ScriptStep(0.0, (0.01, 0.0, 0.0), mode_request=MODE_TELEOP), 0.0, 1)


def _padded_to_foot_command_size(data: bytes) -> bytes:
    return data + bytes(len(_valid().encode()) - len(data))


def _with(**fields) -> bytes:
    message = _valid()
    for name, value in fields.items():
        setattr(message, name, value)
    return message.encode()


@pytest.mark.parametrize(
    ("data", "reason"),
    [
        (_valid().encode()[:-3], "wrong_size"),
        (_padded_to_foot_command_size(rc_command_lcmt().encode()), "wrong_fingerprint"),
        (_with(value=[float("nan"), 0.0, 0.0]), "nonfinite"),
        (_with(value=[0.0, float("inf"), 0.0]), "nonfinite"),
        (_with(mode_request=7), "out_of_range"),
        (_with(frame=2), "out_of_range"),
        (_with(kind=-1), "out_of_range"),
        (_with(friction_request=0.01), "out_of_range"),
        (_with(friction_request=1.6), "out_of_range"),
        (_with(friction_request=float("nan")), "nonfinite"),
    ],
)
def test_a_malformed_foot_command_is_dropped_and_counted_by_reason(data, reason):
    lcm, system, context = _make("lcm")
    lcm.Publish(CHANNEL, _valid().encode())
    before = _tick(system, context, 0.1)
    lcm.Publish(CHANNEL, data)
    after = _tick(system, context, 0.2)
    assert system.counts()["rejected"] == {reason: 1}
    assert after.dropped == 1 and after.received == 1
    np.testing.assert_array_equal(after.value, before.value)
    assert after.age == pytest.approx(before.age + 0.1, abs=1e-9)  # a dropped message is no heartbeat


def _stamped(t: float, sequence: int, value=(0.01, 0.0, 0.0)) -> bytes:
    return foot_command_message(ScriptStep(0.0, value, mode_request=MODE_TELEOP), t, sequence).encode()


@pytest.mark.parametrize(
    ("t", "sequence", "reason"),
    [
        (0.1, 2, "out_of_order"),  # the newest one again
        (0.1, 1, "out_of_order"),  # numbered before it
        (0.05, 3, "out_of_order"),  # stamped before it
        (1.2, 3, "stamp_ahead"),  # a second ahead of what the receiver saw pass
        (0.15, 2 + 10**7, "stamp_ahead"),  # numbered ten million ahead
    ],
)
def test_a_late_replayed_or_future_foot_command_is_dropped_while_the_sender_is_live(t, sequence, reason):
    lcm, system, context = _make("lcm")
    lcm.Publish(CHANNEL, _stamped(0.0, 1))
    lcm.Publish(CHANNEL, _stamped(0.1, 2, (0.02, 0.0, 0.0)))
    _tick(system, context, 0.1)
    lcm.Publish(CHANNEL, _stamped(t, sequence, (0.05, 0.0, 0.0)))
    command = _tick(system, context, 0.2)
    assert system.counts()["rejected"] == {reason: 1}
    assert command.received == 2 and command.value[0] == pytest.approx(0.02)
    lcm.Publish(CHANNEL, _stamped(0.2, 3, (0.03, 0.0, 0.0)))  # the next one in order comes through
    assert _tick(system, context, 0.3).value[0] == pytest.approx(0.03)


def test_a_restarted_sender_is_taken_after_a_silence():
    lcm, system, context = _make("lcm")
    lcm.Publish(CHANNEL, _stamped(5.0, 500))
    _tick(system, context, 0.1)
    restarted = _stamped(0.0, 1, (0.03, 0.0, 0.0))  # its clock and its numbers start again
    lcm.Publish(CHANNEL, restarted)
    _tick(system, context, 0.2)
    assert system.counts()["rejected"] == {"out_of_order": 1}  # the first sender may still be live
    _tick(system, context, SENDER_TAKEOVER_SILENCE + 0.1)
    lcm.Publish(CHANNEL, restarted)
    command = _tick(system, context, SENDER_TAKEOVER_SILENCE + 0.2)
    assert command.received == 2 and command.value[0] == pytest.approx(0.03)


def test_every_message_of_a_burst_on_a_udp_bus_is_taken_or_counted():
    # Between two polls a UDP bus may bring many messages (a 1 kHz operator, a burst after a
    # stall): none may be lost uncounted, an E-stop among them least of all.
    url = f"udpm://239.255.76.67:{20000 + os.getpid() % 20000}?ttl=0"
    system = OperatorInput(OperatorConfig(source="lcm", period=PERIOD), DrakeLcm(url))
    simulator = Simulator(system)
    simulator.Initialize()
    publisher = DrakeLcm(url)
    for k in range(50):
        publisher.Publish(CHANNEL, _stamped(0.001 * k, k + 1))
    publisher.Publish(CHANNEL, b"\x00\x01\x02")
    publisher.Publish(CHANNEL, foot_command_message(ScriptStep(0.0, estop=True), 0.05, 51).encode())
    time.sleep(0.2)  # all of it arrived before the first poll
    command = _tick(system, simulator, 0.0)
    assert command.received == 51 and system.counts()["rejected"] == {"wrong_size": 1}
    assert command.estop


def test_the_estop_latches_and_a_mode_request_stands():
    lcm, system, context = _make("lcm")
    lcm.Publish(CHANNEL, foot_command_message(ScriptStep(0.0, estop=True, mode_request=MODE_AUTONOMOUS), 0, 1).encode())
    _tick(system, context, 0.1)
    lcm.Publish(CHANNEL, foot_command_message(ScriptStep(0.0), 0.1, 2).encode())  # no request, no E-stop
    command = _tick(system, context, 0.2)
    assert command.estop and command.mode_request == MODE_AUTONOMOUS


def test_a_friction_request_stands_until_another():
    lcm, system, context = _make("lcm")
    lcm.Publish(CHANNEL, foot_command_message(ScriptStep(0.0, friction_request=0.3), 0, 1).encode())
    assert _tick(system, context, 0.1).friction_request == 0.3
    lcm.Publish(CHANNEL, foot_command_message(ScriptStep(0.0), 0.1, 2).encode())  # no request
    assert _tick(system, context, 0.2).friction_request == 0.3
    lcm.Publish(CHANNEL, foot_command_message(ScriptStep(0.0, friction_request=1.1), 0.2, 3).encode())
    assert _tick(system, context, 0.3).friction_request == 1.1


def _remote(**fields) -> bytes:
    message = rc_command_lcmt()
    for name, value in fields.items():
        setattr(message, name, value)
    return message.encode()


def test_the_remote_sticks_and_buttons_map_to_foot_velocity_mode_and_estop():
    lcm, system, context = _make("remote")
    lcm.Publish("rc_command", _remote(left_stick=[0.0, 1.0], right_stick=[0.0, 0.0], right_upper_switch=1))
    command = _tick(system, context, 0.1)
    np.testing.assert_allclose(command.value, [0.1, 0.0, 0.0])  # full stick forward = max_speed along +x
    assert command.mode_request == MODE_TELEOP and not command.estop
    lcm.Publish("rc_command", _remote(left_stick=[0.02, 0.0], right_stick=[0.0, -0.5]))  # in the dead band / down
    command = _tick(system, context, 0.2)
    assert command.value[0] == 0.0 and command.value[1] == 0.0 and command.value[2] < 0.0
    lcm.Publish("rc_command", _remote(right_lower_right_switch=1))
    assert _tick(system, context, 0.3).estop


@pytest.mark.parametrize(("sticks", "reason"), [([float("nan"), 0.0], "nonfinite"), ([3.0, 0.0], "out_of_range")])
def test_a_broken_remote_message_is_dropped_and_counted(sticks, reason):
    lcm, system, context = _make("remote")
    lcm.Publish("rc_command", _remote(left_stick=sticks))
    command = _tick(system, context, 0.1)
    assert system.counts()["rejected"] == {reason: 1}
    assert command.received == 0 and math.isinf(command.age)
