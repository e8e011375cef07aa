"""Runtime controller switching (pedi_drake.control.controller_switch): the blend, the requests'
precedence, the configuration's checks and a run with random switches while a foot is lifted."""

import numpy as np
import pytest
from pydrake.systems.framework import DiagramBuilder

from pedi_drake.benchmarks.controller_switches import one_run, request_times
from pedi_drake.control.controller_switch import (
    COMMAND_SIZE,
    ControllerSwitch,
    next_request,
    step_weight,
)
from pedi_drake.exceptions import ConfigError, ScenarioError
from pedi_drake.operator.command import (
    CONTROLLER_NONE,
    CONTROLLER_PROJECTED_IMPEDANCE,
    CONTROLLER_WHOLE_BODY,
    OPERATOR_COMMAND_SIZE,
)
from pedi_drake.scenario import load_scenario

PERIOD = 0.002
HQP, PAPER002 = CONTROLLER_WHOLE_BODY, CONTROLLER_PROJECTED_IMPEDANCE


def test_the_newest_changed_request_wins_and_none_changes_nothing():
    assert next_request(HQP, (CONTROLLER_NONE, CONTROLLER_NONE), (CONTROLLER_NONE, CONTROLLER_NONE)) == HQP
    assert next_request(HQP, (CONTROLLER_NONE, CONTROLLER_NONE), (PAPER002, CONTROLLER_NONE)) == PAPER002
    # A request that stands (seen before) does not switch back after another source switched.
    assert next_request(HQP, (PAPER002, CONTROLLER_NONE), (PAPER002, CONTROLLER_NONE)) == HQP
    assert next_request(PAPER002, (PAPER002, CONTROLLER_NONE), (PAPER002, HQP)) == HQP


def test_the_weight_moves_at_one_over_the_blend_time_and_stops_at_its_end():
    weight, trace = 1.0, []
    for _ in range(60):
        weight = step_weight(weight, PAPER002, PERIOD, 0.1)
        trace.append(weight)
    assert trace[0] == pytest.approx(1.0 - PERIOD / 0.1)
    assert trace[49] == pytest.approx(0.0, abs=1e-12) and trace[-1] == 0.0
    assert step_weight(0.3, HQP, PERIOD, 0.0) == 1.0  # no blend: a step


def _switch_context(blend_time: float):
    builder = DiagramBuilder()
    switch = builder.AddSystem(ControllerSwitch("whole_body", PERIOD, blend_time))
    diagram = builder.Build()
    context = diagram.CreateDefaultContext()
    sub = switch.GetMyMutableContextFromRoot(context)
    hqp, paper002 = np.full(COMMAND_SIZE, 1.0), np.full(COMMAND_SIZE, -1.0)
    switch.command_ports["whole_body"].FixValue(sub, hqp)
    switch.command_ports["projected_impedance"].FixValue(sub, paper002)
    switch.mission_request_port.FixValue(sub, [CONTROLLER_NONE])
    return diagram, switch, context, sub


def _advance(diagram, switch, context, sub, ticks: int) -> list[float]:
    """The command's first entry after each of `ticks` periodic updates."""
    values = []
    for _ in range(ticks):
        sub.SetDiscreteState(switch.EvalUniquePeriodicDiscreteUpdate(sub))
        values.append(float(switch.GetOutputPort("command").Eval(sub)[0]))
    return values


def test_a_request_reversed_mid_blend_turns_the_command_back_without_a_jump():
    diagram, switch, context, sub = _switch_context(0.1)
    assert switch.GetOutputPort("command").Eval(sub)[0] == 1.0  # the HQP drives; no operator connected
    switch.mission_request_port.FixValue(sub, [PAPER002])
    there = _advance(diagram, switch, context, sub, 20)
    switch.mission_request_port.FixValue(sub, [HQP])
    back = _advance(diagram, switch, context, sub, 60)
    trace = np.array([1.0, *there, *back])
    # The two commands differ by 2: each tick moves the blend by at most 2 * period / blend_time.
    assert np.max(np.abs(np.diff(trace))) <= 2.0 * PERIOD / 0.1 + 1e-12
    assert there[-1] == pytest.approx(1.0 - 2.0 * 20 * PERIOD / 0.1)
    assert back[-1] == 1.0
    active, weight, switches = switch.GetOutputPort("switch_state").Eval(sub)
    assert (active, weight, switches) == (HQP, 1.0, 2)


def test_the_operators_request_switches_too():
    diagram, switch, context, sub = _switch_context(0.0)
    command = np.zeros(OPERATOR_COMMAND_SIZE)
    command[10] = PAPER002
    switch.operator_port.FixValue(sub, command)
    assert _advance(diagram, switch, context, sub, 1) == [-1.0]
    command[10] = 7.0  # not a controller: ignored
    switch.operator_port.FixValue(sub, command)
    assert _advance(diagram, switch, context, sub, 1) == [-1.0]


@pytest.mark.parametrize(
    ("text", "field"),
    [
        ("{controller: stand_pd, controller_switch: {enabled: true}}", "controller"),
        ("{controller: whole_body, controller_switch: {enabled: true}, force_estimate: impedance}", "force_estimate"),
        (
            "{controller: whole_body, controller_switch: {enabled: true, blend_time: -0.1}}",
            "controller_switch.blend_time",
        ),
    ],
)
def test_a_bad_switch_configuration_names_its_field(text, field):
    with pytest.raises(ScenarioError, match=field):
        load_scenario(scenario_text=text)


def test_the_switch_needs_a_known_first_controller():
    with pytest.raises(ConfigError, match="stand_pd"):
        ControllerSwitch("stand_pd", PERIOD, 0.1)


def test_twenty_random_switches_with_a_foot_lifted_step_no_target_beyond_the_rate_limit():
    # One noisy seed of `python -m pedi_drake.benchmarks.controller_switches` (6 seeds there).
    row = one_run(3, 20)
    print(f"\n{row}")
    assert len(request_times(3, 20)) == 20
    assert row["success"] and not row["fell"], row["reason"]
    assert row["switches"] >= 20 + 4  # the operator's and the mission's own
    assert row["max_target_step_rad"] <= row["target_step_limit_rad"]
    assert row["lifted_foot_stray_m"] < 0.02
