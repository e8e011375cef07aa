"""A short teleoperation in simulation: a scripted operator on an in-process LCM bus moves the
lifted FR foot 2 cm forward and 2 cm up; the true foot (the plant, read only here) follows.

The robot moves only through go1.command; the mission reads the estimate and the operator input.
Run with -s to see the measured tracking error and displacement.
"""

from pathlib import Path

import numpy as np
import pytest
from pydrake.lcm import DrakeLcm
from pydrake.systems.analysis import Simulator
from pydrake.systems.framework import DiagramBuilder

from pedi_drake.control.references import parse_leg_reference
from pedi_drake.diagram import MakePedipulationDiagram
from pedi_drake.operator.command import MODE_TELEOP
from pedi_drake.operator.scripted_operator import ScriptedOperator, ScriptStep
from pedi_drake.scenario import load_scenario

MISSION = Path(__file__).parent / "fixtures" / "teleop_short.yaml"
SPEED = 0.05  # [m/s]
MOVE_START, MOVE_UP, MOVE_END, END = 2.4, 2.8, 3.2, 3.4  # [s] diagram time
# Floor: the true foot within 1 cm of its reference while moving, and the commanded moves done within 5 mm.
MAX_TRACKING_ERROR = 0.01  # [m]
MAX_DISPLACEMENT_ERROR = 0.005  # [m]


@pytest.fixture(scope="module")
def teleop_run():
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
    script = [
        ScriptStep(0.0, mode_request=MODE_TELEOP),
        ScriptStep(MOVE_START, (SPEED, 0.0, 0.0)),
        ScriptStep(MOVE_UP, (0.0, 0.0, SPEED)),
        ScriptStep(MOVE_END, (0.0, 0.0, 0.0)),
    ]
    builder.AddSystem(ScriptedOperator(lcm, script))
    simulator = Simulator(builder.Build())
    simulator.Initialize()
    station = diagram.GetSubsystemByName("station")
    plant = station.GetSubsystemByName("plant")
    manager = diagram.GetSubsystemByName("mission")
    foot = plant.GetBodyByName("FR_foot")
    samples = []  # (t, true foot, reference foot) [s, m, m]
    for t in np.arange(MOVE_START - 0.2, END + 1e-9, 0.02):
        simulator.AdvanceTo(t)
        root = simulator.get_context()
        p_true = plant.EvalBodyPoseInWorld(plant.GetMyContextFromRoot(root), foot).translation().copy()
        reference = parse_leg_reference(manager.GetOutputPort("leg_reference").Eval(manager.GetMyContextFromRoot(root)))
        samples.append((t, p_true, reference[0]))
    progress = manager.progress(manager.GetMyContextFromRoot(simulator.get_context()))
    return samples, progress


def test_the_teleop_phase_runs_and_the_robot_stays_up(teleop_run):
    samples, progress = teleop_run
    assert progress.records[-1].kind == "teleop_foot" and progress.records[-1].status == "running"
    assert all(reference.mode == 1 for _, _, reference in samples)  # a foot reference throughout


def test_the_true_foot_follows_the_operator(teleop_run):
    samples, progress = teleop_run
    errors = [np.linalg.norm(p_true - reference.position) for _, p_true, reference in samples]
    start = samples[0][1]
    displacement = samples[-1][1] - start
    commanded = SPEED * np.array([MOVE_UP - MOVE_START, 0.0, MOVE_END - MOVE_UP])
    print(
        f"\nteleop: tracking error max {1000 * max(errors):.1f} mm, median {1000 * np.median(errors):.1f} mm; "
        f"true foot moved {np.round(1000 * displacement, 1).tolist()} mm for {np.round(1000 * commanded, 1).tolist()} "
        f"commanded; bounds {progress.records[-1].metrics['bound_activations']}"
    )
    assert max(errors) < MAX_TRACKING_ERROR
    assert np.linalg.norm(displacement - commanded) < MAX_DISPLACEMENT_ERROR
