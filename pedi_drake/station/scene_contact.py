"""Simulation only (`sim.scene_contact_forces`): how hard the robot touches each scene object.

For every scene object, in the order of the scenario's scene, ROBOT_CONTACT_SOURCES values: the
normal contact force [N] between that object's bodies and each foot (FR, FL, RR, RL), then between
it and any other body of the robot (trunk, legs, prongs), summed over their point contacts. Read
from the plant's contact results, the simulation's ground truth, for logging and judging only;
controllers and missions never read it.

The station computes it with the sensors in one callback (`plant_readings.PlantReadings`);
`scene_contact_forces` here is the same sum on the plant's contact results, the reference its
compiled kernel is tested against.
"""

import numpy as np
from pydrake.multibody.plant import ContactResults

from pedi_drake import robot

# The contact sources of each object's block: the four feet, then the rest of the robot.
ROBOT_CONTACT_SOURCES = (*robot.LEG_NAMES, "other")


def scene_contact_index(name: str, source: str, scene_names: list[str]) -> int:
    """Index in `sim.scene_contact_forces` of the force between scene object `name` and `source`
    (a leg name or "other"); `scene_names`: the scene's object names in order."""
    return scene_names.index(name) * len(ROBOT_CONTACT_SOURCES) + ROBOT_CONTACT_SOURCES.index(source)


def scene_contact_forces(
    contact_results: ContactResults, source_of_body: dict[int, int], object_of_body: dict[int, int], num_objects: int
) -> np.ndarray:
    """(num_objects * len(ROBOT_CONTACT_SOURCES),) normal contact forces [N] between robot and objects.

    `source_of_body`: {robot body index: source number}; `object_of_body`: {object body index:
    object number}. A contact between two objects, or between an object and the ground, is not counted.
    """
    forces = np.zeros(num_objects * len(ROBOT_CONTACT_SOURCES))
    for i in range(contact_results.num_point_pair_contacts()):
        info = contact_results.point_pair_contact_info(i)
        a, b = int(info.bodyA_index()), int(info.bodyB_index())
        source, obj = source_of_body.get(a), object_of_body.get(b)
        if source is None or obj is None:
            source, obj = source_of_body.get(b), object_of_body.get(a)
        if source is None or obj is None:
            continue
        normal = abs(float(np.dot(info.contact_force(), info.point_pair().nhat_BA_W)))
        forces[obj * len(ROBOT_CONTACT_SOURCES) + source] += normal
    return forces
