"""Every scene object loads, rests on what it should, and moves (or not) as described."""

import numpy as np
import pytest
from pydrake.systems.analysis import Simulator

from pedi_drake import robot
from pedi_drake.go1_command import pack_command
from pedi_drake.scenario import Push, Scenario, SceneObject
from pedi_drake.station.scene import (
    ESTOP_BUTTON_JOINT,
    ESTOP_BUTTON_PRELOAD,
    ESTOP_BUTTON_STIFFNESS,
    ESTOP_BUTTON_TRIP_TRAVEL,
)
from pedi_drake.station_interface import MakeStation


def _simulate(obj: SceneObject, body_name: str, force_W, duration: float, p_BoBq_B=(0.0, 0.0, 0.0)):
    """Holds the Go1 lying, pushes `body_name` with `force_W` [N] at p_BoBq_B, returns (plant, contexts)."""
    force = float(np.linalg.norm(force_W))
    pushes = []
    if force > 0:
        direction = (np.asarray(force_W, float) / force).tolist()
        pushes = [Push(force=force, body=body_name, point=list(p_BoBq_B), direction=direction, duration=duration)]
    scenario = Scenario(scene=[obj], pushes=pushes)
    station = MakeStation(scenario)
    plant = station.GetSubsystemByName("plant")
    context = station.CreateDefaultContext()
    plant_context = plant.GetMyContextFromRoot(context)
    model = plant.GetModelInstanceByName(obj.instance_name)
    body = plant.GetBodyByName(body_name, model)
    start = body.EvalPoseInWorld(plant_context)
    station.GetInputPort("go1.command").FixValue(context, pack_command(robot.LYING_Q, 0, 40, 1, 0))
    Simulator(station, context).AdvanceTo(duration)
    return plant, plant_context, model, start, body.EvalPoseInWorld(plant_context)


@pytest.mark.parametrize("kind,body", [("box", "box"), ("target_panel", "panel")])
def test_free_objects_rest_on_the_floor(kind, body):
    _, _, _, start, end = _simulate(SceneObject(kind=kind, position=[0.6, 0.4, 0.0]), body, [0, 0, 0], 0.5)
    np.testing.assert_allclose(end.translation(), start.translation(), atol=0.002)
    # Still upright: its z axis within 2 degrees of the world's.
    assert end.rotation().matrix()[2, 2] > np.cos(np.radians(2))


def _pose_on_trunk(plant, context, pose_W):
    X_WB = plant.GetBodyByName(robot.TRUNK_BODY_NAME).EvalPoseInWorld(context)
    return X_WB.inverse() @ pose_W


@pytest.mark.parametrize("drop_height", [0.0, 0.05])
def test_back_object_rests_on_the_trunk(drop_height):
    obj = SceneObject(kind="back_object", position=[0.02, 0.0, drop_height])
    plant, context, _, _, end = _simulate(obj, "object", [0, 0, 0], 0.6)
    X_BO = _pose_on_trunk(plant, context, end)
    # Its bottom face lies on the trunk's top face (0.057 m above the trunk origin).
    np.testing.assert_allclose(X_BO.translation(), [0.02, 0.0, 0.057], atol=0.003)


def test_door_swings_open_when_pushed():
    obj = SceneObject(kind="door", position=[0.8, 0.4, 0.0], initial_angle=0.5)
    plant, context, model, _, _ = _simulate(obj, "leaf", [6.0, 0.0, 0.0], 1.0, p_BoBq_B=(0.0, -0.6, 0.3))
    angle = plant.GetJointByName("hinge", model).get_angle(context)
    assert angle > 0.5 + np.radians(20)


def test_door_stays_put_without_a_push():
    obj = SceneObject(kind="door", position=[0.8, 0.4, 0.0], initial_angle=0.5)
    plant, context, model, _, _ = _simulate(obj, "leaf", [0.0, 0.0, 0.0], 0.5)
    assert plant.GetJointByName("hinge", model).get_angle(context) == pytest.approx(0.5, abs=0.01)


def test_box_slides_when_pushed():
    # 3 N at mid-height beats the ~2.1 N of friction on the 0.5 kg box.
    obj = SceneObject(kind="box", position=[0.6, 0.4, 0.0])
    _, _, _, start, end = _simulate(obj, "box", [3.0, 0, 0], 0.5, p_BoBq_B=(0, 0, 0.075))
    assert end.translation()[0] - start.translation()[0] > 0.05
    # It slides on the floor rather than tumbling.
    assert abs(end.translation()[2] - start.translation()[2]) < 0.01
    roll, pitch, _ = end.rotation().ToRollPitchYaw().vector()
    assert abs(roll) < 0.1 and abs(pitch) < 0.1


def test_box_stays_put_under_a_push_below_friction():
    obj = SceneObject(kind="box", position=[0.6, 0.4, 0.0])
    _, _, _, start, end = _simulate(obj, "box", [1.0, 0, 0], 0.5, p_BoBq_B=(0, 0, 0.075))
    assert abs(end.translation()[0] - start.translation()[0]) < 0.002


def test_soft_obstacle_compresses_under_a_push_and_springs_back():
    obj = SceneObject(kind="soft_obstacle", position=[-0.6, 0.4, 0.0])
    plant, context, model, _, _ = _simulate(obj, "plate", [10.0, 0, 0], 1.0)
    slide = plant.GetJointByName("slide", model)
    # 10 N on a 400 N/m spring: 2.5 cm.
    assert slide.get_translation(context) == pytest.approx(10.0 / 400.0, abs=0.003)


def test_fixed_obstacle_does_not_move_when_pushed():
    obj = SceneObject(kind="fixed_obstacle", position=[-0.6, 0.4, 0.0])
    _, _, _, start, end = _simulate(obj, "block", [50.0, 0, 0], 0.5)
    np.testing.assert_allclose(end.translation(), start.translation(), atol=1e-9)


def _plunger_travel(force_down: float) -> tuple[float, float]:
    """(travel [m], the plunger's own weight [N]) after pushing it down with `force_down` [N]."""
    obj = SceneObject(kind="estop_button", position=[-0.6, 0.4, 0.0])
    plant, context, model, _, _ = _simulate(obj, "plunger", [0.0, 0.0, -force_down], 0.6)
    weight = plant.GetBodyByName("plunger", model).default_mass() * 9.81
    return plant.GetJointByName(ESTOP_BUTTON_JOINT, model).get_translation(context), weight


def test_estop_button_stays_out_under_less_than_its_preload():
    # 1.2 N and the plunger's weight are below the 2 N preload (400 N/m x 5 mm): it stays on its stop.
    assert _plunger_travel(1.2)[0] == pytest.approx(0.0, abs=2e-4)


def test_estop_button_trips_under_a_force_below_the_teleop_bound():
    # 6 N and the plunger's weight against 400 N/m x (travel + 5 mm): about 11 mm, past the 8 mm
    # trip and short of the 12 mm stop.
    travel, weight = _plunger_travel(6.0)
    assert travel == pytest.approx((6.0 + weight) / ESTOP_BUTTON_STIFFNESS - ESTOP_BUTTON_PRELOAD, abs=2e-4)
    assert travel > ESTOP_BUTTON_TRIP_TRAVEL


def test_estop_button_plunger_stops_at_the_end_of_its_travel():
    assert _plunger_travel(40.0)[0] == pytest.approx(0.012, abs=1e-3)
