"""walk_to: the stop of largest SUF against a hand-worked case and a brute-force grid, bad
walk_to phases named by field, and a short walk_to mission judged by physics (the whole
comparison with the fixed stop is the benchmark's: python -m pedi_drake.benchmarks.walk_to)."""

import itertools

import numpy as np
import pytest

from pedi_drake.evaluation import judge
from pedi_drake.exceptions import MissionFileError
from pedi_drake.leg_kinematics import working_position_B
from pedi_drake.locomotion.footholds import NOMINAL_FEET_B
from pedi_drake.mission.spec import load_mission
from pedi_drake.run import simulate
from pedi_drake.scenario import load_scenario
from pedi_drake.suf.stop import StopCase, StopLimits, choose_stop, evaluate_stop

FIXED = (0.0, 0.0, 0.0)


def _case(target) -> StopCase:
    return StopCase(
        leg="FR",
        targets=(tuple(target),),
        lift_B=tuple(working_position_B("FR", 0.15)),
        feet_B=tuple(tuple(p) for p in NOMINAL_FEET_B),
        height=0.28,
    )


def test_a_target_out_of_reach_of_the_fixed_stop_is_walked_up_to():
    # Hand-worked: lifting the front right leg, the trunk shifts about 4 cm back over the other
    # three feet, which puts the hip 0.15 m ahead of the fixed stop and 0.13 m above a target
    # 0.15 m high; the stretched leg reaches 0.43 m, less the joint margins. A target 0.56 m ahead
    # (0.43 m from the hip) is out of reach there, and within it from a stop 8 cm or more on.
    case = _case((0.56, -0.13, 0.15))
    result = choose_stop(case, FIXED)
    assert not result.fixed.posture.feasible
    assert result.best.posture.feasible and result.best.posture.suf > 0.0
    assert 0.08 <= result.best.stop[0] <= 0.10 + 1e-9


def test_the_search_finds_the_grid_s_best_and_never_loses_to_the_fixed_stop():
    case = _case((0.447, -0.13, 0.2))
    limits = StopLimits(shift=0.06, turn=0.2)
    result = choose_stop(case, FIXED, limits)
    grid = [
        evaluate_stop(case, stop)
        for stop in itertools.product(
            np.linspace(-0.06, 0.06, 7), np.linspace(-0.06, 0.06, 7), np.linspace(-0.2, 0.2, 5)
        )
    ]
    best = max(grid, key=lambda e: e.rank)
    assert result.fixed.posture.feasible
    assert result.best.rank >= result.fixed.rank
    assert result.best.posture.suf >= 0.98 * best.posture.suf
    assert np.all(np.abs(np.subtract(result.best.stop, FIXED)) <= [0.06 + 1e-9, 0.06 + 1e-9, 0.2 + 1e-9])


WALK_TO = """\
contact_ramp_time: 0.06
phases:
  - {kind: walk_to, leg: FR, position: [0.5, 0.0], yaw: 0.0, speed: 0.15}
  - {kind: leg_to_pedipulation, leg: FR, posture: optimal, timeout: 8.0}
  - {kind: reach, leg: FR, target: [0.95, -0.13, 0.2], tolerance: 0.005, timeout: 6.0}
  - {kind: leg_to_support, leg: FR, timeout: 6.0}
"""


@pytest.mark.parametrize(
    "old, new, field",
    [
        ("speed: 0.15}", "speed: 0.15, stop: nearest}", "phases[0].stop"),
        ("speed: 0.15}", "speed: 0.15, search: [0.1]}", "phases[0].search"),
        ("speed: 0.15}", "speed: 0.15, goal: {}}", "phases[0].goal"),
        ("leg: FR, position", "leg: FL, position", "phases[0].leg"),
        ("target: [0.95, -0.13, 0.2],", "target: [0.4, -0.13, 0.2], frame: trunk,", "phases[0].leg"),
    ],
)
def test_a_bad_walk_to_is_refused_naming_its_field(tmp_path, old, new, field):
    assert old in WALK_TO
    path = tmp_path / "walk_to.yaml"
    path.write_text(WALK_TO.replace(old, new))
    with pytest.raises(MissionFileError, match=field.replace("[", r"\[").replace("]", r"\]")):
        load_mission(str(path))


def test_walk_to_stops_where_the_suf_is_larger_and_the_foot_touches_the_cat():
    scenario = load_scenario(
        scenario_text="{mission: quick/walk_to_touch, simulation_duration: 40.0, robot: {initial_pose: standing}}"
    )
    result = judge.judge_run(simulate(scenario=scenario, name="walk_to_touch", quiet=True, replay=False))
    assert result["success"], result["reason"]
    (walk,) = result["walks"]
    stop = walk["stop"]
    assert stop["chosen_by"] == "suf" and stop["taken_suf_n"] > stop["fixed_suf_n"]
    assert np.linalg.norm(np.subtract(stop["taken_W"][:2], stop["fixed_W"][:2])) > 0.02  # it did move
    assert walk["goal_error_m"] <= 0.03  # judged against the stop it took, by ground truth
    (posture,) = result["postures"]
    assert posture["taken"] == "optimal"
    touch = next(row for row in result["foot_errors_m"] if row["phase"] == "touch_cat")
    assert touch["error"] <= 0.005
