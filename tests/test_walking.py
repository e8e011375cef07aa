"""Walking missions: their files checked field by field, and short walks in simulation on both
whole-body controllers, judged by ground truth (pedi_drake.evaluation.walks).

The floors' walks (2 m each way, the square, 6 seeds) are the benchmark's:
`python -m pedi_drake.benchmarks.walking`.
"""

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from pedi_drake.benchmarks.teleop import lock_step_run
from pedi_drake.evaluation.judge import judge_run
from pedi_drake.exceptions import MissionFileError
from pedi_drake.go1_driver.lcmtypes import rc_command_lcmt
from pedi_drake.locomotion.gait import GAITS
from pedi_drake.mission.spec import load_mission
from pedi_drake.mission.walk import operator_twist
from pedi_drake.operator.command import KIND_TWIST, KIND_VELOCITY, OperatorCommand
from pedi_drake.operator.config import DEFAULT_FOOT_COMMAND_CHANNEL, RemoteMapping
from pedi_drake.operator.messages import remote_command_vector
from pedi_drake.operator.scripted_operator import ScriptStep, script_stream
from pedi_drake.run import simulate
from pedi_drake.scenario import load_scenario

REPO = Path(__file__).resolve().parents[1]
SHORT_WALK = """\
description: A short static walk forward, to the left and turning, to a pose.
contact_ramp_time: 0.06
phases:
  - {kind: stand_up}
  - {kind: walk, position: [0.3, 0.1], yaw: 0.2, speed: 0.15}
"""


def _mission(tmp_path, text: str) -> Path:
    path = tmp_path / "walk.yaml"
    path.write_text(text)
    return path


@pytest.mark.parametrize(
    "old, new, field",
    [
        ("speed: 0.15}", "speed: 0.5}", "phases[1].speed"),
        ("speed: 0.15}", "speed: 0.15, gait: gallop}", "phases[1].gait"),
        ("contact_ramp_time: 0.06", "contact_ramp_time: 0.3", "contact_ramp_time"),
        ("contact_ramp_time: 0.06\n", "", "contact_ramp_time"),
        (
            "{kind: walk, position: [0.3, 0.1], yaw: 0.2, speed: 0.15}",
            "{kind: walk_velocity, twist: [0.1, 0.0, 0.9]}",
            "phases[1].twist",
        ),
        (
            "{kind: walk, position: [0.3, 0.1], yaw: 0.2, speed: 0.15}",
            "{kind: walk_velocity, twist: [0.0, 0.1, 0.2]}",
            "phases[1].twist",
        ),
    ],
)
def test_a_bad_walk_is_refused_naming_its_field(tmp_path, old, new, field):
    assert old in SHORT_WALK
    path = _mission(tmp_path, SHORT_WALK.replace(old, new))
    with pytest.raises(MissionFileError, match=field.replace("[", r"\[").replace("]", r"\]")):
        load_mission(str(path))


def test_run_sim_exits_2_on_a_speed_beyond_the_gait(tmp_path):
    path = _mission(tmp_path, SHORT_WALK.replace("speed: 0.15}", "speed: 0.5}"))
    result = subprocess.run(
        [sys.executable, str(REPO / "run_sim.py"), "--mission", str(path), "--out", str(tmp_path / "out")],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert result.returncode == 2, result.stderr
    assert "phases[1].speed" in result.stderr and "walk.yaml" in result.stderr
    assert not (tmp_path / "out").exists()


@pytest.fixture(scope="module", params=["whole_body", "projected_impedance"])
def short_walk(request, tmp_path_factory):
    path = _mission(tmp_path_factory.mktemp("walk"), SHORT_WALK)
    scenario = load_scenario(scenario_text=f"{{mission: '{path}', controller: {request.param}}}")
    record = simulate(scenario=scenario, name="short_walk", quiet=True, replay=False)
    return request.param, judge_run(record)


def test_the_short_walk_reaches_its_pose_by_ground_truth(short_walk):
    controller, result = short_walk
    assert result["success"], f"{controller}: {result['reason']}"
    assert not result["fell"]
    (walk,) = result["walks"]
    assert walk["goal_error_m"] < 0.03 and walk["goal_yaw_error_rad"] < 0.05
    assert walk["steps"] >= 8
    assert walk["late_touchdowns"] + walk["early_touchdowns"] == walk["steps"]


def test_no_stance_foot_slips_and_the_estimate_follows(short_walk):
    controller, result = short_walk
    (walk,) = result["walks"]
    assert max(walk["max_stance_slip_m"].values()) < 0.01, controller
    assert walk["estimate_drift_share"] < 0.03 and walk["estimate_height_error_max_m"] < 0.01


def test_the_remote_sticks_become_a_twist_in_the_walk_these_ways_layout():
    mapping = RemoteMapping(sticks="walk", walk_speeds=[0.2, 0.1, 0.3], deadband=0.0)
    message = rc_command_lcmt()
    message.left_stick = [0.5, 1.0]  # up: forward at full speed; right: half to the right
    message.right_stick = [-1.0, 0.7]  # left: turn left at full rate (its y moves no foot here)
    values = remote_command_vector(mapping)(message)
    assert values[2] == KIND_TWIST
    np.testing.assert_allclose(values[3:6], [0.2, -0.05, 0.3])


def test_an_operator_twist_is_held_to_the_gait_and_a_stale_one_is_none():
    limits = GAITS["static_walk"]
    fresh = OperatorCommand(kind=KIND_TWIST, value=np.array([0.5, 0.0, -1.0]), age=0.05)
    np.testing.assert_allclose(operator_twist(fresh, limits), [limits.forward, 0.0, -limits.yaw_rate])
    # Sideways and turning share one budget: at 0.055 m/s sideways (half its limit), half the yaw rate.
    both = OperatorCommand(kind=KIND_TWIST, value=np.array([0.0, -0.055, -1.0]), age=0.05)
    np.testing.assert_allclose(operator_twist(both, limits), [0.0, -0.055, -0.5 * limits.yaw_rate])
    stale = OperatorCommand(kind=KIND_TWIST, value=np.array([0.1, 0.0, 0.0]), age=1.0)
    foot = OperatorCommand(kind=KIND_VELOCITY, value=np.array([0.1, 0.0, 0.0]), age=0.05)
    assert not operator_twist(stale, limits).any() and not operator_twist(foot, limits).any()


def test_the_operator_steers_a_walk_over_lcm():
    # Forward and turning left from 4 s to 10 s, then nothing: the walk steps in place, then stops.
    steps = [ScriptStep(0.0, kind=KIND_TWIST), ScriptStep(4.0, (0.15, 0.0, 0.2), kind=KIND_TWIST)]
    steps.append(ScriptStep(10.0, kind=KIND_TWIST))
    messages = script_stream(steps, 20.0, 12.0, DEFAULT_FOOT_COMMAND_CHANNEL)
    run = lock_step_run("walking/walk_teleop_short", messages, 20.0)
    assert run.result["success"], run.result["reason"]
    (walk,) = run.result["walks"]
    x, y, yaw = walk["end_pose"]
    # About 6 s at the twist (the cycles start when the command is read): 0.9 m along an arc.
    assert 0.5 < walk["displacement_m"] < 1.0 and 0.5 < yaw < 1.3
    assert max(walk["max_stance_slip_m"].values()) < 0.01
