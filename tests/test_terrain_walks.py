"""Static walks on terrain, judged by the simulation's true feet and trunk: onto ground of friction
0.2 with the controllers told so first (it slows down: friction_slowdown), and up a 15-degree
slope (footholds, trunk height and pitch from the ground under the feet; the estimator's height
rows on the terrain)."""

import math

import numpy as np
import pytest

from pedi_drake.evaluation import judge
from pedi_drake.evaluation.mission_results import foot_positions_W
from pedi_drake.locomotion.gait import NOMINAL_WALK_FRICTION, StaticWalkTiming, friction_slowdown
from pedi_drake.run import simulate
from pedi_drake.scenario import load_scenario

# From standing: the front feet walk 0.45 m onto a patch of mu 0.2 that starts 6 cm ahead of them.
MISSION = """
contact_ramp_time: 0.06
scene:
  - {kind: friction_patch, name: ice, position: [0.6, 0.0, 0.0], size: [0.6, 0.8, 0.002], friction: 0.2}
phases:
  - {kind: set_friction, mu: 0.2}
  - {kind: walk, position: [0.45, 0.0], yaw: 0.0, speed: 0.15}
"""
# From standing: up a 15-degree slope whose foot is 6 cm ahead of the front feet, until the front
# feet are 0.44 m up it.
SLOPE_MISSION = """
contact_ramp_time: 0.06
scene:
  - {kind: slope, name: ramp, position: [0.25, 0.0, 0.0], size: [1.2, 1.0], angle: 15}
phases:
  - {kind: walk, position: [0.5, 0.0], yaw: 0.0, speed: 0.15}
"""
MAX_STANCE_SLIP = 0.01  # [m] a loaded foot's slide within one stance


def test_the_walk_slows_so_that_its_accelerations_scale_with_the_friction():
    assert friction_slowdown(NOMINAL_WALK_FRICTION) == 1.0 and friction_slowdown(1.2) == 1.0
    assert friction_slowdown(0.2) == pytest.approx(2.0)
    nominal, slowed = StaticWalkTiming(), StaticWalkTiming().slowed(2.0)
    assert (slowed.swing, slowed.shift, slowed.ramp) == (2 * nominal.swing, 2 * nominal.shift, nominal.ramp)
    # The CoM's sway done in twice the time: a quarter of the acceleration, as mu 0.2 is 0.8 / 4.
    assert (slowed.sway / slowed.shift**2) / (nominal.sway / nominal.shift**2) == pytest.approx(0.2 / 0.8)


def _walked(tmp_path, mission: str, duration: float):
    """(run record, the walk's row of result.json) of `mission` from standing: it succeeded, the
    robot did not fall and no loaded foot slid more than MAX_STANCE_SLIP."""
    path = tmp_path / "mission.yaml"
    path.write_text(mission)
    scenario = load_scenario(
        scenario_text=f"{{mission: {path}, robot: {{initial_pose: standing}}, simulation_duration: {duration}}}"
    )
    record = simulate(scenario=scenario, name="terrain", quiet=True, replay=False)
    result = judge.judge_run(record)
    assert result["success"], result["reason"]
    assert not result["fell"]
    (walk,) = result["walks"]
    assert max(walk["max_stance_slip_m"].values()) <= MAX_STANCE_SLIP, walk["max_stance_slip_m"]
    return record, walk


def test_a_walk_onto_ice_told_of_it_keeps_its_feet(tmp_path):
    _, walk = _walked(tmp_path, MISSION, 20.0)
    # At half the twist with cycles twice as long: the walk took about twice the nominal time.
    assert walk["walking_speed_m_s"] < 0.15 / 2 + 0.01


def test_a_walk_up_a_slope_carries_the_trunk_above_the_ground_pitched_with_it(tmp_path):
    record, walk = _walked(tmp_path, SLOPE_MISSION, 14.0)
    assert walk["estimate_height_error_max_m"] < 0.01
    # At the end: every foot on the slope at its height there, the trunk 0.28 m above their mean
    # height (within 2 cm) and pitched nose up by the slope's 15 degrees (within 3).
    plant = record.built.diagram.GetSubsystemByName("station").GetSubsystemByName("plant")
    states = record.logs["sim.plant_state"].data
    feet = foot_positions_W(plant, states, [states.shape[1] - 1])[0]
    slope = math.tan(math.radians(15))
    ground = np.maximum(feet[:, 0] - 0.25, 0.0) * slope
    np.testing.assert_allclose(feet[:, 2], ground + 0.02 / math.cos(math.radians(15)), atol=0.004)
    quaternion, p_WB = states[0:4, -1], states[4:7, -1]
    assert p_WB[2] == pytest.approx(0.28 + ground.mean(), abs=0.02)
    w, x, y, z = quaternion
    pitch = math.asin(max(-1.0, min(1.0, 2.0 * (w * y - z * x))))
    assert math.degrees(pitch) == pytest.approx(-15.0, abs=3.0)
