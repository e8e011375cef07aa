"""The scenario's `operator:` field is validated on load: a bad value names the field, and
run_sim.py exits 2 before anything is built."""

import subprocess
import sys
from pathlib import Path

import pytest

from pedi_drake.exceptions import ScenarioError
from pedi_drake.mission.spec import TeleopFoot, load_mission, shipped_missions
from pedi_drake.scenario import load_scenario


@pytest.mark.parametrize(
    ("text", "field"),
    [
        ("{operator: {source: joystick}}", "operator.source"),
        ("{operator: {source: lcm, lcm_bus: nowhere}}", "operator.lcm_bus"),
        ("{operator: {period: -0.01}}", "operator.period"),
        ("{operator: {source: remote, remote: {teleop_button: big_red}}}", "operator.remote.teleop_button"),
        ("{operator: {source: remote, remote: {max_speed: .nan}}}", "operator.remote.max_speed"),
        ("{operator: {source: remote, remote: {frame: hip}}}", "operator.remote.frame"),
    ],
)
def test_a_bad_operator_value_names_its_field(text, field):
    with pytest.raises(ScenarioError, match=field.replace(".", r"\.")):
        load_scenario(scenario_text=text)


def test_run_sim_exits_2_on_a_bad_operator_source():
    repo = Path(__file__).resolve().parents[1]
    result = subprocess.run(
        [sys.executable, str(repo / "run_sim.py"), "--scenario_text", "{operator: {source: joystick}}"],
        capture_output=True,
        text=True,
        cwd=repo,
        timeout=120,
    )
    assert result.returncode == 2
    assert "operator.source" in result.stderr and "joystick" in result.stderr


def test_the_operator_mission_loads_outside_the_autonomous_library():
    # It needs an operator, so the autonomous missions' smoke tests and studies do not list it.
    mission = load_mission("operator/teleop_foot")
    assert any(isinstance(phase, TeleopFoot) for phase in mission.phases)
    assert "teleop_foot" not in shipped_missions()
