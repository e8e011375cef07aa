"""The semi-autonomous mode in simulation: a scripted operator on an in-process LCM bus sends a
foot target outside the workspace (refused), a good one (served: optimal posture, lift, reach,
hold, return) and, while it is served, another (refused: busy); the mission then finishes.

The robot moves only through go1.command; the mission reads the estimate and the operator input;
the true foot (the logged plant state) is read only here, to judge. Run with -s to see the numbers.
"""

from pathlib import Path

import numpy as np
import pytest
from pydrake.lcm import DrakeLcm
from pydrake.systems.analysis import Simulator
from pydrake.systems.framework import DiagramBuilder

from pedi_drake.diagram import MakePedipulationDiagram
from pedi_drake.operator.command import FRAME_WORLD, KIND_POSITION, MODE_SEMI_AUTONOMOUS
from pedi_drake.operator.scripted_operator import ScriptedOperator, ScriptStep
from pedi_drake.scenario import load_scenario

MISSION = Path(__file__).parent / "fixtures" / "semi_autonomous.yaml"
# World targets [m]: the trunk stands at the origin, 0.28 m up; the box of the mission's block
# reaches 0.5 m forward of it, so 1.0 m is out.
OUT_OF_WORKSPACE = (1.0, -0.13, 0.20)
GOOD_TARGET = (0.40, -0.13, 0.20)
WHILE_BUSY = (0.38, -0.15, 0.18)
BAD_AT, GOOD_AT, BUSY_AT, END = 0.05, 0.15, 3.0, 12.5  # [s] diagram time
REACH_TOLERANCE = 0.005  # [m] the floor: every target reached within 5 mm


def _target(t: float, p) -> ScriptStep:
    return ScriptStep(t, tuple(p), mode_request=MODE_SEMI_AUTONOMOUS, frame=FRAME_WORLD, kind=KIND_POSITION)


@pytest.fixture(scope="module")
def served_run():
    lcm = DrakeLcm("memq://")
    scenario = load_scenario(
        scenario_text=(
            f"{{mission: {MISSION}, simulation_duration: {END}, robot: {{initial_pose: standing}}, "
            "operator: {source: lcm}}"
        )
    )
    built = MakePedipulationDiagram(scenario, operator_lcm=lcm)
    builder = DiagramBuilder()
    diagram = builder.AddSystem(built.diagram)
    script = [_target(BAD_AT, OUT_OF_WORKSPACE), _target(GOOD_AT, GOOD_TARGET), _target(BUSY_AT, WHILE_BUSY)]
    builder.AddSystem(ScriptedOperator(lcm, script))
    simulator = Simulator(builder.Build())
    simulator.Initialize()
    simulator.AdvanceTo(END)
    root = simulator.get_context()
    manager = diagram.GetSubsystemByName("mission")
    progress = manager.progress(manager.GetMyContextFromRoot(root))
    plant = diagram.GetSubsystemByName("station").GetSubsystemByName("plant")
    states = built.logs(root)["sim.plant_state"]
    return progress, plant, states


def _true_foot(plant, states, t: float) -> np.ndarray:
    context = plant.CreateDefaultContext()
    plant.SetPositionsAndVelocities(context, states.data[:, int(np.searchsorted(states.times, t))])
    return plant.GetBodyByName("FR_foot").EvalPoseInWorld(context).translation().copy()


def test_a_target_is_served_with_the_optimal_posture_and_the_mission_resumes(served_run):
    progress, plant, states = served_run
    rows = [(r.name, r.status) for r in progress.records]
    reach = next(r for r in progress.records if r.name == "semi_1_reach")
    lift = next(r for r in progress.records if r.name == "semi_1_lift")
    error = float(np.linalg.norm(_true_foot(plant, states, reach.t_end) - np.array(GOOD_TARGET)))
    posture = lift.metrics["posture"]
    print(f"\nphases {rows}\nswitches {[(s.from_mode, s.to_mode, s.reason, s.phase) for s in progress.switches]}")
    print(
        f"true FR error at the target {1000 * error:.2f} mm; SUF fixed {posture['fixed']['suf_n']:.2f} N, "
        f"optimal {posture['optimal']['suf_n']:.2f} N"
    )
    assert progress.status == "succeeded"
    assert rows == [
        ("lower", "succeeded"),
        ("semi_1_lift", "succeeded"),
        ("semi_1_reach", "succeeded"),
        ("semi_1_return", "succeeded"),
        ("raise", "succeeded"),
    ]
    assert [(s.from_mode, s.to_mode) for s in progress.switches] == [
        ("autonomous", "semi_autonomous"),
        ("semi_autonomous", "autonomous"),
    ]
    assert error < REACH_TOLERANCE
    assert posture["optimal"]["feasible"]
    assert posture["optimal"]["suf_n"] > posture["fixed"]["suf_n"]


def test_bad_and_busy_targets_are_refused_counted_and_never_followed(served_run):
    progress, _, _ = served_run
    requests = [(r.target_W, r.accepted, r.reason.split(":")[0]) for r in progress.target_requests]
    print(f"\nrequests {requests}")
    assert requests == [
        (OUT_OF_WORKSPACE, False, "outside the workspace"),
        (GOOD_TARGET, True, ""),
        (WHILE_BUSY, False, "busy"),
    ]
    # Only the good target was ever given to a phase.
    targets = [r.metrics.get("target_W") for r in progress.records if r.kind == "reach"]
    assert targets == [list(GOOD_TARGET)]
