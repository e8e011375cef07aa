"""The push judge of paper 003's push recovery (Section VII-A) on synthetic logs: a stance foot
sliding more than 1 cm fails the push. The short runs themselves are judged in
test_paper003_evaluations.py."""

import numpy as np
import pytest

from pedi_drake import robot
from pedi_drake.evaluation.judge import judge_pushes
from pedi_drake.run_logs import SignalLog
from pedi_drake.scenario import Push, RobotConfig
from pedi_drake.station.initial_state import initial_trunk_pose


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
