"""Paper 002's evaluations as short simulations on its controller, judged on ground truth:
IV-A (the lifted foot holds a 5-D world pose while the torso circles) and IV-B (the trunk turns
about one prong while the lifted front feet hold their positions)."""

import json

import numpy as np
import pytest

from pedi_drake.diagram import apply_mission
from pedi_drake.evaluation import paper002 as evaluation
from pedi_drake.evaluation.run_logs import read_run_logs
from pedi_drake.mission.spec import load_mission
from pedi_drake.prongs import ProngDesign
from pedi_drake.run import run
from pedi_drake.scenario import load_scenario
from pedi_drake.station_interface import MakeStation
from pedi_drake.viz.paper002_plots import plot_foot_hold

# One lap of the shipped IV-A circle, from standing (no stand-up, no put-down: a shorter run).
IV_A = """
phases:
  - {kind: leg_to_pedipulation, leg: FL, timeout: 4.0}
  - {kind: hold_foot_pose, name: hold_FL, leg: FL, orientation: true, duration: 0.3, timeout: 2.0}
  - {kind: body_path, name: torso_circle, radius: 0.015, laps: 1, duration: 6.0, tolerance: 0.01, timeout: 8.0}
"""


@pytest.fixture(scope="module")
def iv_a(tmp_path_factory):
    folder = tmp_path_factory.mktemp("iv_a")
    mission = folder / "iv_a.yaml"
    mission.write_text(IV_A)
    scenario = load_scenario(
        scenario_text=f"{{mission: {mission}, controller: projected_impedance, robot: {{initial_pose: standing}}, "
        "simulation_duration: 14.0}"
    )
    result = run(scenario=scenario, name="iv_a", out_dir=folder, quiet=True, replay=False)
    phase = next(p for p in result["phases"] if p["name"] == "torso_circle")
    plant = MakeStation(apply_mission(scenario, load_mission(str(mission)))).GetSubsystemByName("plant")
    hold = evaluation.evaluate_foot_hold(plant, read_run_logs(folder), phase["t_start"], phase["t_end"])
    return result, hold, folder


def test_iv_a_mission_succeeds_without_falling(iv_a):
    result, _, folder = iv_a
    assert result["success"], result["reason"]
    assert not result["fell"]
    assert json.loads((folder / "result.json").read_text())["controller"] == "projected_impedance"


def test_iv_a_foot_holds_its_position_within_5_mm(iv_a):
    _, hold, _ = iv_a
    assert hold.foot_position_error_max_m < evaluation.FOOT_POSITION_FLOOR_M


def test_iv_a_foot_holds_its_roll_and_pitch_within_2_deg(iv_a):
    _, hold, _ = iv_a
    assert hold.foot_orientation_error_max_rad < evaluation.FOOT_ORIENTATION_FLOOR_RAD


def test_iv_a_torso_tracks_the_circle_within_1_cm_rms(iv_a):
    _, hold, _ = iv_a
    assert hold.torso_tracking_rms_m < evaluation.TORSO_TRACKING_RMS_FLOOR_M
    # It did circle: the reference spans the circle's diameter.
    span = hold.trunk_reference[:, :2].max(axis=0) - hold.trunk_reference[:, :2].min(axis=0)
    assert span.min() > 0.025


def test_iv_a_plots_figs_3_to_5(iv_a, tmp_path):
    _, hold, _ = iv_a
    paths = plot_foot_hold(hold, tmp_path, title="projected_impedance")
    assert [p.name for p in paths] == [
        "iva_positions.png",
        "iva_foot_position_error.png",
        "iva_foot_orientation_error.png",
    ]
    assert all(p.stat().st_size > 1000 for p in paths)


# IV-B from standing: lean on the front prong alone, lift both front feet, hold them, turn the
# trunk about the prong's tip by 6 degrees each way in pitch, roll and yaw (the shipped mission,
# prong_pivot_rotations, without standing up and putting the feet back). On the true state: this
# judges the controller; on one prong the Kalman estimate's height drifts by 1 to 2 cm, and the
# feet, held in the estimated world, drift with it (the paper-002 benchmark reports both).
IV_B = """
robot:
  prongs: {}
phases:
  - {kind: body_rotate, name: nose_down, rpy: [0.0, 0.14, 0.0], duration: 1.0, timeout: 3.0}
  - {kind: lean_on_prongs, prongs: [prong_0], duration: 2.0, timeout: 4.0}
  - {kind: leg_to_pedipulation, leg: FR, working_depth: 0.10, timeout: 4.0}
  - {kind: leg_to_pedipulation, leg: FL, working_depth: 0.10, timeout: 4.0}
  - {kind: hold_foot_pose, name: hold_FR, leg: FR, orientation: false, duration: 0.2, timeout: 2.0}
  - {kind: hold_foot_pose, name: hold_FL, leg: FL, orientation: false, duration: 0.2, timeout: 2.0}
  - {kind: body_rotate, name: pitch_up, pivot: prong_0, rpy: [0.0, 0.2447, 0.0], duration: 1.5, timeout: 3.0}
  - {kind: body_rotate, name: pitch_down, pivot: prong_0, rpy: [0.0, 0.0353, 0.0], duration: 2.0, timeout: 3.5}
  - {kind: body_rotate, name: roll_left, pivot: prong_0, rpy: [0.1047, 0.14, 0.0], duration: 1.5, timeout: 3.0}
  - {kind: body_rotate, name: roll_right, pivot: prong_0, rpy: [-0.1047, 0.14, 0.0], duration: 2.0, timeout: 3.5}
  - {kind: body_rotate, name: yaw_left, pivot: prong_0, rpy: [0.0, 0.14, 0.1047], duration: 1.5, timeout: 3.0}
  - {kind: body_rotate, name: yaw_right, pivot: prong_0, rpy: [0.0, 0.14, -0.2094], duration: 2.0, timeout: 3.5}
"""
ROTATION_FLOOR = np.radians(5.0)
FRONT_FEET_FLOOR_M = 0.005


@pytest.fixture(scope="module")
def iv_b(tmp_path_factory):
    folder = tmp_path_factory.mktemp("iv_b")
    mission = folder / "iv_b.yaml"
    mission.write_text(IV_B)
    scenario = load_scenario(
        scenario_text=f"{{mission: {mission}, controller: projected_impedance, robot: {{initial_pose: standing}}, "
        "simulation_duration: 30.0, estimator: ground_truth}"
    )
    result = run(scenario=scenario, name="iv_b", out_dir=folder, quiet=True, replay=False)
    turns = [p for p in result["phases"] if p["name"] in ("pitch_up", "yaw_right")]
    assert len(turns) == 2 and all(p["t_end"] is not None for p in turns), result["reason"]
    plant = MakeStation(apply_mission(scenario, load_mission(str(mission)))).GetSubsystemByName("plant")
    pivot = evaluation.evaluate_pivot_rotations(
        plant,
        read_run_logs(folder),
        turns[0]["t_start"],
        turns[1]["t_end"],
        "prong_0",
        [0.0, 0.0, -ProngDesign().length],
    )
    return result, pivot


def test_iv_b_mission_succeeds_on_one_prong_without_falling(iv_b):
    result, _ = iv_b
    assert result["success"], result["reason"]
    assert not result["fell"]


def test_iv_b_trunk_turns_5_deg_each_way_about_the_prong(iv_b):
    _, pivot = iv_b
    for axis, (most_negative, most_positive) in pivot.rotation_reached_rad.items():
        assert most_positive >= ROTATION_FLOOR, axis
        assert most_negative <= -ROTATION_FLOOR, axis


def test_iv_b_front_feet_hold_within_5_mm(iv_b):
    _, pivot = iv_b
    assert pivot.front_feet_drift_max_m < FRONT_FEET_FLOOR_M
