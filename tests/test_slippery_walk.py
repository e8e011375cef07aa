"""A static walk onto ground of friction 0.2 with the controllers told so first: it slows down
(friction_slowdown) and no loaded foot slides, judged by the simulation's true feet."""

import pytest

from pedi_drake.evaluation import judge
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
MAX_STANCE_SLIP = 0.01  # [m] a loaded foot's slide within one stance


def test_the_walk_slows_so_that_its_accelerations_scale_with_the_friction():
    assert friction_slowdown(NOMINAL_WALK_FRICTION) == 1.0 and friction_slowdown(1.2) == 1.0
    assert friction_slowdown(0.2) == pytest.approx(2.0)
    nominal, slowed = StaticWalkTiming(), StaticWalkTiming().slowed(2.0)
    assert (slowed.swing, slowed.shift, slowed.ramp) == (2 * nominal.swing, 2 * nominal.shift, nominal.ramp)
    # The CoM's sway done in twice the time: a quarter of the acceleration, as mu 0.2 is 0.8 / 4.
    assert (slowed.sway / slowed.shift**2) / (nominal.sway / nominal.shift**2) == pytest.approx(0.2 / 0.8)


def test_a_walk_onto_ice_told_of_it_keeps_its_feet(tmp_path):
    path = tmp_path / "ice.yaml"
    path.write_text(MISSION)
    scenario = load_scenario(
        scenario_text=f"{{mission: {path}, robot: {{initial_pose: standing}}, simulation_duration: 20.0}}"
    )
    record = simulate(scenario=scenario, name="ice", quiet=True, replay=False)
    result = judge.judge_run(record)
    assert result["success"], result["reason"]
    assert not result["fell"]
    (walk,) = result["walks"]
    assert max(walk["max_stance_slip_m"].values()) <= MAX_STANCE_SLIP, walk["max_stance_slip_m"]
    # At half the twist with cycles twice as long: the walk took about twice the nominal time.
    assert walk["walking_speed_m_s"] < 0.15 / 2 + 0.01
