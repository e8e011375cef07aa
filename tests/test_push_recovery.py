"""Paper 003's push recovery on four feet (Section VII-A), short: the push judged by physics.

The short demos (missions/demos/push_recovery_short_*.yaml) lower the standing robot onto its
prongs, or to the same height without them, and push the trunk sideways with 30 N; the figures
come from simulation ground truth (pedi_drake.evaluation.push_response), never from the controller.
"""

import numpy as np
import pytest

from pedi_drake import robot
from pedi_drake.benchmarks.demos import simulate_demo
from pedi_drake.evaluation.judge import judge_pushes
from pedi_drake.evaluation.push_response import STANCE_FOOT_SLIDE_LIMIT
from pedi_drake.run_logs import SignalLog
from pedi_drake.scenario import Push, RobotConfig
from pedi_drake.station.initial_state import initial_trunk_pose

SHORT_DEMOS = {"prongs": "push_recovery_short_prongs", "no_prongs": "push_recovery_short_no_prongs"}


@pytest.fixture(scope="module")
def pushed() -> dict[str, dict]:
    """The judged result of each short push demo, by "prongs" / "no_prongs"."""
    return {key: simulate_demo(name)[1] for key, name in SHORT_DEMOS.items()}


@pytest.mark.parametrize("variant", sorted(SHORT_DEMOS))
def test_no_stance_foot_slides_more_than_1cm_and_nothing_falls(pushed, variant):
    result = pushed[variant]
    assert result["success"], result["reason"]
    assert not result["fell"] and result["stack"] == "paper003"
    (push,) = result["pushes"]
    assert push["stance_legs"] == list(robot.LEG_NAMES)
    assert push["max_foot_slide_m"] < STANCE_FOOT_SLIDE_LIMIT, push["foot_slide_m"]


def test_the_prongs_carry_part_of_the_weight_through_the_push(pushed):
    assert pushed["prongs"]["pushes"][0]["prong_load_N"] > 30.0
    assert abs(pushed["no_prongs"]["pushes"][0]["prong_load_N"]) < 2.0


def test_with_prongs_the_trunk_moves_less_and_the_knees_work_less(pushed):
    # Paper 003's claim (Fig. 6), measured on the simulated Go1.
    with_prongs, without = pushed["prongs"]["pushes"][0], pushed["no_prongs"]["pushes"][0]
    assert with_prongs["trunk_displacement_m"] < without["trunk_displacement_m"]
    assert max(with_prongs["knee_torque_peak_Nm"].values()) < max(without["knee_torque_peak_Nm"].values())


def _sliding_logs(plant, slide: float) -> dict[str, SignalLog]:
    """Logs of the standing robot whose trunk, and so every foot, slides `slide` [m] along x
    between 0.2 s and 0.8 s."""
    plant_map = robot.Go1PlantMap.from_plant(plant)
    X_WB = initial_trunk_pose(RobotConfig(initial_pose="standing"))
    times = np.linspace(0.0, 1.0, 101)
    states = np.zeros((plant.num_positions() + plant.num_velocities(), len(times)))
    for k, t in enumerate(times):
        p_WB = X_WB.translation() + [slide * np.clip((t - 0.2) / 0.6, 0.0, 1.0), 0.0, 0.0]
        states[: plant.num_positions(), k] = plant_map.full_positions(
            X_WB.rotation().ToQuaternion().wxyz(), p_WB, robot.STANDING_Q, plant.num_positions()
        )
    return {
        "sim.plant_state": SignalLog(times, states),
        "sim.motor_torque": SignalLog(times, np.zeros((12, len(times)))),
        "sim.foot_contact_forces": SignalLog(times, np.zeros((12, len(times)))),
    }


@pytest.mark.parametrize("slide,fails", [(0.015, True), (0.005, False)])
def test_the_judge_fails_a_push_under_which_a_stance_foot_slides_over_1cm(go1_plant, slide, fails):
    plant, _ = go1_plant
    push = Push(force=30.0, direction=[1.0, 0.0, 0.0], start=0.1, ramp=0.1, duration=0.7)
    (row,), reason = judge_pushes(plant, _sliding_logs(plant, slide), [push])
    assert row["foot_slide_m"] == pytest.approx(dict.fromkeys(robot.LEG_NAMES, slide), abs=1e-9)
    assert bool(reason) == fails
    if fails:
        assert "foot slid 1.5 cm under pushes[0]" in reason
