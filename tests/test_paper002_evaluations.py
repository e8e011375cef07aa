"""Paper 002's evaluations as short simulations on its controller, judged on ground truth:
IV-A (the lifted foot holds a 5-D world pose while the torso circles)."""

import json

import pytest

from pedi_drake.diagram import apply_mission
from pedi_drake.evaluation import paper002 as evaluation
from pedi_drake.evaluation.run_logs import read_run_logs
from pedi_drake.mission.spec import load_mission
from pedi_drake.run import run
from pedi_drake.scenario import load_scenario
from pedi_drake.station_interface import MakeStation

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
    paths = evaluation.plot_foot_hold(hold, tmp_path, title="projected_impedance")
    assert [p.name for p in paths] == [
        "iva_positions.png",
        "iva_foot_position_error.png",
        "iva_foot_orientation_error.png",
    ]
    assert all(p.stat().st_size > 1000 for p in paths)
