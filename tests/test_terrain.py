"""Terrain scene kinds (slope, platform, friction_patch): the surface under a point against a
hand-worked case, the plant's geometry against that surface, MuJoCo's box the same, and bad
terrain named by file and field before anything is built."""

import math
import subprocess
import sys
import xml.etree.ElementTree as ET

import numpy as np
import pytest
from pydrake.math import RigidTransform
from pydrake.multibody.plant import AddMultibodyPlant, MultibodyPlantConfig
from pydrake.systems.framework import DiagramBuilder

from pedi_drake.exceptions import ScenarioError
from pedi_drake.run_checks import check_scene_geometry
from pedi_drake.scenario import SceneObject, load_scenario
from pedi_drake.station.scene import add_ground, add_scene_object
from pedi_drake.terrain import surface_at, terrain_height, terrain_map, terrain_normal, terrain_table

GROUND = 0.8
SLOPE = SceneObject(kind="slope", name="ramp", position=[1.0, 0.5, 0.0], yaw=math.pi / 2, size=[1.0, 0.6], angle=15)
PLATFORM = SceneObject(kind="platform", name="top", position=[1.0, 1.6, 0.0], size=[0.8, 0.8, 0.2588])
PATCH = SceneObject(kind="friction_patch", name="ice", position=[-1.0, 0.0, 0.0], size=[1.0, 0.8, 0.002], friction=0.2)
SCENE = [SLOPE, PLATFORM, PATCH]


def test_the_surface_under_a_point_is_the_highest_terrain_over_it():
    # Up the ramp (it climbs along +y, yaw 90 degrees) 0.4 m from its foot: 0.4 tan 15 deg high.
    on_slope = surface_at(SCENE, GROUND, 1.1, 0.9)
    assert on_slope.height == pytest.approx(0.4 * math.tan(math.radians(15)))
    np.testing.assert_allclose(
        on_slope.normal, [0.0, -math.sin(math.radians(15)), math.cos(math.radians(15))], atol=1e-15
    )
    assert (on_slope.friction, on_slope.name) == (GROUND, "ramp")
    # The platform overlaps the ramp's last 0.066 m (its foot at y = 1.2); where both are, the higher.
    assert surface_at(SCENE, GROUND, 1.0, 1.3).name == "top"
    assert surface_at(SCENE, GROUND, 1.0, 1.3).height == pytest.approx(0.2588)
    ice = surface_at(SCENE, GROUND, -1.4, 0.3)
    assert (ice.height, ice.friction, ice.name) == (0.002, 0.2, "ice")
    floor = surface_at(SCENE, GROUND, 0.0, 0.0)
    assert (floor.height, floor.friction, floor.name) == (0.0, GROUND, "")


def test_the_compiled_height_and_normal_are_surface_at_s():
    table = terrain_table([*SCENE, SceneObject(kind="box")])  # a box is no terrain: left out
    assert table.shape[0] == 3
    rng = np.random.default_rng(20261207)
    normal = np.empty(3)
    on_slope = 0
    for x, y in rng.uniform([-1.7, -0.6], [1.6, 2.2], size=(500, 2)):
        surface = surface_at(SCENE, GROUND, x, y)
        assert terrain_height(table, x, y) == pytest.approx(surface.height, abs=1e-12)
        terrain_normal(table, x, y, normal)
        np.testing.assert_allclose(normal, surface.normal, atol=1e-12)
        on_slope += surface.name == "ramp"
    assert on_slope > 20  # the sample met the slope's tilted normal, not only flat tops
    assert terrain_height(terrain_table([]), 1.1, 0.9) == 0.0
    terrain_normal(terrain_map(None), 1.1, 0.9, normal)
    np.testing.assert_array_equal(normal, [0.0, 0.0, 1.0])


def test_the_plant_has_the_surface_surface_at_gives():
    builder = DiagramBuilder()
    plant, scene_graph = AddMultibodyPlant(MultibodyPlantConfig(time_step=0.001), builder)
    add_ground(plant, GROUND)
    for obj in SCENE:
        add_scene_object(plant, obj, RigidTransform(), GROUND)
    plant.Finalize()
    diagram = builder.Build()
    query = scene_graph.get_query_output_port().Eval(scene_graph.GetMyContextFromRoot(diagram.CreateDefaultContext()))
    inspector = query.inspector()
    # Points of the plan at least 5 cm inside a footprint (or 5 cm away from all of them).
    points = [(1.1, 0.6), (0.8, 0.95), (1.2, 1.1), (1.0, 1.6), (0.75, 1.85), (-1.0, 0.0), (-1.4, 0.3), (0.0, 0.0)]
    for x, y in points:
        surface = surface_at(SCENE, GROUND, x, y)
        # 1 cm above the surface along z: 1 cm times the normal's z from it.
        distances = query.ComputeSignedDistanceToPoint(np.array([x, y, surface.height + 0.01]), threshold=0.05)
        terrain = [d for d in distances if inspector.GetName(d.id_G) != "ground"]  # the half space reports none
        if not surface.name:
            assert not terrain, (x, y)
            continue
        nearest = min(terrain, key=lambda d: d.distance)
        assert inspector.GetName(nearest.id_G).endswith(surface.name), (x, y)
        assert nearest.distance == pytest.approx(0.01 * surface.normal[2], abs=1e-6), (x, y)


def test_terrain_may_join_terrain_but_not_the_robot():
    check_scene_geometry(load_scenario(scenario_text=_scene_text(SCENE)))
    on_robot = SceneObject(kind="platform", name="under", position=[0.0, 0.0, 0.0], size=[1.0, 0.8, 0.1])
    with pytest.raises(ScenarioError, match=r"scene\[0\] \(under\): overlaps the robot at its start pose"):
        check_scene_geometry(load_scenario(scenario_text=_scene_text([on_robot])))


def _scene_text(scene: list[SceneObject]) -> str:
    entries = []
    for obj in scene:
        fields = {"kind": obj.kind, "name": obj.name, "position": obj.position, "yaw": obj.yaw, "size": obj.size}
        if obj.angle:
            fields["angle"] = obj.angle
        if obj.friction:
            fields["friction"] = obj.friction
        entries.append("{" + ", ".join(f"{k}: {v}" for k, v in fields.items()) + "}")
    return "{scene: [" + ", ".join(entries) + "]}"


@pytest.mark.parametrize(
    ("entry", "message"),
    [
        ("{kind: slope, size: [1.0, 0.6], angle: 40}", r"scene\[0\]\.angle: a slope's angle must be in \(0, 35\]"),
        ("{kind: slope, size: [1.0, 0.6]}", r"scene\[0\]\.angle: a slope's angle must be in \(0, 35\]"),
        ("{kind: friction_patch, size: [1, 1, 0.002]}", r"scene\[0\]\.friction: a friction_patch needs its friction"),
        (
            "{kind: friction_patch, size: [1, 1, 0.002], friction: 2.0}",
            r"scene\[0\]\.friction: must be in \[0.05, 1.5\]",
        ),
        ("{kind: platform, size: [1.0, 0.6]}", r"scene\[0\]\.size: a platform takes \[length, width, height\]"),
        ("{kind: box, friction: 0.3}", r"scene\[0\]\.friction: only terrain"),
    ],
)
def test_bad_terrain_names_the_field(entry, message):
    with pytest.raises(ScenarioError, match=message):
        load_scenario(scenario_text=f"{{scene: [{entry}]}}")


def test_run_sim_exits_2_naming_the_file_and_field_of_a_bad_slope(tmp_path):
    mission = tmp_path / "ramp.yaml"
    mission.write_text(
        "scene:\n  - {kind: slope, position: [1, 0, 0], size: [1, 0.6], angle: 50}\nphases:\n  - {kind: stand_up}\n"
    )
    run = subprocess.run(
        [sys.executable, "run_sim.py", "--mission", str(mission), "--out", str(tmp_path / "out")],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert run.returncode == 2, run.stderr
    assert "ramp.yaml: scene[0].angle: a slope's angle must be in (0, 35] degrees, got 50" in run.stderr
    assert not (tmp_path / "out").exists()


def test_mujoco_gets_the_same_box_and_friction():
    from pedi_drake.apps.mujoco_scene import add_scene

    root = ET.Element("mujoco")
    ET.SubElement(root, "worldbody")
    add_scene(root, SCENE, RigidTransform(), GROUND)
    geoms = {g.get("name"): g for g in root.iter("geom")}
    assert set(geoms) == {"ramp", "top", "ice"}
    np.testing.assert_allclose([float(v) for v in geoms["ice"].get("size").split()], [0.5, 0.4, 0.001])
    assert geoms["ice"].get("friction").split()[0] == "0.2"
    assert geoms["ramp"].get("friction").split()[0] == "0.8"
    assert [float(v) for v in geoms["top"].get("pos").split()] == pytest.approx([1.0, 1.6, 0.1294])
