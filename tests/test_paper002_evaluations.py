"""Paper 002's evaluations as short simulations on its controller, on the Kalman estimate as
shipped, judged on ground truth: IV-A (the lifted foot holds a 5-D world pose while the torso
circles) and IV-B (the trunk turns about one prong while the lifted front feet hold their
positions), through `python -m pedi_drake.reproduce 002 --quick`, whose report they also check.

The missions are the short versions in missions/quick/ (one lap; each rotation once)."""

import json
import re

import pytest

from pedi_drake.evaluation import paper002 as evaluation
from pedi_drake.reproduce.__main__ import main

ROTATION_FLOOR_DEG = 5.0
FRONT_FEET_FLOOR_M = 0.005


def _reproduce(out):
    assert main(["002", "--quick", "--out", str(out)]) == 0


@pytest.fixture(scope="module")
def quick_report(made_once):
    folder = made_once("reproduce_002_quick", _reproduce) / "002"
    rows = {row["case"]: row for row in json.loads((folder / "rows.json").read_text())}
    return rows, folder


@pytest.fixture(scope="module")
def iv_a(quick_report):
    rows, _ = quick_report
    return rows["IV-A"]


@pytest.fixture(scope="module")
def iv_b(quick_report):
    rows, _ = quick_report
    return rows["IV-B"]


def test_iv_a_mission_succeeds_without_falling(iv_a):
    assert iv_a["success"], iv_a["reason"]
    assert not iv_a["fell"]
    assert iv_a["controller"] == "projected_impedance"


def test_iv_a_foot_holds_its_position_within_5_mm(iv_a):
    assert iv_a["foot_position_error_max_m"] < evaluation.FOOT_POSITION_FLOOR_M


def test_iv_a_foot_holds_its_roll_and_pitch_within_2_deg(iv_a):
    assert iv_a["foot_orientation_error_max_deg"] < 2.0


def test_iv_a_torso_tracks_the_circle_within_1_cm_rms(iv_a):
    assert iv_a["torso_tracking_rms_m"] < evaluation.TORSO_TRACKING_RMS_FLOOR_M
    # It did circle: the reference spans the 1.5 cm circle's diameter.
    assert iv_a["torso_reference_span_m"] > 0.025


def test_iv_b_mission_succeeds_on_one_prong_without_falling(iv_b):
    assert iv_b["success"], iv_b["reason"]
    assert not iv_b["fell"]


def test_iv_b_trunk_turns_5_deg_each_way_about_the_prong(iv_b):
    for axis, (most_negative, most_positive) in iv_b["rotation_reached_deg"].items():
        assert most_positive >= ROTATION_FLOOR_DEG, axis
        assert most_negative <= -ROTATION_FLOOR_DEG, axis


def test_iv_b_front_feet_hold_within_5_mm(iv_b):
    assert iv_b["front_feet_drift_max_m"] < FRONT_FEET_FLOOR_M


def test_the_report_shows_figs_3_to_5_and_7_beside_the_published_statements(quick_report):
    _, folder = quick_report
    report = (folder / "report.md").read_text()
    figures = re.findall(r"!\[[^\]]*\]\(([^)]+)\)", report)
    assert sorted(name.rsplit("/", 1)[-1] for name in figures) == [
        "iva_foot_orientation_error.png",
        "iva_foot_position_error.png",
        "iva_positions.png",
        "ivb_rotations.png",
    ]
    for figure in figures:
        assert (folder / figure).stat().st_size > 1000, figure
    assert "yaw error much greater than the other directions" in report
    assert "Not yet reproduced" not in report
