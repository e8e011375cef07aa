"""Touches confirmed by sensed contact, and leans on the prongs confirmed by the load they carry.

A touching reach (`touch:` in a reach phase) ends with a guarded move along its approach: it
succeeds when the foot force estimate feels the object and fails with "no contact felt" when it
does not, however close the estimate says the foot came. The object is moved after the mission
was planned, as a robot whose idea of the world is off would meet it.
"""

import numpy as np
import pytest

from pedi_drake.mission.phases import PRONG_LOAD_FRACTION
from pedi_drake.mission.spec import MissionFileError, load_mission
from pedi_drake.prongs import ProngDesign
from pedi_drake.run import run
from pedi_drake.run_logs import read_run_logs
from pedi_drake.scenario import load_scenario

# hit_target_front's cardboard cat: its front face is where the mission's target puts the foot.
PANEL_X = 0.47
TOUCH_MISSION = """
description: Touch the cat with the front right foot, the cat at x = {x}.
scene:
  - {{kind: target_panel, position: [{x}, -0.13, 0.0], yaw: 3.14159}}
phases:
  - {{kind: stand_up, height: 0.28, duration: 2.0, timeout: 4.0}}
  - {{kind: leg_to_pedipulation, leg: FR, timeout: 4.0}}
  - {{kind: reach, name: touch_cat, leg: FR, target: [0.447, -0.13, 0.20], approach_offset: [-0.05, 0.0, 0.0],
      tolerance: 0.005, touch: {{force: 3.0, over_travel: 0.02}}, timeout: 6.0}}
"""
LEAN_MISSION = """
description: Stand up and lean on both prongs.
robot:
  prongs: {}
stack: paper003
phases:
  - {kind: stand_up, height: 0.28, duration: 2.0, timeout: 4.0}
  - {kind: lean_on_prongs, duration: 2.0, timeout: 6.0}
"""


def _run_mission(tmp_path, text: str, scenario_text: str = "{}") -> dict:
    mission = tmp_path / "mission.yaml"
    mission.write_text(text)
    scenario = load_scenario(scenario_text=scenario_text)
    scenario.mission, scenario.controller = str(mission), "whole_body"
    return run(scenario=scenario, name="guarded", out_dir=tmp_path / "out", quiet=True, replay=False)


def _touch_row(result: dict) -> dict:
    (row,) = result["sensed_touches"]
    return row


def test_a_touch_is_confirmed_by_the_force_it_feels(tmp_path):
    result = _run_mission(tmp_path, TOUCH_MISSION.format(x=PANEL_X))
    assert result["success"], result["reason"]
    row = _touch_row(result)
    assert row["confirmed"] and row["force_n"] >= 3.0
    # Contact came within a few millimetres of the planned target.
    assert abs(row["felt_from_target_m"]) < 0.006, row


def test_joint_friction_is_not_felt_as_a_touch(tmp_path):
    # Coulomb friction in every joint resists the leg along the guarded line: about 3 N against
    # the approach from the start of the drive, which felt like the cat 4-5 cm before it. The
    # touch must come at the cat, with force on it by the plant's truth.
    result = _run_mission(tmp_path, TOUCH_MISSION.format(x=PANEL_X), "{model_error: {joint_friction: 0.2}}")
    row = _touch_row(result)
    assert row["confirmed"] and row["bias_in_motion"], row
    assert abs(row["felt_from_target_m"]) < 0.008, row
    true_force = read_run_logs(tmp_path / "out" / "logs.npz")["sim.foot_contact_forces"].data[0:3]
    assert np.linalg.norm(true_force, axis=0).max() >= 1.0


def test_a_target_moved_away_after_planning_fails_with_no_contact_felt(tmp_path):
    result = _run_mission(tmp_path, TOUCH_MISSION.format(x=PANEL_X + 0.03))
    assert not result["success"]
    assert "no contact felt" in result["reason"], result["reason"]
    row = _touch_row(result)
    assert not row["confirmed"] and row["travel_m"] > 0.05 + 0.019


def test_a_target_moved_into_the_object_is_felt_early(tmp_path):
    result = _run_mission(tmp_path, TOUCH_MISSION.format(x=PANEL_X - 0.01))
    assert result["success"], result["reason"]
    row = _touch_row(result)
    assert row["confirmed"] and row["felt_from_target_m"] < -0.005, row


def test_a_touch_needs_an_approach_to_move_along(tmp_path):
    text = TOUCH_MISSION.format(x=PANEL_X).replace("approach_offset: [-0.05, 0.0, 0.0],", "")
    (tmp_path / "bad.yaml").write_text(text)
    with pytest.raises(MissionFileError, match=r"touch: a guarded touch moves along the approach direction"):
        load_mission(str(tmp_path / "bad.yaml"))


@pytest.mark.parametrize("field", ["force", "over_travel", "speed"])
def test_bad_touch_values_name_the_field(tmp_path, field):
    values = {"force": 3.0, "over_travel": 0.02, "speed": 0.04, field: -1.0}
    touch = "{" + ", ".join(f"{name}: {value}" for name, value in values.items()) + "}"
    text = TOUCH_MISSION.format(x=PANEL_X).replace("touch: {force: 3.0, over_travel: 0.02}", f"touch: {touch}")
    (tmp_path / "bad.yaml").write_text(text)
    with pytest.raises(MissionFileError, match=rf"touch\.{field}: must be a finite number > 0"):
        load_mission(str(tmp_path / "bad.yaml"))


def test_a_lean_is_done_when_the_prongs_carry_load(tmp_path):
    result = _run_mission(tmp_path, LEAN_MISSION)
    assert result["success"], result["reason"]
    (lean,) = result["prong_leans"]
    assert lean["load_felt_at_s"] is not None
    assert lean["prong_load_n"] >= PRONG_LOAD_FRACTION * lean["feet_load_before_n"]


def test_a_lean_on_legs_with_joint_damping_and_friction_is_felt_when_the_prongs_meet_the_ground(tmp_path):
    # Damping and friction in the joints bias the joint-torque loads while the legs move (tens of
    # newtons as the trunk goes down): the load counts only once the prongs have stopped the trunk.
    text = "{model_error: {joint_damping: 2.0, joint_friction: 0.2}}"
    result = _run_mission(tmp_path, LEAN_MISSION, scenario_text=text)
    assert result["success"], result["reason"]
    (lean,) = result["prong_leans"]
    logs = read_run_logs(tmp_path / "out")
    states = logs["sim.plant_state"]
    k = int(np.searchsorted(states.times, lean["load_felt_at_s"]))
    rest = ProngDesign().ground_contact_height()
    # The Go1 is the plant's only model: its trunk height is q[6] (quaternion first, then position).
    assert states.data[6, k] < rest + 0.005, (states.data[6, k], rest)
