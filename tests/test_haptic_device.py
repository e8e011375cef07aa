"""The haptic-device adapter (pedi_drake.operator.haptic_device): its rate control, and a simulated
spring device driving the FR foot into a wall, where the fed-back force pushes the hand back."""

import numpy as np
import pytest
from pydrake.lcm import DrakeLcm
from pydrake.systems.analysis import Simulator
from pydrake.systems.framework import DiagramBuilder
from pydrake.systems.primitives import LogVectorOutput

from pedi_drake.diagram import MakePedipulationDiagram
from pedi_drake.operator.config import DEFAULT_FOOT_COMMAND_CHANNEL, DEFAULT_FOOT_FEEDBACK_CHANNEL
from pedi_drake.operator.device_operator import DeviceOperator
from pedi_drake.operator.haptic_device import AdapterConfig, DeviceAdapter, SpringDevice, offset_velocity
from pedi_drake.scenario import load_scenario
from pedi_drake.station.scene_contact import scene_contact_index

PUSH_AT, RELEASE_AT, END = 6.5, 11.0, 12.0  # [s]: the teleop phase runs from about 5.8 s
HAND_PUSH = 0.03  # [m] forward, where the hand wants the handle from PUSH_AT on


def test_the_offset_asks_for_a_velocity_beyond_the_dead_band_up_to_the_speed_bound():
    config = AdapterConfig(velocity_gain=2.0, max_speed=0.1, deadband=0.002)
    np.testing.assert_array_equal(offset_velocity([0.001, 0.0, 0.0], config), np.zeros(3))
    np.testing.assert_allclose(offset_velocity([0.012, 0.0, 0.0], config), [0.02, 0.0, 0.0])
    assert np.linalg.norm(offset_velocity([0.5, 0.5, 0.0], config)) == pytest.approx(0.1)


def test_the_spring_hand_settles_where_its_push_balances_the_rendered_force():
    device = SpringDevice(hand_target=np.array([0.02, 0.0, 0.0]))
    device.render(np.array([-4.0, 0.0, 0.0]))
    for _ in range(300):
        device.step(0.01)
    np.testing.assert_allclose(device.offset, [0.02 - 4.0 / device.hand_stiffness, 0.0, 0.0], atol=1e-6)


@pytest.fixture(scope="module")
def device_run():
    lcm = DrakeLcm("memq://")
    scenario = load_scenario(
        scenario_text=(
            "{mission: operator/teleop_foot_wall, controller: whole_body, simulation_duration: 12.0, "
            "operator: {source: lcm}}"
        )
    )
    built = MakePedipulationDiagram(scenario, operator_lcm=lcm)
    builder = DiagramBuilder()
    diagram = builder.AddSystem(built.diagram)
    device = SpringDevice()
    adapter = DeviceAdapter(device, lcm, DEFAULT_FOOT_COMMAND_CHANNEL, DEFAULT_FOOT_FEEDBACK_CHANNEL)
    targets = [(0.0, (0.0, 0.0, 0.0)), (PUSH_AT, (HAND_PUSH, 0.0, 0.0))]
    # The hand lets go of the button at RELEASE_AT: the autonomous mission again.
    operator = builder.AddSystem(DeviceOperator(adapter, device, targets, button_release=RELEASE_AT))
    handle = LogVectorOutput(operator.GetOutputPort("handle"), builder, 0.01)
    simulator = Simulator(builder.Build())
    simulator.Initialize()
    simulator.AdvanceTo(END)
    manager = diagram.GetSubsystemByName("mission")
    progress = manager.progress(manager.GetMyContextFromRoot(simulator.get_context()))
    logs = built.logs(simulator.get_context())
    wall = [obj.instance_name for obj in built.mission.scene]
    log = handle.FindLog(simulator.get_context())
    return (log.sample_times(), log.data()), progress, logs, wall


def test_the_device_drives_the_foot_to_the_wall_and_feels_it_push_back(device_run):
    (times, handle), progress, logs, scene_names = device_run
    offsets = handle[0]
    rendered = np.linalg.norm(handle[6:9], axis=0)
    contact = logs["sim.scene_contact_forces"]
    wall_force = contact.data[scene_contact_index("wall", "FR", scene_names)]
    free = (times > PUSH_AT + 0.3) & (times < PUSH_AT + 0.5)
    held = (times > RELEASE_AT - 1.0) & (times < RELEASE_AT)
    print(
        f"\nhandle free {1000 * offsets[free].mean():.1f} mm, at the wall {1000 * offsets[held].mean():.1f} mm; "
        f"rendered {rendered[held].mean():.1f} N; true wall force max {wall_force.max():.1f} N"
    )
    # Before the wall the hand pushes the handle nearly where it wants it; at the wall the fed-back
    # force holds the handle back, by the rendered force over the hand's stiffness.
    assert offsets[free].mean() > 0.8 * HAND_PUSH
    assert rendered[held].mean() > 3.0
    assert offsets[held].mean() < HAND_PUSH - 2.0 / SpringDevice().hand_stiffness
    assert wall_force[contact.times < RELEASE_AT].max() > 5.0  # the foot pushed the wall
    teleop = next(record for record in progress.records if record.kind == "teleop_foot")
    assert teleop.metrics["ended_by"] == "operator"
    assert teleop.metrics["max_force_n"] < 15.0 + 2.0
