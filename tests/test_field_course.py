"""Paper 002's field course (missions/terrain/field_course.yaml): its layout keeps the way out off
the slippery bridge and the box's slide, and two of its stages, short (the prong strike and the
bridge: missions/quick/field_course_push_and_bridge.yaml), judged by physics. The whole course over
six seeds is the benchmark's (python -m pedi_drake.benchmarks.field_course)."""

import numpy as np

from pedi_drake.evaluation import judge
from pedi_drake.mission.spec import Walk, load_mission
from pedi_drake.run import simulate
from pedi_drake.scenario import load_scenario
from pedi_drake.terrain import surface_at

GROUND_FRICTION = 0.8
HALF_WIDTH = 0.3  # [m] the robot's feet and prongs, and a margin, either side of its path
HALF_LENGTH = 0.27  # [m] ahead of and behind its trunk origin: the feet, 6 cm of foothold error


def _footprint_frictions(scene, start, goal) -> set[float]:
    """The friction coefficients under the robot's footprint on its straight way from `start` to
    `goal` (x, y) [m], sampled every 5 cm."""
    found = set()
    for s in np.linspace(0.0, 1.0, 1 + int(np.linalg.norm(np.subtract(goal, start)) / 0.05)):
        x, y = np.add(start, s * np.subtract(goal, start))
        for dx in np.linspace(-HALF_LENGTH, HALF_LENGTH, 8):
            for dy in np.linspace(-HALF_WIDTH, HALF_WIDTH, 7):
                found.add(surface_at(scene, GROUND_FRICTION, x + dx, y + dy).friction)
    return found


def test_the_way_out_keeps_off_the_bridge_and_the_box_slides_clear_of_the_lane():
    course = load_mission("terrain/field_course")
    walks = {phase.name: phase for phase in course.phases if isinstance(phase, Walk)}
    way_out = [(0.0, 0.0)] + [tuple(walks[name].position) for name in ("trot_to_box", "to_the_slope", "climb")]
    for start, goal in zip(way_out, way_out[1:], strict=False):
        assert _footprint_frictions(course.scene, start, goal) == {GROUND_FRICTION}, (start, goal)
    way_back = [tuple(walks[name].position) for name in ("descend", "cross_the_bridge")]
    assert 0.2 in _footprint_frictions(course.scene, *way_back)
    # The box, struck along x, slides in its own lane: the robot's lane at y = -0.9 m is clear of it.
    (box,) = [obj for obj in course.scene if obj.instance_name == "wide_box"]
    assert box.position[1] - 0.22 > walks["to_the_slope"].position[1] + HALF_WIDTH


def test_the_prong_strike_and_the_bridge_of_the_field_course():
    scenario = load_scenario(
        scenario_text="{mission: quick/field_course_push_and_bridge, simulation_duration: 70.0, "
        "robot: {initial_pose: standing}}"
    )
    result = judge.judge_run(simulate(scenario=scenario, name="field_course_stages", quiet=True, replay=False))
    assert result["success"], result["reason"]
    assert not result["fell"]
    assert result["object_push"]["moved_m"] >= 0.20
    bridge = next(row for row in result["walks"] if row["phase"] == "cross_the_bridge")
    assert max(bridge["max_stance_slip_m"].values()) <= 0.01
