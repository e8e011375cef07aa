"""Mission files: the shipped library loads; mistakes name the file, the phase index and the field."""

from pathlib import Path

import pytest
from pydrake.common.yaml import yaml_load

from pedi_drake.diagram import apply_mission
from pedi_drake.exceptions import MissionFileError
from pedi_drake.mission.spec import PHASE_KINDS, LegToSupport, Reach, load_mission, shipped_demos, shipped_missions
from pedi_drake.resources import missions_dir, scenarios_dir
from pedi_drake.scenario import Scenario, load_scenario

PAPER_MISSIONS = {
    "hit_target_front",
    "hit_target_side",
    "hit_target_behind",
    "open_door",
    "remove_object_from_back",
    "obstacle_sensing",
    "give_paw",
    "prong_push_box",
}


def _write(tmp_path: Path, body: str) -> str:
    path = tmp_path / "m.yaml"
    path.write_text(body)
    return str(path)


def test_the_shipped_library_has_every_paper_mission():
    assert PAPER_MISSIONS <= set(shipped_missions())


@pytest.mark.parametrize("name", sorted(PAPER_MISSIONS))
def test_shipped_mission_loads_and_starts_by_standing_up(name):
    mission = load_mission(name)
    assert mission.phases[0].__class__.__name__ == "StandUp"
    assert any(isinstance(phase, Reach) for phase in mission.phases)


@pytest.mark.parametrize("path", sorted((missions_dir() / "operator").glob("*.yaml")), ids=lambda path: path.stem)
def test_every_operator_mission_loads_and_lets_the_operator_take_or_direct_a_foot(path):
    mission = load_mission(f"operator/{path.stem}")
    teleop_phases = [phase for phase in mission.phases if phase.__class__.__name__ == "TeleopFoot"]
    assert teleop_phases or mission.teleop is not None or mission.semi_autonomous is not None


def test_every_demo_mission_loads_with_a_demo_scenario_of_its_name():
    demos_file = scenarios_dir() / "wbc_demos.yaml"
    names = {name.removeprefix("demos/") for name in shipped_demos()}
    assert names == set(yaml_load(filename=str(demos_file)))
    for name in names:
        scenario = load_scenario(filename=demos_file, scenario_name=name)
        assert scenario.mission == f"demos/{name}" and scenario.estimator == "ground_truth"
        assert load_mission(scenario.mission).name == name
    # The demos are not library missions (those run on the default scenario).
    assert not names & set(shipped_missions())


def test_numbers_are_read_as_floats(tmp_path):
    mission = load_mission(_write(tmp_path, "phases:\n  - {kind: reach, leg: FL, target: [1, 0, 1]}\n"))
    assert mission.phases[0].target == [1.0, 0.0, 1.0] and isinstance(mission.phases[0].target[0], float)


def test_reach_takes_companion_legs(tmp_path):
    body = "phases:\n  - {kind: reach, leg: FR, target: [1, -1, 1], together: [{leg: FL, target: [1, 1, 1]}]}\n"
    (phase,) = load_mission(_write(tmp_path, body)).phases
    assert [(c.leg, c.target) for c in phase.together] == [("FL", [1.0, 1.0, 1.0])]
    assert isinstance(phase.together[0].target[0], float)
    shipped = {phase.name: phase for phase in load_mission("prong_push_box").phases}
    assert [shipped[name].together[0].leg for name in ("touch_box", "push_box")] == ["FL", "FL"]


@pytest.mark.parametrize(
    "body,pattern",
    [
        ("phases:\n  - {kind: fly}\n", r"phases\[0\]\.kind: unknown phase kind 'fly'"),
        ("phases:\n  - {kind: stand_up}\n  - {kind: reach, leg: FX}\n", r"phases\[1\]\.leg: must be one of"),
        ("phases:\n  - {kind: reach, target: [1, 2]}\n", r"phases\[0\]\.target: expected \[x, y, z\]"),
        ("phases:\n  - {kind: reach, targt: [1, 2, 3]}\n", r"phases\[0\]\.targt: unknown field"),
        ("phases:\n  - {kind: wait, duration: soon}\n", r"phases\[0\]\.duration: expected a number"),
        ("phases:\n  - {kind: wait, timeout: -1}\n", r"phases\[0\]\.timeout: must be > 0"),
        ("phases:\n  - {kind: reach, frame: hip}\n", r"phases\[0\]\.frame: must be one of"),
        ("phases:\n  - {kind: press, direction: [0, 0, 0]}\n", r"phases\[0\]\.direction: expected a unit"),
        ("phases:\n  - {kind: body_move, height: -0.1}\n", r"phases\[0\]\.height: must be a finite number >= 0"),
        ("phases: []\n", r"phases: expected a non-empty list"),
        ("phases:\n  - {kind: wait, name: a}\n  - {kind: wait, name: a}\n", r"duplicate phase names \['a'\]"),
        ("scene:\n  - {kind: box, positon: [0, 0, 0]}\nphases:\n  - {kind: wait}\n", r"scene\[0\]\.positon: unknown"),
        (
            "phases:\n  - {kind: wait}\n  - {kind: reach, together: [{leg: FX, target: [1, 2, 3]}]}\n",
            r"phases\[1\]\.together\[0\]\.leg: must be one of .*got 'FX'",
        ),
        (
            "phases:\n  - {kind: reach, together: [{leg: FL}]}\n",
            r"phases\[0\]\.together\[0\]\.target: expected \[x, y, z\] in metres, got nothing",
        ),
        (
            "phases:\n  - {kind: reach, together: [{leg: FL, target: [1, 2]}]}\n",
            r"phases\[0\]\.together\[0\]\.target: expected \[x, y, z\]",
        ),
        (
            "phases:\n  - {kind: reach, together: [{target: [1, 2, 3]}]}\n",
            r"phases\[0\]\.together\[0\]\.leg: must be one of",
        ),
        (
            "phases:\n  - {kind: reach, leg: FR, together: [{leg: FR, target: [1, 2, 3]}]}\n",
            r"phases\[0\]\.together\[0\]\.leg: FR already moves in this phase",
        ),
        (
            "phases:\n  - {kind: reach, together: [{leg: FL, target: [1, 2, 3], via_points: [[1, 2]]}]}\n",
            r"phases\[0\]\.together\[0\]\.via_points\[0\]: expected \[x, y, z\]",
        ),
        (
            "phases:\n  - {kind: reach, together: [{leg: FL, targt: [1, 2, 3]}]}\n",
            r"phases\[0\]\.together\[0\]\.targt: unknown field; CompanionReach has",
        ),
        ("phases:\n  - {kind: reach, together: {leg: FL}}\n", r"phases\[0\]\.together: expected a list"),
        ("phases:\n  - {kind: body_path, radius: -0.1}\n", r"phases\[0\]\.radius: must be >= 0 m"),
        ("phases:\n  - {kind: body_path}\n", r"phases\[0\]\.via_points: give a circle radius > 0 or"),
        ("phases:\n  - {kind: body_path, via_points: [[0.01, 0]]}\n", r"phases\[0\]\.via_points\[0\]: expected"),
        ("phases:\n  - {kind: body_path, radius: 0.03, laps: 0}\n", r"phases\[0\]\.laps: must be at least 1"),
        ("phases:\n  - {kind: hold_foot_pose, leg: XX}\n", r"phases\[0\]\.leg: must be one of"),
        ("phases:\n  - {kind: lean_on_prongs, prongs: [front]}\n", r"phases\[0\]\.prongs\[0\]: expected a prong name"),
        ("phases:\n  - {kind: body_rotate, pivot: tip}\n", r"phases\[0\]\.pivot: expected a prong name"),
        ("force_estimate: sensor\nphases:\n  - {kind: wait}\n", r"force_estimate: must be one of"),
    ],
)
def test_mistakes_name_file_phase_and_field(tmp_path, body, pattern):
    with pytest.raises(MissionFileError, match=r"m\.yaml.*" + pattern):
        load_mission(_write(tmp_path, body))


def test_unknown_mission_name_lists_the_library():
    with pytest.raises(MissionFileError, match=r"unknown mission 'nope'; shipped missions: .*hit_target_front"):
        load_mission("nope")


def test_missing_mission_file_is_named(tmp_path):
    with pytest.raises(MissionFileError, match=r"nothere\.yaml: mission file not found"):
        load_mission(str(tmp_path / "nothere.yaml"))


def test_every_phase_kind_has_a_timeout_and_a_name():
    for kind in PHASE_KINDS.values():
        phase = kind()
        assert phase.timeout > 0 and hasattr(phase, "name")


def test_the_longest_duration_lets_every_phase_time_out_then_recover(tmp_path):
    path = tmp_path / "m.yaml"
    path.write_text(
        "phases:\n"
        "  - {kind: stand_up, height: 0.28, duration: 2.0, timeout: 4.0}\n"
        "  - {kind: wait, duration: 1.0, timeout: 2.5}\n"
    )
    recovery = 2 * LegToSupport().timeout  # both front legs put back after a failure
    assert load_mission(str(path)).longest_duration() == pytest.approx(4.0 + 2.5 + recovery)


def test_a_mission_names_the_task_stack_it_runs_on(tmp_path):
    mission = load_mission(_write(tmp_path, "stack: paper003\nphases:\n  - {kind: wait}\n"))
    assert apply_mission(Scenario(controller="whole_body"), mission).whole_body.stack == "paper003"
    unnamed = load_mission(_write(tmp_path, "phases:\n  - {kind: wait}\n"))
    assert apply_mission(Scenario(controller="whole_body"), unnamed).whole_body.stack == "paper000"


def test_an_unknown_task_stack_names_the_file_and_field(tmp_path):
    with pytest.raises(MissionFileError, match=r"m\.yaml: stack: must be one of \('paper000', 'paper003'\)"):
        load_mission(_write(tmp_path, "stack: paper004\nphases:\n  - {kind: wait}\n"))
