"""The controllers' friction coefficient changed at run time: by a set_friction phase and by the
operator's friction request, reaching both whole-body controllers, logged and in result.json; a
coefficient outside FRICTION_RANGE refused on load (a phase) or dropped (a message)."""

import numpy as np
import pytest

from pedi_drake.evaluation import judge
from pedi_drake.exceptions import MissionFileError
from pedi_drake.friction import FRICTION_RANGE
from pedi_drake.mission.spec import load_mission
from pedi_drake.operator.config import DEFAULT_FOOT_COMMAND_CHANNEL
from pedi_drake.operator.scripted_operator import ScriptStep, script_stream
from pedi_drake.run import simulate
from pedi_drake.scenario import load_scenario

MISSION = """
phases:
  - {kind: wait, duration: 0.3}
  - {kind: set_friction, name: wet, mu: 0.35}
  - {kind: wait, duration: 0.3}
"""
GROUND_FRICTION = 0.8  # the shipped scenario's [-]


def _mission(tmp_path, text: str = MISSION):
    path = tmp_path / "mission.yaml"
    path.write_text(text)
    return path


def _friction_log(record) -> tuple[np.ndarray, np.ndarray]:
    log = record.logs["mission.friction"]
    return log.times, log.data[0]


@pytest.mark.parametrize("controller", ["whole_body", "projected_impedance"])
def test_a_set_friction_phase_gives_the_controller_the_new_coefficient(tmp_path, controller):
    scenario = load_scenario(
        scenario_text=f"{{mission: {_mission(tmp_path)}, controller: {controller}, "
        "robot: {initial_pose: standing}, simulation_duration: 2.0}"
    )
    record = simulate(scenario=scenario, name="friction", quiet=True, replay=False)
    result = judge.judge_run(record)
    assert result["success"], result["reason"]
    times, friction = _friction_log(record)
    changed = result["friction_changes"]
    assert [(c["friction"], c["by"]) for c in changed] == [(0.35, "mission")]
    assert np.all(friction[times < changed[0]["time"]] == GROUND_FRICTION)
    assert friction[-1] == 0.35
    # What the controller itself reads on its port at the end of the run.
    system, context = record.subsystem("controller")
    assert system.GetInputPort("friction").Eval(context)[0] == 0.35


@pytest.mark.parametrize("mu", [FRICTION_RANGE[0] / 2, FRICTION_RANGE[1] + 0.1, 0.0])
def test_a_set_friction_phase_outside_the_range_is_refused_naming_the_field(tmp_path, mu):
    path = _mission(tmp_path, MISSION.replace("mu: 0.35", f"mu: {mu}"))
    with pytest.raises(MissionFileError, match=r"mission.yaml: phases\[1\]\.mu: must be in \[0.05, 1.5\]"):
        load_mission(str(path))


def test_the_operator_changes_the_friction_and_a_request_out_of_range_is_dropped(tmp_path):
    mission = _mission(tmp_path, "phases:\n  - {kind: wait, duration: 1.6}\n")
    steps = [
        ScriptStep(0.0),
        ScriptStep(0.4, friction_request=0.5),
        ScriptStep(0.8, friction_request=3.0),  # beyond FRICTION_RANGE: dropped by the input
        ScriptStep(1.0),  # no request: the last one stands
    ]
    scenario = load_scenario(
        scenario_text=f"{{mission: {mission}, controller: whole_body, operator: {{source: lcm}}, "
        "robot: {initial_pose: standing}, simulation_duration: 1.8}"
    )
    messages = script_stream(steps, 50.0, 1.6, DEFAULT_FOOT_COMMAND_CHANNEL)
    record = simulate(scenario=scenario, name="friction", quiet=True, replay=False, operator_messages=messages)
    result = judge.judge_run(record)
    assert result["success"], result["reason"]
    changes = result["friction_changes"]
    assert [(c["friction"], c["by"]) for c in changes] == [(0.5, "operator")]
    assert 0.4 < changes[0]["time"] < 0.5
    times, friction = _friction_log(record)
    assert friction[-1] == 0.5 and np.all(friction[times < 0.4] == GROUND_FRICTION)
    asking_too_much = sum(1 for m in messages if 0.8 <= m.t < 1.0)
    assert asking_too_much == 10 and record.logs["operator.command"].data[9, -1] == asking_too_much  # dropped
