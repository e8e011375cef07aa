"""The Go1 model against the independent reference description (example-robot-data 6.0.0)."""

import importlib.metadata
import re
from pathlib import Path

import numpy as np
import pytest
from pydrake.multibody.parsing import Parser
from pydrake.multibody.plant import MultibodyPlant
from pydrake.multibody.tree import BodyIndex

from pedi_drake import robot
from pedi_drake.prongs import ProngDesign


def _reference_urdf_text() -> str:
    """The reference go1.urdf of the `example-robot-data` distribution (a test dependency)."""
    files = importlib.metadata.files("example-robot-data") or []
    (entry,) = [f for f in files if str(f).endswith("robots/go1_description/urdf/go1.urdf")]
    text = Path(entry.locate()).read_text()
    # The reference visuals use Collada meshes; kinematics and inertia need no geometry.
    return re.sub(r"<(visual|collision)>.*?</\1>", "", text, flags=re.S)


@pytest.fixture(scope="module")
def reference():
    plant = MultibodyPlant(0.0)
    Parser(plant).AddModelsFromString(_reference_urdf_text(), "urdf")
    plant.Finalize()
    return plant


def _is_placeholder(name: str) -> bool:
    """Reference bodies the model leaves out: the dummy root `base` and the Gazebo sensor frames."""
    return name == "base" or name.startswith(("camera_", "ultraSound_"))


def _bodies(plant) -> dict:
    """Every body of `plant` but the world, by name."""
    return {b.name(): b for b in (plant.get_body(BodyIndex(i)) for i in range(1, plant.num_bodies()))}


def _context_at(plant, q12):
    context = plant.CreateDefaultContext()
    for name, angle in zip(robot.JOINT_NAMES, q12, strict=True):
        plant.GetJointByName(name).set_angle(context, angle)
    return context


def _com_B(plant, context, body_names=None) -> np.ndarray:
    """COM [m] in the trunk frame of the bodies named (of the whole plant if None)."""
    X_BW = plant.GetBodyByName("trunk").EvalPoseInWorld(context).inverse()
    if body_names is None:
        return X_BW @ plant.CalcCenterOfMassPositionInWorld(context)
    bodies = [plant.GetBodyByName(n) for n in body_names]
    masses = np.array([b.get_mass(context) for b in bodies])
    p_WBcm = [b.EvalPoseInWorld(context) @ b.CalcCenterOfMassInBodyFrame(context) for b in bodies]
    return X_BW @ (masses @ np.array(p_WBcm) / masses.sum())


def _foot_positions_B(plant, q12, trunk="trunk"):
    context = _context_at(plant, q12)
    trunk_frame = plant.GetFrameByName(trunk)
    return np.array(
        [
            plant.CalcRelativeTransform(context, trunk_frame, plant.GetFrameByName(f)).translation()
            for f in robot.FOOT_BODY_NAMES
        ]
    )


def test_foot_positions_match_reference_at_random_configurations(reference, go1_plant, rng):
    plant, _ = go1_plant
    for _ in range(50):
        q12 = rng.uniform(robot.Q_LOWER, robot.Q_UPPER)
        np.testing.assert_allclose(_foot_positions_B(plant, q12), _foot_positions_B(reference, q12), atol=1e-6)


def test_body_poses_match_reference_at_random_configurations(reference, go1_plant, rng):
    plant, _ = go1_plant
    names = sorted(_bodies(plant))
    for _ in range(20):
        q12 = rng.uniform(robot.Q_LOWER, robot.Q_UPPER)
        for name in names:
            X_BA = [
                p.CalcRelativeTransform(_context_at(p, q12), p.GetFrameByName("trunk"), p.GetFrameByName(name))
                for p in (plant, reference)
            ]
            np.testing.assert_allclose(X_BA[0].GetAsMatrix4(), X_BA[1].GetAsMatrix4(), atol=1e-9, err_msg=name)


def test_model_has_every_reference_body_but_the_placeholders(reference, go1_plant):
    plant, _ = go1_plant
    assert set(_bodies(plant)) == {n for n in _bodies(reference) if not _is_placeholder(n)}


def test_reference_placeholders_weigh_under_a_tenth_of_a_gram(reference):
    context = reference.CreateDefaultContext()
    masses = [b.get_mass(context) for n, b in _bodies(reference).items() if _is_placeholder(n)]
    assert len(masses) > 0 and sum(masses) < 1e-4


def test_total_mass_matches_reference_within_a_milligram(reference, go1_plant):
    plant, _ = go1_plant
    ours = plant.CalcTotalMass(plant.CreateDefaultContext())
    context = reference.CreateDefaultContext()
    theirs = sum(b.get_mass(context) for n, b in _bodies(reference).items() if not _is_placeholder(n))
    assert abs(ours - theirs) < 1e-6


def test_total_mass_constant_is_the_model_mass(go1_plant):
    plant, _ = go1_plant
    assert plant.CalcTotalMass(plant.CreateDefaultContext()) == pytest.approx(robot.TOTAL_MASS, abs=1e-9)


def test_whole_robot_com_matches_reference_at_random_configurations(reference, go1_plant, rng):
    plant, _ = go1_plant
    for _ in range(50):
        q12 = rng.uniform(robot.Q_LOWER, robot.Q_UPPER)
        ours = _com_B(plant, _context_at(plant, q12))
        theirs = _com_B(reference, _context_at(reference, q12))
        assert np.linalg.norm(ours - theirs) < 1e-4, q12  # [m]


def test_leg_com_matches_reference_at_random_configurations(reference, go1_plant, rng):
    plant, _ = go1_plant
    for _ in range(50):
        q12 = rng.uniform(robot.Q_LOWER, robot.Q_UPPER)
        contexts = _context_at(plant, q12), _context_at(reference, q12)
        for leg in robot.LEG_NAMES:
            names = sorted(n for n in _bodies(plant) if n.startswith(f"{leg}_"))
            ours, theirs = (_com_B(p, c, names) for p, c in zip((plant, reference), contexts, strict=True))
            assert np.linalg.norm(ours - theirs) < 1e-6, (leg, q12)  # [m]


def test_joint_limits_equal_reference_and_constants(reference, go1_plant):
    plant, _ = go1_plant
    for k, name in enumerate(robot.JOINT_NAMES):
        ours, theirs = plant.GetJointByName(name), reference.GetJointByName(name)
        assert ours.position_lower_limits()[0] == theirs.position_lower_limits()[0] == robot.Q_LOWER[k]
        assert ours.position_upper_limits()[0] == theirs.position_upper_limits()[0] == robot.Q_UPPER[k]
        assert ours.velocity_upper_limits()[0] == theirs.velocity_upper_limits()[0] == robot.VELOCITY_LIMIT[k]
        actuator = plant.GetJointActuatorByName(robot.MOTOR_NAMES[k])
        assert actuator.effort_limit() == robot.EFFORT_LIMIT[k]


def test_link_inertias_match_reference(reference, go1_plant):
    plant, _ = go1_plant
    ours_context, theirs_context = plant.CreateDefaultContext(), reference.CreateDefaultContext()
    for name in sorted(_bodies(plant)):  # trunk, IMU, leg links and rotors
        a = plant.GetBodyByName(name).CalcSpatialInertiaInBodyFrame(ours_context)
        b = reference.GetBodyByName(name).CalcSpatialInertiaInBodyFrame(theirs_context)
        np.testing.assert_allclose(a.CopyToFullMatrix6(), b.CopyToFullMatrix6(), atol=1e-12, err_msg=name)


def test_unitree_order_round_trips_through_plant_vectors(go1_plant, rng):
    plant, plant_map = go1_plant
    q12 = rng.uniform(robot.Q_LOWER, robot.Q_UPPER)
    q = plant_map.full_positions([1, 0, 0, 0], [0.1, 0.2, 0.3], q12, plant.num_positions())
    np.testing.assert_array_equal(plant_map.joint_positions(q), q12)
    for k, name in enumerate(robot.JOINT_NAMES):
        assert plant.GetJointByName(name).GetOnePosition(_context_with(plant, q)) == q12[k]


def _context_with(plant, q):
    context = plant.CreateDefaultContext()
    plant.SetPositions(context, q)
    return context


def test_prongs_add_their_mass_and_touch_ground_at_design_height():
    design = ProngDesign()
    plant, _ = robot.make_go1_plant(robot.design_key(design))
    mass = plant.CalcTotalMass(plant.CreateDefaultContext())
    assert mass == pytest.approx(robot.TOTAL_MASS + design.num_prongs * design.mass)
    assert design.ground_contact_height() == pytest.approx(0.17)
    assert robot.prong_body_names(design) == ("prong_0", "prong_1")


def test_models_directory_has_the_package_manifest():
    assert (robot.models_dir() / "package.xml").exists()
    assert (robot.models_dir() / "go1" / "go1.urdf").exists()


def test_shipped_urdf_is_what_the_generator_writes():
    import importlib.util

    path = robot.models_dir() / "go1" / "generate_go1_urdf.py"
    spec = importlib.util.spec_from_file_location("generate_go1_urdf", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    assert module.make_urdf() == (robot.models_dir() / "go1" / "go1.urdf").read_text()
