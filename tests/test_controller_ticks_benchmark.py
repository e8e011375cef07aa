"""benchmarks.controller_ticks: a warm second call of an update computes what the first did."""

import numpy as np
import pytest

from pedi_drake import robot
from pedi_drake.benchmarks.controller_ticks import _Variant
from pedi_drake.benchmarks.demos import demo_scenario

STANDING_BASE = np.array(
    [1.0, 0.0, 0.0, 0.0, 0.0, 0.0, robot.trunk_height_for(robot.STANDING_Q[1], robot.STANDING_Q[2])] + [0.0] * 6
)


def ticks(count: int) -> list[dict[str, np.ndarray]]:
    """`count` ticks of a standing robot whose joints drift a little."""
    rng = np.random.default_rng(3)
    return [
        {
            "base_state": STANDING_BASE,
            "position_measured": robot.STANDING_Q + 0.01 * rng.standard_normal(12),
            "velocity_measured": 0.1 * rng.standard_normal(12),
        }
        for _ in range(count)
    ]


@pytest.mark.parametrize("controller", ["whole_body", "projected_impedance"])
def test_the_warm_call_leaves_the_state_the_single_call_leaves(controller):
    scenario = demo_scenario("three_leg_hold")
    once, twice = _Variant(scenario, controller), _Variant(scenario, controller)
    for inputs in ticks(5):
        _, solved_once, not_timed = once.tick(inputs)
        _, solved_twice, again = twice.tick(inputs, warm=True)
        assert np.isnan(not_timed) and again > 0.0
        assert solved_once and solved_twice
        np.testing.assert_array_equal(
            twice.context.get_discrete_state().get_vector(twice.system.command_state).value(),
            once.context.get_discrete_state().get_vector(once.system.command_state).value(),
        )
