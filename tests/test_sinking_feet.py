"""Feet that sink into the ground do not lift the estimated world: a Go1 on soft feet (the scenario's
model_error: a foot contact that sinks 17 mm under the standing robot, and feet of 23 mm radius
where the controllers take 20) stands up, and the estimate's trunk height is held against the
plant's. The estimator learns the feet's sink from the trunk resting on the ground, which every
stand-up from lying begins with, and their compliance from how their loads differ."""

import pytest

from pedi_drake.run import run
from pedi_drake.scenario import load_scenario

STAND_MISSION = """
description: Stand up from lying and stand still.
phases:
  - {kind: stand_up, height: 0.28, duration: 2.0, timeout: 4.0}
  - {kind: wait, duration: 1.0, timeout: 2.0}
"""
# A Drake foot contact this stiff sinks 17 mm under a standing Go1 (tests/test_model_error.py) [N/m].
SOFT_FOOT = "{foot_contact_stiffness: 1880.0, foot_radius: 0.023}"
# The estimator of rigid feet: no compliance, no sink.
RIGID_ESTIMATOR = (
    "{foot_compliance_std: 0.0, foot_compliance_process_noise: 0.0, foot_sink_std: 0.0, foot_sink_process_noise: 0.0}"
)


def _height_error(tmp_path, kalman: str = "{}") -> float:
    """The largest |estimated - true| trunk height while standing [m]."""
    mission = tmp_path / "stand.yaml"
    mission.write_text(STAND_MISSION)
    scenario = load_scenario(scenario_text=f"{{model_error: {SOFT_FOOT}, kalman: {kalman}}}")
    scenario.mission, scenario.controller = str(mission), "whole_body"
    result = run(scenario=scenario, name="soft_feet", out_dir=tmp_path / "out", quiet=True, replay=False)
    assert result["success"], result["reason"]
    return result["estimator_errors"]["height_error_standing_max_m"]


def test_a_robot_on_feet_that_sink_17_mm_knows_its_height_within_5_mm(tmp_path):
    # Not exact: the stand-up's rest tells the sink at the resting load, and the compliance that
    # carries it to the standing load is learnt from the feet's load differences while standing.
    assert _height_error(tmp_path) < 0.005


def test_taking_those_feet_as_rigid_puts_the_trunk_a_centimetre_too_high(tmp_path):
    assert _height_error(tmp_path, RIGID_ESTIMATOR) == pytest.approx(0.014, abs=0.004)
