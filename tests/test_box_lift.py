"""The box lift with the two side legs: per-leg foot gains, the box object and the judge. The short
run (missions/demos/box_lift_short.yaml) is judged in test_paper003_evaluations.py."""

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from pydrake.math import RotationMatrix
from reference_stacks import ResolvedInputs
from reference_whole_body_tick import ReferenceTick

from pedi_drake import robot
from pedi_drake.control import references
from pedi_drake.control.config import WholeBodyControllerConfig
from pedi_drake.control.whole_body_controller import WholeBodyController
from pedi_drake.evaluation.box_lift import BoxLiftTrace, box_corners_B, judge_box_lift
from pedi_drake.exceptions import MissionFileError
from pedi_drake.mission.spec import BoxLift, load_mission
from pedi_drake.resources import missions_dir
from pedi_drake.scenario import Scenario, SceneObject
from pedi_drake.station_interface import MakeStation

REPO = Path(__file__).resolve().parents[1]
LIFT_BOX = "package://pedi_drake/scenes/lift_box.sdf"


def _mission_with(tmp_path, old: str, new: str):
    text = (missions_dir() / "box_lift_side_legs.yaml").read_text()
    assert old in text
    path = tmp_path / "bad_box_lift.yaml"
    path.write_text(text.replace(old, new))
    return path


@pytest.mark.parametrize(
    "old,new,field",
    [
        ("foot_gains: {kp: 250.0, kd: 30.0}", "foot_gains: {kp: 0.0, kd: 20.0}", "phases[6].foot_gains.kp"),
        ("foot_gains: {kp: 250.0, kd: 30.0}", "foot_gains: {kp: 100.0, kd: -1.0}", "phases[6].foot_gains.kd"),
        ("foot_gains: {kp: 250.0, kd: 30.0}", "foot_gains: {kp: 100.0}", "phases[6].foot_gains.kd"),
    ],
)
def test_a_non_positive_foot_gain_is_rejected_naming_file_and_field(tmp_path, old, new, field):
    path = _mission_with(tmp_path, old, new)
    with pytest.raises(MissionFileError) as error:
        load_mission(str(path))
    assert str(path) in str(error.value) and field in str(error.value)


def test_a_bad_foot_gain_exits_2_from_run_sim(tmp_path):
    path = _mission_with(tmp_path, "foot_gains: {kp: 250.0, kd: 30.0}", "foot_gains: {kp: -5.0, kd: 20.0}")
    run_sim = REPO / "run_sim.py"
    done = subprocess.run(
        [sys.executable, str(run_sim), "--mission", str(path), "--out", str(tmp_path / "out")],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert done.returncode == 2, done.stderr
    assert "phases[6].foot_gains.kp" in done.stderr and str(path) in done.stderr


def test_box_lift_check_must_name_a_scene_object_and_a_phase(tmp_path):
    for old, new, field in [
        ("box_lift: {box: box,", "box_lift: {box: crate,", "box_lift.box"),
        ("until_phase: put_down}", "until_phase: nowhere}", "box_lift.until_phase"),
        ("height: 0.05, hold: 3.0", "height: 0.0, hold: 3.0", "box_lift.height"),
    ]:
        with pytest.raises(MissionFileError, match=field.replace(".", r"\.")):
            load_mission(str(_mission_with(tmp_path, old, new)))


def test_leg_reference_carries_each_legs_foot_gains():
    x = references.leg_reference_vector(
        {"FL": (references.LEG_MODE_FOOT, np.ones(3), np.zeros(3), np.zeros(3))}, {"FL": (80.0, 15.0)}
    )
    legs = references.parse_leg_reference(x)
    assert (legs[1].foot_kp, legs[1].foot_kd) == (80.0, 15.0)
    assert all((leg.foot_kp, leg.foot_kd) == (0.0, 0.0) for k, leg in enumerate(legs) if k != 1)


def test_a_legs_own_gains_set_its_foot_rows_and_no_other():
    """The stack's foot rows scale with the leg reference's kp; 0 keeps the configured gains."""
    controller = WholeBodyController(WholeBodyControllerConfig(), None)
    base = np.array([1.0, 0, 0, 0, 0, 0, 0.28, 0, 0, 0, 0, 0, 0])
    snapshot = controller.model.update(base, robot.STANDING_Q.copy(), np.zeros(12))
    offset = np.array([0.01, 0.0, 0.0])  # 1 cm from the reference, at rest

    def foot_rhs(kp: float) -> dict:
        entries = {
            leg: (references.LEG_MODE_FOOT, snapshot.p_contacts[k] + offset, np.zeros(3), np.zeros(3))
            for k, leg in ((1, "FL"), (3, "RL"))
        }
        inputs = ResolvedInputs(
            body=references.parse_body_reference(references.body_reference_vector(np.zeros(3), RotationMatrix())),
            legs=references.parse_leg_reference(references.leg_reference_vector(entries, {"FL": (kp, 10.0)})),
            ramp=np.ones(4),
            no_motion=np.array([True, False, True, False]),
            polygon_N=np.zeros((0, 2)),
            polygon_d=np.zeros(0),
            friction=0.6,
            ground_height=0.0,
        )
        return {row.name: row.b for row in ReferenceTick(controller).builder.leg_tasks(snapshot, inputs)}

    low, default = foot_rhs(50.0), foot_rhs(0.0)
    bias = snapshot.Jdot_v_contacts[3:6]
    np.testing.assert_allclose(low["foot_FL"] + bias, 50.0 * offset, atol=1e-9)
    np.testing.assert_allclose(default["foot_FL"] + bias, controller.config.foot_position.kp * offset, atol=1e-9)
    np.testing.assert_allclose(low["foot_RL"], default["foot_RL"], atol=1e-12)


def test_the_lift_box_is_a_free_box_of_its_size_and_mass_with_friction():
    station = MakeStation(Scenario(scene=[SceneObject(kind="box", model=LIFT_BOX, position=[0.0, 0.3, 0.0])]))
    plant = station.GetSubsystemByName("plant")
    inspector = station.GetSubsystemByName("scene_graph").model_inspector()
    box = plant.GetBodyByName("box", plant.GetModelInstanceByName("box"))
    assert box.is_floating_base_body() and box.default_mass() == pytest.approx(0.3)
    corners = box_corners_B(plant, inspector, box)
    np.testing.assert_allclose(corners.min(axis=0), [-0.10, -0.05, 0.0], atol=1e-12)
    np.testing.assert_allclose(corners.max(axis=0), [0.10, 0.05, 0.06], atol=1e-12)
    (geometry,) = plant.GetCollisionGeometriesForBody(box)
    friction = inspector.GetProximityProperties(geometry).GetProperty("material", "coulomb_friction")
    assert friction.static_friction() == pytest.approx(0.8)


def _trace(bottom, forces) -> BoxLiftTrace:
    times = np.arange(len(bottom)) * 0.5
    return BoxLiftTrace(times, np.asarray(bottom, float), np.asarray(forces, float), np.zeros((len(bottom), 2, 3)))


CHECK = BoxLift(height=0.05, hold=1.0, contact_force=1.0, until_phase="put_down")
PHASES = [{"name": "put_down", "t_start": 2.5}]


def test_judge_passes_a_box_held_high_enough_for_long_enough():
    row, problem = judge_box_lift(_trace([0, 0.06, 0.06, 0.06, 0.06, 0.03, 0], [[3, 3]] * 7), CHECK, PHASES)
    assert problem == "" and row["held_s"] == pytest.approx(1.5) and row["dropped_at_s"] is None


def test_judge_fails_a_box_not_held_by_both_feet():
    # High enough, long enough, but one foot does not touch it: something else holds it.
    row, problem = judge_box_lift(_trace([0, 0.06, 0.06, 0.06, 0.06, 0, 0], [[3, 0]] * 7), CHECK, PHASES)
    assert row["held_s"] == 0.0 and "held by FL+RL" in problem


def test_judge_fails_a_box_dropped_before_the_put_down():
    bottom = [0, 0.06, 0.06, 0.06, 0.0, 0.06, 0.06, 0.06, 0.0]
    row, problem = judge_box_lift(_trace(bottom, [[3, 3]] * 9), CHECK, [{"name": "put_down", "t_start": 3.5}])
    assert row["dropped_at_s"] == pytest.approx(2.0) and "fell back" in problem
