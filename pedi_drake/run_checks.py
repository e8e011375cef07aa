"""Checks of a whole run's inputs that no single file can make alone, before anything is built.

A scenario and a mission are each validated on load (`Scenario.validate`, `load_mission`); what
only their combination and the command line decide is checked here: the merged scene (unique
names, no object overlapping another or the robot's start pose, model files that parse), the
duration (finite, at least one control tick) and the output folder. Each raises ScenarioError
naming the flag or field and what is allowed, which run_sim.py turns into exit code 2.
"""

import math
import tempfile
from pathlib import Path

from pydrake.geometry import CollisionFilterDeclaration, GeometrySet, Role
from pydrake.multibody.plant import AddMultibodyPlant, MultibodyPlantConfig
from pydrake.systems.framework import DiagramBuilder

from pedi_drake import robot
from pedi_drake.exceptions import ScenarioError
from pedi_drake.scenario import Scenario, scene_problems
from pedi_drake.station.initial_state import initial_trunk_pose, set_default_go1_state
from pedi_drake.station.scene import add_scene_object
from pedi_drake.terrain import is_terrain

# Penetration deeper than this between two start-pose geometries is an overlap [m]; shallower is
# resting contact (the door leaf on its frame, an object set on the floor or on the trunk).
OVERLAP_DEPTH = 0.002


def control_period(scenario: Scenario) -> float:
    """Period of the controller the scenario runs [s]: one tick of it is the shortest run."""
    if scenario.controller == "whole_body":
        return scenario.whole_body.period
    if scenario.controller == "projected_impedance":
        return scenario.projected_impedance.period
    return scenario.stand.period


def check_duration(scenario: Scenario, where: str = "simulation_duration") -> None:
    """The run's duration is finite and covers at least one control tick."""
    duration, period = scenario.simulation_duration, control_period(scenario)
    if not math.isfinite(duration):
        raise ScenarioError(f"{where}: must be a finite number of seconds, got {duration}")
    if not duration >= period:
        raise ScenarioError(
            f"{where}: must be at least one control tick ({period} s for {scenario.controller}), got {duration} s"
        )


def check_scene_geometry(scenario: Scenario, where: str = "scene") -> None:
    """No scene object overlaps another or the robot at its start pose; every model file parses.

    `scenario` is the merged one (the scenario's objects, then the mission's). The check loads the
    same models the station will, into a geometry-only plant, and asks SceneGraph for
    penetrations at the start pose.
    """
    for problem in scene_problems(scenario.scene, None, field=where):
        raise ScenarioError(problem)
    if not scenario.scene:
        return
    builder = DiagramBuilder()
    plant, scene_graph = AddMultibodyPlant(MultibodyPlantConfig(time_step=0.0), builder)
    go1 = robot.add_go1(plant, prongs=scenario.robot.prongs)
    X_WB0 = initial_trunk_pose(scenario.robot)
    objects = {}
    for i, obj in enumerate(scenario.scene):
        try:
            objects[add_scene_object(plant, obj, X_WB0, scenario.ground_friction)] = (
                f"{where}[{i}] ({obj.instance_name})"
            )
        except RuntimeError as error:  # Drake's parser: a model that is not valid SDF/URDF
            raise ScenarioError(f"{where}[{i}].model: cannot be loaded: {error}") from None
    plant.Finalize()
    set_default_go1_state(plant, robot.Go1PlantMap.from_plant(plant, go1), scenario.robot)
    diagram = builder.Build()
    context = diagram.CreateDefaultContext()
    sg_context = scene_graph.GetMyContextFromRoot(context)
    inspector = scene_graph.model_inspector()
    # The plant filters contact between bodies welded together, and every fixed object is welded
    # to the world: for this check every pair counts (pairs within one model are skipped below).
    everything = GeometrySet(list(inspector.GetGeometryIds(GeometrySet(inspector.GetAllFrameIds()), Role.kProximity)))
    scene_graph.collision_filter_manager(sg_context).Apply(CollisionFilterDeclaration().AllowWithin(everything))
    query = scene_graph.get_query_output_port().Eval(sg_context)

    def owner(geometry_id) -> str | None:
        body = plant.GetBodyFromFrameId(inspector.GetFrameId(geometry_id))
        if body is None or body.index() == plant.world_body().index():
            return None  # the ground
        if body.model_instance() == go1:
            return "the robot at its start pose"
        return objects.get(body.model_instance())

    # Terrain may join terrain (a ramp's box runs under the platform it leads onto).
    terrain = {f"{where}[{i}] ({obj.instance_name})" for i, obj in enumerate(scenario.scene) if is_terrain(obj)}
    for pair in query.ComputePointPairPenetration():
        a, b = owner(pair.id_A), owner(pair.id_B)
        if a is None or b is None or a == b or pair.depth < OVERLAP_DEPTH or {a, b} <= terrain:
            continue
        first, second = (a, b) if a.startswith(where) else (b, a)
        raise ScenarioError(
            f"{first}: overlaps {second} by {1000 * pair.depth:.0f} mm; move it (position, yaw) so that "
            "nothing starts inside anything else"
        )


def check_out_dir(out_dir: Path, where: str = "--out") -> None:
    """`out_dir` is a folder that exists and is writable, or can be made in one that is.

    Writability is probed with a temporary file in the nearest existing folder (permission bits
    do not tell the whole story: root, read-only mounts), which is removed at once: a rejected
    --out leaves nothing behind.
    """
    out_dir = Path(out_dir)
    if any(len(part.encode()) > 255 for part in out_dir.parts):
        raise ScenarioError(f"{where}: a folder name in {str(out_dir)[:80]!r}... is longer than 255 bytes")
    existing = out_dir
    while not existing.exists() and existing.parent != existing:
        existing = existing.parent
    if not existing.is_dir():
        raise ScenarioError(f"{where}: {existing} is a file, not a folder; give a folder for the results")
    try:
        with tempfile.TemporaryFile(dir=existing):
            pass
    except OSError as error:
        raise ScenarioError(
            f"{where}: {existing} is not writable ({error.strerror}); give a folder you can write to"
        ) from None
