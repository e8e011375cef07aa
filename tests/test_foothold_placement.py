"""leg_to_support with a foothold: the foot goes down where the phase says (trunk or world frame),
judged by the simulation's true foot position; a foothold beyond the leg's reach is refused on
load (trunk frame) or fails the phase with the reason (world frame)."""

import numpy as np
import pytest

from pedi_drake import robot
from pedi_drake.evaluation.mission_results import foot_positions_W
from pedi_drake.exceptions import MissionFileError
from pedi_drake.locomotion.footholds import NOMINAL_FEET_B, PlanarPose, stance_pose
from pedi_drake.mission.spec import load_mission
from pedi_drake.run import simulate
from pedi_drake.scenario import load_scenario

FR = robot.LEG_NAMES.index("FR")
# 7 cm ahead of and 2 cm outside the point under FR's hip, in the trunk's heading frame [m].
FOOTHOLD_B = NOMINAL_FEET_B[FR] + np.array([0.07, -0.02])
MISSION = """
phases:
  - {kind: leg_to_pedipulation, leg: FR, duration: 1.0, timeout: 4.0}
  - {kind: leg_to_support, name: place, leg: FR, foothold: [%.4f, %.4f], frame: %s, duration: 1.0}
"""


def _mission(tmp_path, foothold, frame: str = "trunk"):
    path = tmp_path / "mission.yaml"
    path.write_text(MISSION % (foothold[0], foothold[1], frame))
    return path


def _run(path):
    scenario = load_scenario(
        scenario_text=f"{{mission: {path}, robot: {{initial_pose: standing}}, simulation_duration: 9.0}}"
    )
    return simulate(scenario=scenario, name="foothold", quiet=True, replay=False)


def test_the_foot_goes_down_at_the_trunk_frame_foothold(tmp_path):
    record = _run(_mission(tmp_path, FOOTHOLD_B))
    assert record.mission_progress().status == "succeeded", record.mission_progress().reason
    plant = record.built.diagram.GetSubsystemByName("station").GetSubsystemByName("plant")
    states = record.logs["sim.plant_state"]
    foot = foot_positions_W(plant, states.data, [states.data.shape[1] - 1])[0, FR]
    # The robot starts standing square at the origin facing +x: the stance frame of its other three
    # feet is the world frame, within the millimetres they settle by.
    assert np.linalg.norm(foot[:2] - FOOTHOLD_B) < 0.015, (foot, FOOTHOLD_B)
    assert foot[2] < robot.FOOT_RADIUS + 0.005


def test_the_stance_frame_of_three_feet_is_the_pose_that_put_them_under_their_hips():
    # Hand-worked: feet placed square by a known pose, then one moved; the other three give the pose.
    pose = PlanarPose(0.3, -0.2, 0.4)
    feet = np.array([pose.to_world(p) for p in NOMINAL_FEET_B])
    found = stance_pose(feet[1:], [1, 2, 3])
    assert (found.x, found.y, found.yaw) == pytest.approx((0.3, -0.2, 0.4), abs=1e-12)
    # Feet 1 cm off their places either way along x: the least-squares pose is the middle one.
    shifted = feet[1:] + np.array([[0.01, 0.0], [-0.01, 0.0], [0.0, 0.0]])
    assert stance_pose(shifted, [1, 2, 3]).xy == pytest.approx(pose.xy, abs=0.01)


def test_a_trunk_frame_foothold_beyond_reach_is_refused_on_load(tmp_path):
    far = NOMINAL_FEET_B[FR] + np.array([0.25, 0.0])
    with pytest.raises(MissionFileError, match=r"mission.yaml: phases\[1\]\.foothold: .* beyond the leg's reach"):
        load_mission(str(_mission(tmp_path, far)))


def test_a_world_foothold_beyond_reach_fails_the_phase_with_the_reason(tmp_path):
    record = _run(_mission(tmp_path, [0.60, -0.13], frame="world"))
    assert record.mission_progress().status == "failed"
    assert "beyond the leg's reach for a foothold" in record.mission_progress().reason, record.mission_progress().reason
