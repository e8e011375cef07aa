"""The Meshcat panel source: a page connected over the Meshcat's WebSocket (MeshcatPage, the same
messages a browser sends) moves its sliders and clicks its buttons; the panel's operator_command
carries them like the LCM sources do, drops what the page could not have sent, and ages when the
page goes."""

import math
from pathlib import Path

import numpy as np
import pytest
from pydrake.geometry import Meshcat
from pydrake.systems.analysis import Simulator

from pedi_drake.diagram import MakePedipulationDiagram
from pedi_drake.exceptions import ScenarioError
from pedi_drake.go1_command import split_command
from pedi_drake.operator.command import (
    CONTROLLER_NONE,
    CONTROLLER_PROJECTED_IMPEDANCE,
    CONTROLLER_WHOLE_BODY,
    FRAME_WORLD,
    KIND_TWIST,
    KIND_VELOCITY,
    MODE_AUTONOMOUS,
    MODE_TELEOP,
    OperatorCommand,
)
from pedi_drake.operator.config import MeshcatPanelConfig
from pedi_drake.operator.meshcat_page import MeshcatPage, msgpack_map
from pedi_drake.operator.meshcat_panel import (
    AUTONOMOUS_BUTTON,
    ESTOP_BUTTON,
    PROJECTED_IMPEDANCE_BUTTON,
    SLIDERS,
    STOP_BUTTON,
    TELEOP_BUTTON,
    WALK_SLIDERS,
    WHOLE_BODY_BUTTON,
    MeshcatOperatorPanel,
)
from pedi_drake.scenario import load_scenario

PERIOD = 0.01  # [s]
X, Y, Z = (label for label, _, _ in SLIDERS)


@pytest.fixture(scope="module")
def meshcat():
    return Meshcat()


def _make(meshcat, controller_buttons=False, **config):
    panel = MeshcatOperatorPanel(MeshcatPanelConfig(**config), meshcat, PERIOD, controller_buttons=controller_buttons)
    simulator = Simulator(panel)
    simulator.Initialize()
    return panel, simulator


def _tick(panel, simulator, t: float) -> OperatorCommand:
    simulator.AdvanceTo(t)
    return OperatorCommand.from_vector(panel.get_output_port().Eval(simulator.get_context()))


def test_msgpack_of_a_button_message_is_what_the_page_sends():
    # fixmap of 2, fixstr "type", fixstr "button", fixstr "name", fixstr "E"
    assert msgpack_map({"type": "button", "name": "E"}) == b"\x82\xa4type\xa6button\xa4name\xa1E"


def test_sliders_and_buttons_become_the_operator_command(meshcat):
    panel, simulator = _make(meshcat, frame="world")
    assert math.isinf(_tick(panel, simulator, 0.0).age)  # no page yet: a silent operator
    with MeshcatPage(meshcat) as page:
        page.click(TELEOP_BUTTON)
        page.set_slider(X, 0.05)
        page.set_slider(Z, -0.02)
        command = _tick(panel, simulator, 0.1)
        assert (command.mode_request, command.frame, command.kind) == (MODE_TELEOP, FRAME_WORLD, KIND_VELOCITY)
        np.testing.assert_allclose(command.value, [0.05, 0.0, -0.02])
        # The update at 0.1 s runs with the next step: the last one that saw the page was at 0.09 s.
        assert command.age == pytest.approx(PERIOD) and not command.estop
        assert command.received == 2  # one click, one update that found the sliders moved
        page.click(STOP_BUTTON)
        command = _tick(panel, simulator, 0.2)
        np.testing.assert_array_equal(command.value, np.zeros(3))
        assert meshcat.GetSliderValue(X) == 0.0  # the page shows the stopped foot
        assert command.mode_request == MODE_TELEOP  # a mode request stands
    # The page is gone: the command ages from the last update that saw it.
    assert _tick(panel, simulator, 0.5).age == pytest.approx(0.3, abs=PERIOD + 1e-9)


def test_walking_sliders_give_a_twist_each_within_its_own_bound(meshcat):
    panel, simulator = _make(meshcat, sliders="walk", walk_speeds=[0.2, 0.1, 0.3])
    forward, sideways, yaw_rate = (label for label, _, _ in WALK_SLIDERS)
    with pytest.raises(RuntimeError):
        meshcat.GetSliderValue(X)  # the foot's sliders are not there
    with MeshcatPage(meshcat) as page:
        page.set_slider(forward, 0.15)
        page.set_slider(yaw_rate, -0.25)
        command = _tick(panel, simulator, 0.1)
        assert command.kind == KIND_TWIST
        np.testing.assert_allclose(command.value, [0.15, 0.0, -0.25])
        page.set_slider(sideways, 0.2)  # beyond its 0.1 m/s: dropped, the slider put back
        command = _tick(panel, simulator, 0.2)
        np.testing.assert_allclose(command.value, [0.15, 0.0, -0.25])
        assert command.dropped == 1 and meshcat.GetSliderValue(sideways) == 0.0


def test_both_mode_buttons_in_one_period_ask_for_the_autonomous_mission(meshcat):
    panel, simulator = _make(meshcat)
    with MeshcatPage(meshcat) as page:
        page.click(AUTONOMOUS_BUTTON)
        page.click(TELEOP_BUTTON)
        assert _tick(panel, simulator, 0.05).mode_request == MODE_AUTONOMOUS
        page.click(TELEOP_BUTTON)
        assert _tick(panel, simulator, 0.1).mode_request == MODE_TELEOP


def test_the_controller_buttons_ask_for_a_controller_only_where_the_run_has_both(meshcat):
    panel, simulator = _make(meshcat, controller_buttons=True)
    with MeshcatPage(meshcat) as page:
        assert _tick(panel, simulator, 0.05).controller_request == CONTROLLER_NONE
        page.click(PROJECTED_IMPEDANCE_BUTTON)
        assert _tick(panel, simulator, 0.1).controller_request == CONTROLLER_PROJECTED_IMPEDANCE
        page.click(WHOLE_BODY_BUTTON)
        assert _tick(panel, simulator, 0.2).controller_request == CONTROLLER_WHOLE_BODY
    _make(meshcat)
    assert WHOLE_BODY_BUTTON not in meshcat.GetButtonNames()


def test_the_estop_button_latches(meshcat):
    panel, simulator = _make(meshcat)
    with MeshcatPage(meshcat) as page:
        assert not _tick(panel, simulator, 0.05).estop
        page.click(ESTOP_BUTTON)
        assert _tick(panel, simulator, 0.1).estop
        page.click(TELEOP_BUTTON)
        assert _tick(panel, simulator, 0.2).estop


@pytest.mark.parametrize(("value", "reason"), [(float("nan"), "nonfinite"), (5.0, "out_of_range")])
def test_a_slider_value_the_page_cannot_send_is_dropped_counted_and_undone(meshcat, value, reason):
    panel, simulator = _make(meshcat, max_speed=0.1)
    with MeshcatPage(meshcat) as page:
        page.set_slider(Y, 0.03)
        before = _tick(panel, simulator, 0.05)
        page.set_slider(Y, value)
        after = _tick(panel, simulator, 0.1)
    assert panel.counts(simulator.get_context()) == {"received": 1, "dropped": 1, "rejected": {reason: 1}}
    np.testing.assert_array_equal(after.value, before.value)
    assert meshcat.GetSliderValue(Y) == pytest.approx(0.03)  # put back to the value in force


def test_the_meshcat_source_needs_a_meshcat():
    scenario = load_scenario(scenario_text="{operator: {source: meshcat}}")
    with pytest.raises(ScenarioError, match="meshcat"):
        MakePedipulationDiagram(scenario, None, hardware=True)


@pytest.mark.parametrize(
    ("text", "field"),
    [
        ("{operator: {source: meshcat, meshcat: {max_speed: 0}}}", "operator.meshcat.max_speed"),
        ("{operator: {source: meshcat, meshcat: {step: 0.5}}}", "operator.meshcat.step"),
        ("{operator: {source: meshcat, meshcat: {frame: hip}}}", "operator.meshcat.frame"),
    ],
)
def test_a_bad_panel_value_names_its_field(text, field):
    with pytest.raises(ScenarioError, match=field.replace(".", r"\.")):
        load_scenario(scenario_text=text)


MISSION = Path(__file__).parent / "fixtures" / "teleop_short.yaml"
MOVE_START, MOVE_END, ESTOP, END = 2.4, 2.8, 3.0, 3.1  # [s] diagram time (the lift is done by 2.4 s)
SPEED = 0.05  # [m/s]


@pytest.fixture(scope="module")
def panel_run(meshcat):
    """A short teleoperation from the panel: teleop at once, x slider at SPEED from MOVE_START, the
    stop button at MOVE_END, the E-stop at ESTOP. (true FR foot at MOVE_START and at ESTOP, the
    command at END, the gate's latch, the mission's progress)."""
    scenario = load_scenario(
        scenario_text=(
            f"{{mission: {MISSION}, simulation_duration: {END}, robot: {{initial_pose: standing}}, "
            "operator: {source: meshcat}}"
        )
    )
    built = MakePedipulationDiagram(scenario, meshcat)
    diagram = built.diagram
    simulator = Simulator(diagram)
    plant = diagram.GetSubsystemByName("station").GetSubsystemByName("plant")
    foot = plant.GetBodyByName("FR_foot")

    def true_foot():
        context = plant.GetMyContextFromRoot(simulator.get_context())
        return plant.EvalBodyPoseInWorld(context, foot).translation().copy()

    with MeshcatPage(meshcat) as page:
        page.click(TELEOP_BUTTON)
        simulator.Initialize()
        simulator.AdvanceTo(MOVE_START)
        start = true_foot()
        page.set_slider(X, SPEED)
        simulator.AdvanceTo(MOVE_END)
        page.click(STOP_BUTTON)
        simulator.AdvanceTo(ESTOP)
        stopped = true_foot()
        page.click(ESTOP_BUTTON)
        simulator.AdvanceTo(END)
    root = simulator.get_context()
    gate = diagram.GetSubsystemByName("operator.estop_gate")
    manager = diagram.GetSubsystemByName("mission")
    return {
        "moved": stopped - start,
        "command": diagram.GetOutputPort("go1.command").Eval(root),
        "latched": gate.GetOutputPort("latched").Eval(gate.GetMyContextFromRoot(root))[0],
        "progress": manager.progress(manager.GetMyContextFromRoot(root)),
    }


def test_the_panel_moves_the_true_foot(panel_run):
    moved = panel_run["moved"]
    commanded = np.array([SPEED * (MOVE_END - MOVE_START), 0.0, 0.0])  # trunk x, the trunk faces world x
    print(f"\npanel: true FR foot moved {np.round(1000 * moved, 1).tolist()} mm for {1000 * commanded[0]:.0f} mm")
    assert np.linalg.norm(moved - commanded) < 0.005


def test_the_panel_estop_ends_in_damping(panel_run):
    _, qd_des, kp, kd, tau_ff = split_command(panel_run["command"])
    assert panel_run["latched"] == 1.0
    assert np.all(kp == 0.0) and np.all(kd > 0.0) and np.all(tau_ff == 0.0) and np.all(qd_des == 0.0)
    progress = panel_run["progress"]
    assert progress.status == "failed" and "E-stop" in progress.reason
