"""The simulated Go1 station: MultibodyPlant + SceneGraph + motor model + sensors.

Exports exactly the station ports of docs/conventions.md (`go1.*`), plus simulation-only
ports (`sim.*`) for logging and tests, which controllers and estimators never read.
"""

from pydrake.geometry import Meshcat, MeshcatVisualizer, MeshcatVisualizerParams, Role
from pydrake.multibody.plant import AddMultibodyPlant
from pydrake.systems.framework import Diagram, DiagramBuilder

from pedi_drake import robot
from pedi_drake.scenario import Scenario
from pedi_drake.station.disturbance import PushDisturbance
from pedi_drake.station.initial_state import initial_trunk_pose, set_default_go1_state
from pedi_drake.station.motor_model import Go1MotorModel
from pedi_drake.station.scene import add_ground, add_scene_object
from pedi_drake.station.scene_contact import SceneContactForces
from pedi_drake.station.sensors import FootContactForces, Go1SensorModel

GO1_OUTPUT_PORTS = (
    "go1.position_measured",
    "go1.velocity_measured",
    "go1.torque_estimated",
    "go1.imu",
    "go1.foot_contact",
)


def MakeSimulationStation(scenario: Scenario, meshcat: Meshcat | None = None) -> Diagram:
    """Builds the simulated station for `scenario`; its subsystem "plant" is the MultibodyPlant."""
    builder = DiagramBuilder()
    plant, scene_graph = AddMultibodyPlant(scenario.plant_config, builder)
    model = robot.add_go1(plant, prongs=scenario.robot.prongs)
    add_ground(plant, scenario.ground_friction)
    X_WB0 = initial_trunk_pose(scenario.robot)
    for obj in scenario.scene:
        add_scene_object(plant, obj, X_WB0)
    plant.Finalize()
    plant_map = robot.Go1PlantMap.from_plant(plant, model)
    set_default_go1_state(plant, plant_map, scenario.robot)

    motors = builder.AddNamedSystem(
        "motors", Go1MotorModel(plant_map, plant.num_positions(), plant.num_velocities(), plant.num_actuators())
    )
    builder.Connect(plant.get_state_output_port(), motors.GetInputPort("plant_state"))
    builder.Connect(motors.GetOutputPort("actuation"), plant.get_actuation_input_port())
    builder.ExportInput(motors.GetInputPort("command"), "go1.command")

    sensors = builder.AddNamedSystem(
        "sensors",
        Go1SensorModel(plant, plant_map, scenario.sensor_noise, scenario.random_seed, plant.time_step()),
    )
    builder.Connect(plant.get_state_output_port(), sensors.GetInputPort("plant_state"))
    builder.Connect(plant.get_generalized_acceleration_output_port(), sensors.GetInputPort("generalized_acceleration"))
    builder.Connect(plant.get_contact_results_output_port(), sensors.GetInputPort("contact_results"))
    builder.Connect(motors.GetOutputPort("torque"), sensors.GetInputPort("motor_torque"))
    for name in GO1_OUTPUT_PORTS:
        builder.ExportOutput(sensors.GetOutputPort(name.removeprefix("go1.")), name)

    # The world's disturbances: the plant's applied forces come from the scenario only.
    pushes = builder.AddNamedSystem("pushes", PushDisturbance(plant, scenario.pushes))
    builder.Connect(pushes.forces_port, plant.get_applied_spatial_force_input_port())

    feet = builder.AddNamedSystem("foot_contact_forces", FootContactForces(plant, plant_map))
    builder.Connect(plant.get_contact_results_output_port(), feet.GetInputPort("contact_results"))
    builder.ExportOutput(feet.GetOutputPort("foot_contact_forces"), "sim.foot_contact_forces")
    scene_names = [obj.instance_name for obj in scenario.scene]
    touches = builder.AddNamedSystem("scene_contact_forces", SceneContactForces(plant, plant_map, scene_names))
    builder.Connect(plant.get_contact_results_output_port(), touches.GetInputPort("contact_results"))
    builder.ExportOutput(touches.GetOutputPort("scene_contact_forces"), "sim.scene_contact_forces")
    builder.ExportOutput(plant.get_state_output_port(), "sim.plant_state")
    builder.ExportOutput(plant.get_contact_results_output_port(), "sim.contact_results")
    builder.ExportOutput(plant.get_body_poses_output_port(), "sim.body_poses")
    builder.ExportOutput(motors.GetOutputPort("torque"), "sim.motor_torque")
    builder.ExportOutput(pushes.push_force_port, "sim.push_force")
    builder.ExportOutput(scene_graph.get_query_output_port(), "sim.query_object")

    if meshcat is not None:
        params = MeshcatVisualizerParams(publish_period=scenario.visualization_period, role=Role.kIllustration)
        MeshcatVisualizer.AddToBuilder(builder, scene_graph, meshcat, params)
    diagram = builder.Build()
    diagram.set_name("go1_station")
    return diagram
