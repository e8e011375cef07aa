"""Lower control rates (the shipped control_400hz and control_250hz scenarios) run a mission:
a short one, the reach of hit_target_front, judged by the simulation's ground truth."""

import pytest

from pedi_drake.evaluation.judge import judge_run
from pedi_drake.exceptions import ScenarioError
from pedi_drake.run import simulate
from pedi_drake.scenario import load_scenario

SHORT_MISSION = """
scene:
  - {kind: target_panel, position: [0.47, -0.13, 0.0], yaw: 3.14159}
phases:
  - {kind: stand_up, height: 0.28, duration: 2.0, timeout: 4.0}
  - {kind: leg_to_pedipulation, leg: FR, timeout: 4.0}
  - {kind: reach, name: touch_cat, leg: FR, target: [0.447, -0.13, 0.20],
     approach_offset: [-0.05, 0.0, 0.0], tolerance: 0.005, timeout: 6.0}
  - {kind: leg_to_support, leg: FR, timeout: 6.0}
"""


@pytest.mark.parametrize(("scenario_name", "period"), [("control_400hz", 0.0025), ("control_250hz", 0.004)])
def test_a_lower_control_rate_runs_a_short_mission(tmp_path, scenario_name, period):
    mission = tmp_path / "short.yaml"
    mission.write_text(SHORT_MISSION)
    scenario = load_scenario(
        scenario_name=scenario_name, scenario_text=f"{{mission: {mission}, simulation_duration: 20}}"
    )
    assert scenario.whole_body.period == scenario.kalman.period == scenario.go1_driver.safety.period == period
    result = judge_run(simulate(scenario=scenario, name=scenario_name, quiet=True, replay=False))
    assert result["success"], result["reason"]
    (row,) = result["foot_errors_m"]
    assert row["error"] < 0.005
    assert result["max_base_drift_m"] < 0.01


def test_the_control_period_is_one_for_estimator_controller_and_driver():
    with pytest.raises(ScenarioError, match="control period must be the same everywhere"):
        load_scenario(scenario_text="{controller: whole_body, whole_body: {period: 0.004}}")
