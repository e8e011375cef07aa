"""Mode switching in simulation: a scripted operator on an in-process LCM bus takes the FR foot
during an autonomous mission, moves it, and gives it back; the mission then finishes.

The robot moves only through go1.command; the mission reads the estimate and the operator input;
the true foot and trunk (the logged plant state) are read only here, to judge. Run with -s to see
the measured numbers.
"""

from pathlib import Path

import numpy as np
import pytest
from pydrake.lcm import DrakeLcm
from pydrake.systems.analysis import Simulator
from pydrake.systems.framework import DiagramBuilder

from pedi_drake.diagram import MakePedipulationDiagram
from pedi_drake.evaluation.reference_steps import (
    MAX_BODY_STEP,
    MAX_FOOT_STEP_AT_MODE_CHANGE,
    MAX_FOOT_STEP_SAME_MODE,
    reference_steps,
)
from pedi_drake.operator.command import MODE_AUTONOMOUS, MODE_TELEOP
from pedi_drake.operator.scripted_operator import ScriptedOperator, ScriptStep
from pedi_drake.scenario import load_scenario

MISSION = Path(__file__).parent / "fixtures" / "mode_switch.yaml"
SPEED = 0.05  # [m/s]
# The teleop request comes during the first trunk move (it waits for the phase boundary); the
# lift is done by about 2.5 s; the foot moves 2 cm forward, then the operator gives it back.
ASK_TELEOP, MOVE_START, MOVE_END, ASK_AUTONOMOUS, END = 0.1, 3.0, 3.4, 3.6, 6.8  # [s] diagram time
# The mission manager's first update after the start [s] (its period).
FIRST_MISSION_UPDATE = 0.01
TRUNK_MIN_HEIGHT = 0.2  # [m] the true trunk stays at least this high (standing at 0.28 m)


def run_with_operator(script: list[ScriptStep], end: float):
    """(progress, logs) of the fixture mission with `script` published on memq, run to `end` [s]."""
    lcm = DrakeLcm("memq://")
    scenario = load_scenario(
        scenario_text=(
            f"{{mission: {MISSION}, simulation_duration: {end}, robot: {{initial_pose: standing}}, "
            "operator: {source: lcm}}"
        )
    )
    built = MakePedipulationDiagram(scenario, operator_lcm=lcm)
    builder = DiagramBuilder()
    diagram = builder.AddSystem(built.diagram)
    builder.AddSystem(ScriptedOperator(lcm, script))
    simulator = Simulator(builder.Build())
    simulator.Initialize()
    simulator.AdvanceTo(end)
    root = simulator.get_context()
    manager = diagram.GetSubsystemByName("mission")
    progress = manager.progress(manager.GetMyContextFromRoot(root))
    every = built.logs(root)
    logs = {
        name: (every[name].times, every[name].data)
        for name in ("mission.body_reference", "mission.leg_reference", "sim.plant_state")
    }
    plant = diagram.GetSubsystemByName("station").GetSubsystemByName("plant")
    return progress, logs, plant


def steps_of(logs) -> dict:
    """Largest tick-to-tick steps of the references (pedi_drake.evaluation.reference_steps)."""
    times, body = logs["mission.body_reference"]
    return reference_steps(times, body, logs["mission.leg_reference"][1], FIRST_MISSION_UPDATE)


def true_foot_at(logs, plant, t: float, leg: str) -> np.ndarray:
    times, states = logs["sim.plant_state"]
    context = plant.CreateDefaultContext()
    plant.SetPositionsAndVelocities(context, states[:, int(np.searchsorted(times, t))])
    return plant.GetBodyByName(f"{leg}_foot").EvalPoseInWorld(context).translation().copy()


def true_trunk_heights(logs, plant) -> np.ndarray:
    _, states = logs["sim.plant_state"]
    context = plant.CreateDefaultContext()
    trunk = plant.GetBodyByName("trunk")
    heights = []
    for x in states[:, ::25].T:
        plant.SetPositionsAndVelocities(context, x)
        heights.append(trunk.EvalPoseInWorld(context).translation()[2])
    return np.array(heights)


@pytest.fixture(scope="module")
def switched_run():
    script = [
        ScriptStep(ASK_TELEOP, mode_request=MODE_TELEOP),
        ScriptStep(MOVE_START, (SPEED, 0.0, 0.0)),
        ScriptStep(MOVE_END, (0.0, 0.0, 0.0)),
        ScriptStep(ASK_AUTONOMOUS, mode_request=MODE_AUTONOMOUS),
    ]
    return run_with_operator(script, END)


def test_the_operator_takes_the_foot_and_the_mission_then_succeeds(switched_run):
    progress, logs, plant = switched_run
    rows = [(r.name, r.status) for r in progress.records]
    switches = [(s.from_mode, s.to_mode, s.reason, s.phase) for s in progress.switches]
    teleop = next(r for r in progress.records if r.kind == "teleop_foot")
    moved = true_foot_at(logs, plant, teleop.t_end, "FR") - true_foot_at(logs, plant, teleop.t_start, "FR")
    heights = true_trunk_heights(logs, plant)
    print(f"\nphases {rows}\nswitches {switches}\ntrue FR foot moved in teleop {np.round(1000 * moved, 1)} mm")
    print(f"reference steps {steps_of(logs)}; lowest true trunk {heights.min():.3f} m")
    assert progress.status == "succeeded"
    assert rows == [
        ("lower", "succeeded"),
        ("teleop_1_lift", "succeeded"),
        ("teleop_1", "succeeded"),
        ("teleop_1_place", "succeeded"),
        ("raise", "succeeded"),
    ]
    assert switches == [
        ("autonomous", "teleop", "operator request (phase boundary)", "raise"),
        ("teleop", "autonomous", "operator request", "raise"),
    ]
    commanded = np.array([SPEED * (MOVE_END - MOVE_START), 0.0, 0.0])
    assert np.linalg.norm(moved - commanded) < 0.005
    assert heights.min() > TRUNK_MIN_HEIGHT


def test_the_switches_never_step_the_references(switched_run):
    _, logs, _ = switched_run
    steps = steps_of(logs)
    assert steps["body"] < MAX_BODY_STEP
    assert steps["same"] < MAX_FOOT_STEP_SAME_MODE
    assert steps["change"] < MAX_FOOT_STEP_AT_MODE_CHANGE


# A seed of its own, printed: a failure names the switch times that caused it.
RANDOM_SWITCH_SEED = 17017


@pytest.fixture(scope="module")
def randomly_switched_run():
    rng = np.random.default_rng(RANDOM_SWITCH_SEED)
    ask_teleop = float(rng.uniform(0.0, 0.8))  # during either trunk move or at its boundary
    ask_autonomous = ask_teleop + float(rng.uniform(0.2, 3.5))  # during the lift or the teleop
    script = [
        ScriptStep(ask_teleop, mode_request=MODE_TELEOP),
        ScriptStep(ask_autonomous, mode_request=MODE_AUTONOMOUS),
    ]
    progress, logs, plant = run_with_operator(script, 7.5)
    return (ask_teleop, ask_autonomous), progress, logs, plant


def test_a_switch_at_a_random_time_never_steps_the_references(randomly_switched_run):
    times, progress, logs, plant = randomly_switched_run
    steps = steps_of(logs)
    print(
        f"\nteleop asked at {times[0]:.3f} s, autonomous at {times[1]:.3f} s: switches "
        f"{[(round(s.time, 3), s.from_mode, s.to_mode, s.reason) for s in progress.switches]}; "
        f"phases {[(r.name, r.status) for r in progress.records]}; steps {steps}"
    )
    assert len(progress.switches) == 2
    assert steps["body"] < MAX_BODY_STEP
    assert steps["same"] < MAX_FOOT_STEP_SAME_MODE
    assert steps["change"] < MAX_FOOT_STEP_AT_MODE_CHANGE
    assert true_trunk_heights(logs, plant).min() > TRUNK_MIN_HEIGHT
    assert progress.status == "succeeded"
    assert all(r.status == "succeeded" for r in progress.records)
