"""The simulated Go1 station: MultibodyPlant + SceneGraph + motor model + sensors.

Exports exactly the station ports of docs/conventions.md (`go1.*`), plus simulation-only
ports (`sim.*`) for logging and tests, which controllers and estimators never read. The
scenario's `model_error` (pedi_drake.station.model_error) makes this plant and its motors differ
from the Go1 the controllers model.
"""

import numpy as np
from pydrake.geometry import Meshcat, MeshcatVisualizer, MeshcatVisualizerParams, Role
from pydrake.multibody.plant import AddMultibodyPlant
from pydrake.systems.framework import Diagram, DiagramBuilder
from pydrake.systems.primitives import ConstantVectorSource, Demultiplexer

from pedi_drake import robot
from pedi_drake.scenario import Scenario
from pedi_drake.station.disturbance import PUSH_FORCE_SIZE, PushDisturbance
from pedi_drake.station.initial_state import initial_trunk_pose, set_default_go1_state
from pedi_drake.station.model_error import apply_plant_error
from pedi_drake.station.motor_model import Go1MotorModel
from pedi_drake.station.plant_readings import PlantReadings
from pedi_drake.station.scene import add_ground, add_scene_object
from pedi_drake.station.sensors import JointEncoders

GO1_OUTPUT_PORTS = (
    "go1.position_measured",
    "go1.velocity_measured",
    "go1.torque_estimated",
    "go1.imu",
    "go1.foot_contact",
)
SIM_OUTPUT_PORTS = (
    "sim.foot_contact_forces",
    "sim.scene_contact_forces",
    "sim.plant_state",
    "sim.contact_results",
    "sim.body_poses",
    "sim.motor_torque",
    "sim.push_force",
    "sim.query_object",
)


def MakeSimulationStation(scenario: Scenario, meshcat: Meshcat | None = None) -> Diagram:
    """Builds the simulated station for `scenario`; its subsystem "plant" is the MultibodyPlant."""
    builder = DiagramBuilder()
    plant, scene_graph = AddMultibodyPlant(scenario.plant_config, builder)
    model = robot.add_go1(plant, prongs=scenario.robot.prongs)
    # The reality gap: this plant and its motors only, never the controllers' model.
    error = scenario.model_error
    apply_plant_error(plant, scene_graph, model, error)
    add_ground(plant, scenario.ground_friction)
    X_WB0 = initial_trunk_pose(scenario.robot, error.foot_radius)
    for obj in scenario.scene:
        add_scene_object(plant, obj, X_WB0, scenario.ground_friction)
    plant.Finalize()
    plant_map = robot.Go1PlantMap.from_plant(plant, model)
    set_default_go1_state(plant, plant_map, scenario.robot, error.foot_radius)

    motors = builder.AddNamedSystem(
        "motors",
        Go1MotorModel(
            plant_map,
            plant.num_positions(),
            plant.num_velocities(),
            plant.num_actuators(),
            error=error,
            time_step=plant.time_step(),
        ),
    )
    builder.Connect(plant.get_state_output_port(), motors.GetInputPort("plant_state"))
    builder.Connect(motors.GetOutputPort("actuation"), plant.get_actuation_input_port())
    builder.ExportInput(motors.GetInputPort("command"), "go1.command")

    encoders = builder.AddNamedSystem(
        "encoders",
        JointEncoders(
            plant_map,
            plant.num_positions(),
            plant.num_velocities(),
            scenario.sensor_noise,
            scenario.random_seed,
            plant.time_step(),
        ),
    )
    builder.Connect(plant.get_state_output_port(), encoders.GetInputPort("plant_state"))
    outputs = {name: encoders.GetOutputPort(name.removeprefix("go1.")) for name in GO1_OUTPUT_PORTS[:2]}

    # The IMU, foot sensors, torque estimate and contact ground truth: one callback, split in C++.
    scene_names = [obj.instance_name for obj in scenario.scene]
    readings = builder.AddNamedSystem(
        "readings",
        PlantReadings(plant, plant_map, scene_names, scenario.sensor_noise, scenario.random_seed, plant.time_step()),
    )
    builder.Connect(plant.get_state_output_port(), readings.GetInputPort("plant_state"))
    builder.Connect(plant.get_generalized_acceleration_output_port(), readings.GetInputPort("generalized_acceleration"))
    builder.Connect(plant.get_contact_results_output_port(), readings.GetInputPort("contact_results"))
    builder.Connect(motors.GetOutputPort("torque"), readings.GetInputPort("motor_torque"))
    sizes = {name: size for name, size in readings.sizes.items() if size > 0}
    split = builder.AddNamedSystem("readings.split", Demultiplexer(list(sizes.values())))
    builder.Connect(readings.get_output_port(), split.get_input_port())
    outputs.update({name: split.get_output_port(k) for k, name in enumerate(sizes)})
    for name in readings.sizes.keys() - sizes.keys():
        # No scene objects: an empty ground truth of robot-object contact.
        outputs[name] = builder.AddNamedSystem(f"readings.{name}", ConstantVectorSource(np.zeros(0))).get_output_port()

    # The world's disturbances: the plant's applied forces come from the scenario only.
    if scenario.pushes:
        pushes = builder.AddNamedSystem("pushes", PushDisturbance(plant, scenario.pushes))
        builder.Connect(pushes.forces_port, plant.get_applied_spatial_force_input_port())
        push_force = pushes.push_force_port
    else:
        # Nothing to apply, and zero force to log, without a Python callback every plant step.
        push_force = builder.AddNamedSystem("pushes", ConstantVectorSource(np.zeros(PUSH_FORCE_SIZE))).get_output_port()

    outputs.update(
        {
            "sim.plant_state": plant.get_state_output_port(),
            "sim.contact_results": plant.get_contact_results_output_port(),
            "sim.body_poses": plant.get_body_poses_output_port(),
            "sim.motor_torque": motors.GetOutputPort("torque"),
            "sim.push_force": push_force,
            "sim.query_object": scene_graph.get_query_output_port(),
        }
    )
    for name in (*GO1_OUTPUT_PORTS, *SIM_OUTPUT_PORTS):
        builder.ExportOutput(outputs[name], name)

    if meshcat is not None:
        params = MeshcatVisualizerParams(publish_period=scenario.visualization_period, role=Role.kIllustration)
        MeshcatVisualizer.AddToBuilder(builder, scene_graph, meshcat, params)
    diagram = builder.Build()
    diagram.set_name("go1_station")
    return diagram
