"""Mission outcomes judged by physics: a touch needs a contact force, a cleared back needs the
object off the trunk, a push needs the object moved from a firm stance; each check fails when
its outcome is absent, from synthetic logs, from a real plant's contact results, and from a
short real run."""

import numpy as np
import pytest
from pydrake.systems.analysis import Simulator

from pedi_drake import robot
from pedi_drake.evaluation.object_push import judge_object_push
from pedi_drake.evaluation.off_trunk import ON_TRUNK_MAX_HEIGHT, OffTrunkTrace, judge_off_trunk, off_trunk_trace
from pedi_drake.evaluation.touches import judge_touches
from pedi_drake.exceptions import MissionFileError
from pedi_drake.go1_command import pack_command
from pedi_drake.mission.spec import ObjectPush, Touch, load_mission
from pedi_drake.resources import missions_dir
from pedi_drake.run import run
from pedi_drake.scenario import Scenario, SceneObject, load_scenario
from pedi_drake.station.scene import root_body
from pedi_drake.station.scene_contact import ROBOT_CONTACT_SOURCES, scene_contact_index
from pedi_drake.station_interface import MakeStation

PHASES = [{"name": "touch_cat", "t_start": 1.0, "t_end": 2.0}]
TOUCH = Touch(object="target_panel", leg="FR", phase="touch_cat", force=1.0)
SCENE = ["target_panel"]


def _forces(times, fr_force):
    """Synthetic `sim.scene_contact_forces` of a one-object scene: only FR touches it."""
    forces = np.zeros((len(ROBOT_CONTACT_SOURCES), len(times)))
    forces[scene_contact_index("target_panel", "FR", SCENE)] = fr_force
    return forces


def test_no_contact_with_the_panel_fails_the_touch_naming_foot_and_object():
    times = np.linspace(0.0, 3.0, 301)
    rows, problem = judge_touches([TOUCH], SCENE, PHASES, times, _forces(times, 0.0))
    assert rows[0]["touched"] is False and rows[0]["max_normal_force_n"] == 0.0
    assert "touch_cat" in problem and "FR" in problem and "target_panel" in problem


def test_a_force_below_the_threshold_is_not_a_touch():
    times = np.linspace(0.0, 3.0, 301)
    rows, problem = judge_touches([TOUCH], SCENE, PHASES, times, _forces(times, 0.6))
    assert rows[0]["touched"] is False and "0.60 N" in problem


def test_contact_outside_the_phase_does_not_count():
    times = np.linspace(0.0, 3.0, 301)
    rows, problem = judge_touches([TOUCH], SCENE, PHASES, times, _forces(times, np.where(times > 2.5, 5.0, 0.0)))
    assert rows[0]["touched"] is False and problem


def test_another_foot_on_the_panel_is_not_the_reaching_foot():
    times = np.linspace(0.0, 3.0, 301)
    forces = np.zeros((len(ROBOT_CONTACT_SOURCES), len(times)))
    forces[scene_contact_index("target_panel", "FL", SCENE)] = 5.0
    rows, problem = judge_touches([TOUCH], SCENE, PHASES, times, forces)
    assert rows[0]["touched"] is False and problem


def test_a_press_in_the_phase_is_a_touch_with_its_peak_and_time():
    times = np.linspace(0.0, 3.0, 301)
    force = np.where(np.abs(times - 1.5) < 0.05, 2.5, 0.0)
    rows, problem = judge_touches([TOUCH], SCENE, PHASES, times, _forces(times, force))
    assert problem == ""
    assert rows[0]["touched"] is True and rows[0]["max_normal_force_n"] == 2.5
    assert 1.44 < rows[0]["max_force_at_s"] < 1.56


def test_a_phase_that_never_ran_fails_the_touch():
    times = np.linspace(0.0, 3.0, 301)
    _, problem = judge_touches([TOUCH], SCENE, [], times, _forces(times, 5.0))
    assert "never ran" in problem


def _trace(p_TopO):
    p_TopO = np.asarray(p_TopO, float)
    return OffTrunkTrace(np.arange(len(p_TopO)) * 0.1, p_TopO, p_TopO)


def test_an_object_still_on_the_trunk_fails_naming_it():
    row, problem = judge_off_trunk("back_object", _trace([[0.06, 0.02, 0.025]] * 5))
    assert row["on_trunk"] is True and row["left_at_s"] is None
    assert "back_object" in problem and "still on the trunk" in problem


def test_an_object_beside_the_trunk_left_it_at_its_first_sample_off():
    side = robot.TRUNK_HALF_EXTENTS[1] + 0.03
    row, problem = judge_off_trunk("back_object", _trace([[0.06, 0.02, 0.025]] * 3 + [[-0.1, side, -0.05]] * 2))
    assert problem == "" and row["on_trunk"] is False
    assert row["left_at_s"] == pytest.approx(0.3)
    assert row["final_position_trunk_m"] == pytest.approx([-0.1, side, -0.05])


def test_an_object_back_on_the_trunk_at_the_end_did_not_leave_it():
    row, problem = judge_off_trunk("back_object", _trace([[0.3, 0.0, 0.0]] * 2 + [[0.0, 0.0, 0.02]]))
    assert row["on_trunk"] is True and problem


def test_an_object_high_above_the_footprint_is_not_resting_on_it():
    row, _ = judge_off_trunk("back_object", _trace([[0.0, 0.0, ON_TRUNK_MAX_HEIGHT + 0.05]]))
    assert row["on_trunk"] is False


def _back_object_plant():
    station = MakeStation(Scenario(scene=[SceneObject(kind="back_object", position=[0.06, 0.02, 0.0])]))
    plant = station.GetSubsystemByName("plant")
    return plant, plant.GetPositions(plant.CreateDefaultContext())


def test_the_shipped_back_object_starts_on_the_trunk_and_is_off_it_on_the_ground():
    plant, q = _back_object_plant()
    states = np.tile(q[:, None], (1, 2))
    (body,) = plant.GetBodyIndices(plant.GetModelInstanceByName("back_object"))
    start = plant.get_body(body).floating_positions_start() + 4
    states[start : start + 3, 1] = [0.0, 0.5, 0.0]  # on the ground, half a metre to the left
    trace = off_trunk_trace(plant, "back_object", np.array([0.0, 1.0]), states)
    row, problem = judge_off_trunk("back_object", trace)
    assert trace.p_TopO[0] == pytest.approx([0.06, 0.02, 0.026], abs=1e-3)
    assert row["on_trunk"] is False and row["left_at_s"] == 1.0 and problem == ""


def test_the_station_reports_a_foot_pressing_on_a_scene_object_as_that_foots_force():
    """A hand placed 5 mm into the FR foot of the initial (lying) pose: the FR entry is a positive
    normal force, every other robot part's entry is zero."""
    plant, q = _back_object_plant()  # any plant of the Go1 gives the initial foot position
    context = plant.CreateDefaultContext()
    p_foot = plant.GetBodyByName("FR_foot").EvalPoseInWorld(context).translation()
    top = p_foot - [0.0, 0.0, robot.FOOT_RADIUS - 0.005]
    station = MakeStation(Scenario(scene=[SceneObject(kind="hand", position=top.tolist())]))
    context = station.CreateDefaultContext()
    station.GetInputPort("go1.command").FixValue(context, pack_command(robot.LYING_Q, 0, 40, 1, 0))
    # The plant's contact results are those of its last step: take one.
    Simulator(station, context).AdvanceTo(station.GetSubsystemByName("plant").time_step())
    forces = station.GetOutputPort("sim.scene_contact_forces").Eval(context)
    fr = scene_contact_index("hand", "FR", ["hand"])
    assert forces[fr] > 1.0
    assert np.all(np.delete(forces, fr) == 0.0)


def _mission_with(tmp_path, name, old, new):
    text = (missions_dir() / f"{name}.yaml").read_text()
    assert old in text
    path = tmp_path / f"{name}_changed.yaml"
    path.write_text(text.replace(old, new))
    return path


@pytest.mark.parametrize(
    "old,new,field",
    [
        ("object: target_panel, leg: FR", "object: cat, leg: FR", "touches[0].object"),
        ("leg: FR, phase: touch_cat", "leg: XX, phase: touch_cat", "touches[0].leg"),
        ("phase: touch_cat, force", "phase: nowhere, force", "touches[0].phase"),
        ("force: 1.0}", "force: 0.0}", "touches[0].force"),
    ],
)
def test_a_touch_must_name_an_object_a_leg_a_phase_and_a_positive_force(tmp_path, old, new, field):
    with pytest.raises(MissionFileError, match=field.replace(".", r"\.").replace("[", r"\[").replace("]", r"\]")):
        load_mission(str(_mission_with(tmp_path, "hit_target_front", old, new)))


def test_leaves_trunk_must_name_a_scene_object(tmp_path):
    path = _mission_with(tmp_path, "remove_object_from_back", "leaves_trunk: back_object", "leaves_trunk: cup")
    with pytest.raises(MissionFileError, match="leaves_trunk"):
        load_mission(str(path))


def _run_until_touched(tmp_path, mission, duration: float = 8.6):
    """The mission up to just after hit_target_front's reach ends (8.4 s at seed 0; a touch that
    finds nothing goes on 2 cm past its target, about a second more)."""
    scenario = load_scenario(scenario_name="default")
    scenario.mission, scenario.controller, scenario.simulation_duration = str(mission), "whole_body", duration
    return run(scenario=scenario, name="touch", out_dir=tmp_path / "out", quiet=True, replay=False)


def test_a_touch_that_ends_short_of_the_panel_fails_although_the_foot_passed_its_target(tmp_path):
    # The panel 3 cm further away: the foot passes its target by the touch's over-travel (2 cm),
    # still short of the panel's face, and the run fails by the robot's sense and by physics alike.
    path = _mission_with(tmp_path, "hit_target_front", "position: [0.47, -0.13, 0.0]", "position: [0.50, -0.13, 0.0]")
    result = _run_until_touched(tmp_path, path, duration=10.0)
    reach = next(row for row in result["phases"] if row["name"] == "touch_cat")
    assert reach["status"] == "failed" and "no contact felt" in reach["reason"]
    assert result["touches"][0]["touched"] is False and result["touches"][0]["max_normal_force_n"] < 0.1
    assert "did not touch target_panel" in result["reason"]


@pytest.fixture(scope="module")
def push_plant():
    """The plant of push_light_box's scene, and its default positions (the robot lying, the box placed)."""
    scenario = load_scenario()
    scenario.scene = load_mission("push_light_box").scene
    plant = MakeStation(scenario).GetSubsystemByName("plant")
    return plant, plant.GetPositions(plant.CreateDefaultContext())


def _push_states(plant, q0, box_shift, trunk_shift=0.0):
    """Plant states over 0-3 s: the box's root body, and the whole robot with its feet, move
    `box_shift` and `trunk_shift` [m] along x during the push phase (1-2 s)."""
    times = np.linspace(0.0, 3.0, 301)
    ramp = np.clip(times - 1.0, 0.0, 1.0)
    box = root_body(plant, plant.GetModelInstanceByName("light_box"))
    states = np.zeros((plant.num_multibody_states(), len(times)))
    states[: len(q0)] = q0[:, None]
    states[box.floating_positions_start() + 4] += box_shift * ramp
    states[robot.Go1PlantMap.from_plant(plant).base_q_start + 4] += trunk_shift * ramp
    return times, states


PUSH = dict(object="light_box", phase="push_box", distance=0.10, stance_slide=0.01)
PUSH_PHASES = [{"name": "push_box", "t_start": 1.0, "t_end": 2.0}]


def test_a_push_that_moved_the_box_far_enough_from_a_firm_stance_passes(push_plant):
    plant, q0 = push_plant
    times, states = _push_states(plant, q0, 0.12)
    row, problem = judge_object_push(plant, ObjectPush(**PUSH), PUSH_PHASES, times, states)
    assert problem == "" and row["moved_m"] == pytest.approx(0.12, abs=1e-3)


def test_a_box_moved_too_little_fails_the_push_naming_it(push_plant):
    plant, q0 = push_plant
    times, states = _push_states(plant, q0, 0.05)
    row, problem = judge_object_push(plant, ObjectPush(**PUSH), PUSH_PHASES, times, states)
    assert row["moved_m"] == pytest.approx(0.05, abs=1e-3)
    assert "light_box moved 5.0 cm from push_box to the end of push_box" in problem


def _slide_states(plant, q0, push_shift, slide_shift):
    """Plant states over 0-4 s: the box moves `push_shift` [m] along x in the push phase (1-2 s)
    and `slide_shift` more in the phase after it (2-3 s), as a struck box slides on."""
    times = np.linspace(0.0, 4.0, 401)
    shift = push_shift * np.clip(times - 1.0, 0.0, 1.0) + slide_shift * np.clip(times - 2.0, 0.0, 1.0)
    box = root_body(plant, plant.GetModelInstanceByName("light_box"))
    states = np.zeros((plant.num_multibody_states(), len(times)))
    states[: len(q0)] = q0[:, None]
    states[box.floating_positions_start() + 4] += shift
    return times, states


def test_a_struck_box_is_measured_after_it_slid_until_the_named_phase_ends(push_plant):
    plant, q0 = push_plant
    times, states = _slide_states(plant, q0, 0.04, 0.16)
    phases = [*PUSH_PHASES, {"name": "box_slides", "t_start": 2.0, "t_end": 3.0}]
    struck = ObjectPush(**{**PUSH, "distance": 0.18})
    row, problem = judge_object_push(plant, struck, phases, times, states)
    assert row["moved_m"] == pytest.approx(0.04, abs=1e-3) and "4.0 cm" in problem
    measured_later = ObjectPush(**{**PUSH, "distance": 0.18, "until": "box_slides"})
    row, problem = judge_object_push(plant, measured_later, phases, times, states)
    assert problem == "" and row["moved_m"] == pytest.approx(0.20, abs=1e-3) and row["until"] == "box_slides"


def test_stance_feet_that_slid_fail_the_push(push_plant):
    plant, q0 = push_plant
    times, states = _push_states(plant, q0, 0.12, trunk_shift=0.02)
    row, problem = judge_object_push(plant, ObjectPush(**PUSH), PUSH_PHASES, times, states)
    assert row["stance_feet_slide_m"], "the lying robot's feet are on the ground"
    assert max(row["stance_feet_slide_m"].values()) == pytest.approx(0.02, abs=1e-3)
    assert "stance foot slid 20.0 mm in push_box" in problem


def test_an_object_push_naming_no_scene_object_is_refused(tmp_path):
    text = (missions_dir() / "push_light_box.yaml").read_text().replace("object: light_box", "object: heavy_box")
    path = tmp_path / "bad_push.yaml"
    path.write_text(text)
    with pytest.raises(MissionFileError, match="object_push.object: must name a scene object"):
        load_mission(str(path))


def test_an_object_push_measured_until_an_earlier_phase_is_refused(tmp_path):
    text = (missions_dir() / "push_light_box.yaml").read_text()
    text = text.replace("stance_slide: 0.01}", "stance_slide: 0.01, until: touch_box}")
    path = tmp_path / "bad_until.yaml"
    path.write_text(text)
    with pytest.raises(MissionFileError, match="object_push.until: must name `phase` or a phase after it"):
        load_mission(str(path))
