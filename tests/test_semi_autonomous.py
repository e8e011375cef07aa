"""posture: optimal and the semi-autonomous block are validated on load (a bad value names the
file and the field); the goal comes from the reaches that follow; an operator target is checked
before anything moves."""

from pathlib import Path

import numpy as np
import pytest
from pydrake.math import RigidTransform, RollPitchYaw

from pedi_drake.exceptions import MissionFileError
from pedi_drake.mission.mission_manager import ik_legs_of, needs_posture_planner
from pedi_drake.mission.semi_autonomous import target_problem, target_sequence
from pedi_drake.mission.spec import LegToPedipulation, LegToSupport, Reach, load_mission, shipped_missions
from pedi_drake.operator.command import FRAME_TRUNK, FRAME_WORLD, KIND_POSITION, KIND_VELOCITY, OperatorCommand

LIFT = "{kind: leg_to_pedipulation, leg: FR, posture: optimal, timeout: 8.0}"
REACH = "{kind: reach, name: touch, leg: FR, target: [0.40, -0.13, 0.17], approach_offset: [-0.05, 0.0, 0.0]}"
PRESS = "{kind: press, leg: FR, direction: [1.0, 0.0, 0.0], max_displacement: 0.04}"
REACH_2 = "{kind: reach, name: touch_2, leg: FR, target: [0.40, -0.10, 0.17]}"
BACK = "{kind: leg_to_support, leg: FR}"


def _mission(tmp_path: Path, *phases: str, header: str = "") -> Path:
    path = tmp_path / "mission.yaml"
    lines = "".join(f"  - {phase}\n" for phase in ("{kind: stand_up}", *phases))
    path.write_text(f"{header}phases:\n{lines}")
    return path


def test_an_optimal_lift_gets_the_targets_and_passing_points_of_its_reaches(tmp_path):
    mission = load_mission(str(_mission(tmp_path, LIFT, REACH, PRESS, REACH_2, BACK)))
    goal = mission.phases[1].goal
    assert goal.leg == "FR" and goal.frame == "world" and goal.attitude is None
    assert goal.targets == [[0.40, -0.13, 0.17], [0.40, -0.10, 0.17]]
    approach, press_end = goal.reach_only
    assert np.allclose(approach, [0.35, -0.13, 0.17]) and np.allclose(press_end, [0.44, -0.13, 0.17])
    assert needs_posture_planner(mission)


def test_a_body_rotate_among_the_targets_sets_the_attitude(tmp_path):
    rotate = "{kind: body_rotate, rpy: [0.25, 0.0, 0.0]}"
    mission = load_mission(str(_mission(tmp_path, LIFT, rotate, REACH, BACK)))
    assert mission.phases[1].goal.attitude == [0.25, 0.0, 0.0]


def test_the_shipped_missions_keep_the_fixed_posture():
    for name in shipped_missions():
        mission = load_mission(name)
        lifts = [p for p in mission.phases if isinstance(p, LegToPedipulation)]
        assert all(p.posture == "fixed" and p.goal is None for p in lifts), name
        assert not needs_posture_planner(mission)


@pytest.mark.parametrize(
    ("phases", "field", "problem"),
    [
        (("{kind: leg_to_pedipulation, leg: FR, posture: best}", REACH, BACK), "posture", "must be one of"),
        (("{kind: leg_to_pedipulation, leg: FR, posture: optimal, timeout: 4.0}", REACH, BACK), "timeout", "exceed"),
        (
            ("{kind: leg_to_pedipulation, leg: FR, posture: optimal, trunk_targets: hand, timeout: 8.0}", REACH, BACK),
            "trunk_targets",
            "must be one of",
        ),
        ((LIFT, BACK), "posture", "no reach"),
        (
            (LIFT, "{kind: reach, leg: FR, target: [0.4, -0.1, 0.2], frame: trunk}", REACH, BACK),
            "posture",
            "mix frames",
        ),
        ((LIFT, "{kind: body_move, offset: [0.0, 0.0, -0.02]}", REACH, BACK), "posture", "changes the stance"),
        (
            ("{kind: leg_to_pedipulation, leg: FR, posture: optimal, timeout: 8.0, goal: {targets: []}}", REACH),
            "goal",
            "not a field",
        ),
    ],
)
def test_a_bad_optimal_lift_names_file_and_field(tmp_path, phases, field, problem):
    path = _mission(tmp_path, *phases)
    with pytest.raises(MissionFileError, match=rf"phases\[1\]\.{field}: .*{problem}") as error:
        load_mission(str(path))
    assert str(path) in str(error.value)


def test_an_optimal_lift_on_the_prongs_is_refused(tmp_path):
    path = _mission(tmp_path, "{kind: lean_on_prongs}", LIFT, REACH, BACK)
    path.write_text("robot: {prongs: {}}\n" + path.read_text())
    with pytest.raises(MissionFileError, match="prongs"):
        load_mission(str(path))


@pytest.mark.parametrize(
    ("block", "field"),
    [
        ("{leg: XX}", "leg"),
        ("{box_min: [0.5, 0.0, 0.0], box_max: [0.1, 0.1, 0.1]}", "box_max"),
        ("{box_min: [.nan, 0.0, 0.0]}", "box_min"),
        ("{min_height: 0.01}", "min_height"),
        ("{hold: -1.0}", "hold"),
    ],
)
def test_a_bad_semi_autonomous_block_names_file_and_field(tmp_path, block, field):
    path = _mission(tmp_path, header=f"semi_autonomous: {block}\n")
    with pytest.raises(MissionFileError, match=rf"semi_autonomous\.{field}"):
        load_mission(str(path))


def test_the_semi_autonomous_block_sets_the_inserted_phases(tmp_path):
    mission = load_mission(str(_mission(tmp_path, header="semi_autonomous: {leg: FL, hold: 2.0}\n")))
    assert ik_legs_of(mission) == ("FL",) and needs_posture_planner(mission)
    lift, reach, back = target_sequence(mission.semi_autonomous, np.array([0.4, 0.13, 0.2]), 2)
    assert isinstance(lift, LegToPedipulation) and lift.posture == "optimal" and lift.name == "semi_2_lift"
    assert lift.goal.targets == [[0.4, 0.13, 0.2]] and lift.goal.frame == "world"
    assert isinstance(reach, Reach) and reach.target == [0.4, 0.13, 0.2] and reach.hold == 2.0
    assert isinstance(back, LegToSupport) and back.leg == "FL"


STANDING = RigidTransform(np.array([0.0, 0.0, 0.28]))


def _command(value, frame=FRAME_WORLD, kind=KIND_POSITION) -> OperatorCommand:
    return OperatorCommand(frame=frame, kind=kind, value=np.array(value, float))


@pytest.mark.parametrize(
    ("command", "problem"),
    [
        (_command([0.40, -0.13, 0.20]), None),
        (_command([0.40, -0.13, -0.08], frame=FRAME_TRUNK), None),
        (_command([0.05, 0.0, 0.0], kind=KIND_VELOCITY), "not a position"),
        (_command([1.0, -0.13, 0.20]), "outside the workspace"),
        (_command([0.40, 0.20, 0.20]), "outside the workspace"),
        (_command([0.40, -0.13, 0.03]), "too low"),
        (_command([np.inf, -0.13, 0.20]), "non-finite"),
    ],
)
def test_an_operator_target_is_checked_before_anything_moves(tmp_path, command, problem):
    block = load_mission(str(_mission(tmp_path, header="semi_autonomous: {}\n"))).semi_autonomous
    found = target_problem(block, command, STANDING)
    assert (found is None) if problem is None else (problem in found)


def test_the_workspace_box_turns_with_the_trunk(tmp_path):
    block = load_mission(str(_mission(tmp_path, header="semi_autonomous: {}\n"))).semi_autonomous
    turned = RigidTransform(RollPitchYaw(0.0, 0.0, np.pi / 2), [0.0, 0.0, 0.28])
    # 0.4 m ahead of the turned trunk is +y in the world.
    assert target_problem(block, _command([0.13, 0.40, 0.20]), turned) is None
    assert "outside the workspace" in target_problem(block, _command([0.40, -0.13, 0.20]), turned)
