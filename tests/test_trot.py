"""The trot: its schedule, footholds and twist's rate limit (pedi_drake.locomotion.trot), and a
short trot in simulation on the HQP, judged by ground truth.

The floors' trots (3 m at 0.5 m/s, half a turn in place, 6 seeds) are the benchmark's:
`python -m pedi_drake.benchmarks.walking`.
"""

import numpy as np
import pytest

from pedi_drake.evaluation.judge import judge_run
from pedi_drake.exceptions import MissionFileError, PediError
from pedi_drake.locomotion.footholds import NOMINAL_FEET_B, PlanarPose
from pedi_drake.locomotion.trot import TROT_PAIRS, TrotTiming, next_twist, pair_of, trot_foothold_W
from pedi_drake.mission.spec import load_mission
from pedi_drake.run import simulate
from pedi_drake.scenario import load_scenario

TIMING = TrotTiming()
SHORT_TROT = """\
description: A short trot forward.
contact_ramp_time: 0.02
phases:
  - {kind: stand_up}
  - {kind: walk_velocity, twist: [0.5, 0.0, 0.0], duration: 2.0, gait: trot}
"""


def test_the_pairs_are_diagonal_and_alternate():
    for pair in TROT_PAIRS:
        front, hind = sorted(pair)  # "F." sorts before "R."
        assert front[0] == "F" and hind[0] == "R" and front[1] != hind[1]
    assert [pair_of(k) for k in range(4)] == [TROT_PAIRS[0], TROT_PAIRS[1], TROT_PAIRS[0], TROT_PAIRS[1]]
    assert set(TROT_PAIRS[0]) | set(TROT_PAIRS[1]) == {"FR", "FL", "RR", "RL"}


def test_the_foothold_is_raiberts_point_by_hand():
    # 0.5 m/s forward, mid-stance 1.5 half periods (0.375 s) ahead: 0.1875 m ahead of the hip; the
    # trunk 0.1 m/s too fast sideways puts the foot 1 cm further that way.
    hold = trot_foothold_W(
        "FR", PlanarPose(0.0, 0.0, 0.0), np.array([0.5, 0.0, 0.0]), np.array([0.0, 0.1, 0.0]), TIMING
    )
    np.testing.assert_allclose(hold, NOMINAL_FEET_B[0] + [0.1875, TIMING.velocity_gain * 0.1])


def test_the_twist_changes_within_the_accelerations():
    twist = next_twist(np.zeros(3), np.array([0.5, -0.5, 1.0]), 0.25, TIMING)
    np.testing.assert_allclose(twist, [0.25, -0.25, 0.5])
    assert next_twist(twist, np.array([0.3, -0.25, 0.5]), 0.25, TIMING) == pytest.approx([0.3, -0.25, 0.5])


def test_a_ramp_that_leaves_no_swing_is_refused():
    with pytest.raises(PediError, match="ramp"):
        TrotTiming(period=0.2, ramp=0.06)


def test_a_trot_with_a_slow_contact_ramp_is_refused_naming_the_field(tmp_path):
    path = tmp_path / "trot.yaml"
    path.write_text(SHORT_TROT.replace("contact_ramp_time: 0.02", "contact_ramp_time: 0.06"))
    with pytest.raises(MissionFileError, match="contact_ramp_time"):
        load_mission(str(path))


def test_a_short_trot_on_the_hqp_keeps_its_speed_by_ground_truth(tmp_path):
    path = tmp_path / "trot.yaml"
    path.write_text(SHORT_TROT)
    scenario = load_scenario(scenario_text=f"{{mission: '{path}', controller: whole_body}}")
    result = judge_run(simulate(scenario=scenario, name="short_trot", quiet=True, replay=False))
    assert result["success"], result["reason"]
    (walk,) = result["walks"]
    # Over the commanded 2 s, the first 0.5 s of which the speed ramps up at 1 m/s^2.
    assert 0.35 < walk["mean_velocity_m_s"][0] < 0.55 and abs(walk["mean_velocity_m_s"][1]) < 0.1
    assert max(walk["max_stance_slip_m"].values()) < 0.01
    assert walk["steps"] >= 16
