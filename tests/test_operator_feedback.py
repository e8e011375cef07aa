"""The operator's haptic feedback (foot_feedback_lcmt): what the mission writes is what a receiver
on the operator's bus decodes, at the operator period, in order."""

import math

import numpy as np
from pydrake.lcm import DrakeLcm
from pydrake.systems.analysis import Simulator

from pedi_drake.go1_driver.lcmtypes import foot_feedback_lcmt
from pedi_drake.operator.config import DEFAULT_FOOT_FEEDBACK_CHANNEL
from pedi_drake.operator.feedback import (
    FEEDBACK_SIZE,
    OperatorFeedback,
    feedback_from_message,
    feedback_message,
    feedback_vector,
)

PERIOD = 0.01  # [s]


def test_a_feedback_vector_survives_the_wire(rng):
    for _ in range(50):
        x = feedback_vector(
            int(rng.integers(-1, 4)),
            rng.normal(size=3) * 30.0,
            float(rng.uniform(0, 50)) if rng.uniform() < 0.7 else math.nan,
            float(rng.uniform(0, 60)),
            int(rng.integers(0, 6)),
            bool(rng.integers(0, 2)),
        )
        data = feedback_message(x, 1.234, 7).encode()
        decoded = foot_feedback_lcmt.decode(data)
        assert decoded.timestamp_us == 1_234_000 and decoded.sequence == 7
        np.testing.assert_array_equal(feedback_from_message(decoded), x)


def test_the_feedback_reaches_a_receiver_at_the_operator_period():
    lcm = DrakeLcm("memq://")
    received = []
    lcm.Subscribe(DEFAULT_FOOT_FEEDBACK_CHANNEL, lambda data: received.append(foot_feedback_lcmt.decode(data)))
    system = OperatorFeedback(lcm, DEFAULT_FOOT_FEEDBACK_CHANNEL, PERIOD)
    context = system.CreateDefaultContext()
    x = feedback_vector(0, np.array([-12.5, 0.25, 3.0]), 18.0, 25.9, 1, True)
    assert x.shape == (FEEDBACK_SIZE,)
    system.GetInputPort("operator_feedback").FixValue(context, x)
    simulator = Simulator(system, context)
    simulator.AdvanceTo(0.1 + 1e-9)
    lcm.HandleSubscriptions(0)
    assert [m.sequence for m in received] == list(range(1, 12))
    assert [m.timestamp_us for m in received] == [10_000 * k for k in range(11)]
    for message in received:
        np.testing.assert_array_equal(feedback_from_message(message), x)
