"""Where the Meshcat camera starts: on the robot and the objects of its scene.

Meshcat's default camera looks at the world origin from several metres away, so a Go1 is a
speck in the middle of the field. `frame_scene` places the camera so the robot's start pose and
every scene object fit in view, from the front right and above. It goes through
`Meshcat.SetCameraPose`, which Meshcat keeps in its scene state: the live view and the static
HTML replay (`Meshcat.StaticHtml`) both open on it.
"""

import math

import numpy as np
from pydrake.geometry import Meshcat

from pedi_drake.scenario import Scenario

FIELD_OF_VIEW = math.radians(75.0)  # [rad] vertical, Meshcat's default perspective camera
# Direction from the framed centre to the camera: in front of the robot, to its right, above.
VIEW_DIRECTION = np.array([1.0, -1.2, 0.7])
ROBOT_RADIUS = 0.45  # [m] half the Go1's length with its legs and a margin: the least that must fit in view
OBJECT_RADIUS = 0.3  # [m] about half the size of the largest shipped scene object
LOOK_HEIGHT = 0.15  # [m] the view's centre sits this high (a standing trunk is at 0.28 m)


def scene_frame(scenario: Scenario) -> tuple[np.ndarray, float]:
    """(centre [m], radius [m]) of a sphere holding the robot's start pose and every scene object.

    `scenario` is the merged one (the mission's objects included). Objects placed on the trunk
    (`back_object`) are at the robot.
    """
    x, y = scenario.robot.initial_xy
    points, radii = [np.array([x, y, LOOK_HEIGHT])], [ROBOT_RADIUS]
    for obj in scenario.scene:
        if obj.kind == "back_object":
            continue
        points.append(np.array([obj.position[0], obj.position[1], LOOK_HEIGHT]))
        radii.append(OBJECT_RADIUS)
    points = np.array(points)
    low = np.min(points - np.array(radii)[:, None], axis=0)
    high = np.max(points + np.array(radii)[:, None], axis=0)
    centre = 0.5 * (low + high)
    radius = float(max(np.linalg.norm(p - centre) + r for p, r in zip(points, radii, strict=True)))
    centre[2] = LOOK_HEIGHT
    return centre, radius


def camera_pose(scenario: Scenario) -> tuple[np.ndarray, np.ndarray]:
    """(camera position, target) in the world [m] that fit `scene_frame` in the field of view."""
    centre, radius = scene_frame(scenario)
    # The distance at which a sphere of `radius` just fills the vertical field of view.
    distance = radius / math.sin(FIELD_OF_VIEW / 2)
    direction = VIEW_DIRECTION / np.linalg.norm(VIEW_DIRECTION)
    return centre + distance * direction, centre


def frame_scene(meshcat: Meshcat, scenario: Scenario) -> None:
    """Points `meshcat`'s camera at the robot and its scene (see the module docstring)."""
    camera, target = camera_pose(scenario)
    meshcat.SetCameraPose(camera, target)
