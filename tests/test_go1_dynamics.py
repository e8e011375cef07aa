"""The compiled Go1 dynamics (`go1_dynamics`) against Drake, through ControllerModel's two paths.

Tolerance: every array of the snapshot must satisfy |compiled - Drake| <= 1e-9 (|Drake| + max
|Drake of that array|), i.e. 1e-9 relative, entries far below the array's scale judged at that
scale. Both sides compute the same exact quantities with different operation orders (Drake in
its own body frames, the kernel in world axes about the trunk origin), so they differ by
accumulated rounding only: measured below 1e-14 of each array's largest entry. A modelling slip
is orders of magnitude above 1e-9: a missing IMU body (1 g) moves M by ~1e-4 relative, a missing
reflected rotor inertia by ~3e-4, the joint damping h by ~1e-3.
"""

import re

import numpy as np
import pytest
from pydrake.multibody.parsing import Parser
from pydrake.multibody.plant import MultibodyPlant

from pedi_drake import robot
from pedi_drake.control.robot_model import ControllerModel
from pedi_drake.dynamics import go1_dynamics as gd
from pedi_drake.prongs import ProngDesign
from pedi_drake.resources import models_dir
from pedi_drake.runtime.jit import python_records
from pedi_drake.scenario import load_scenario

RNG_SEED = 20261203
NUM_STATES = 200
SNAPSHOT_FIELDS = (
    "q",
    "v",
    "M",
    "h",
    "J_contacts",
    "Jdot_v_contacts",
    "p_contacts",
    "J_trunk",
    "Jdot_v_trunk",
    "R_WB",
    "p_WB",
    "p_com",
    "J_com",
    "Jdot_v_com",
    "q_joints",
    "v_joints",
    "V_trunk",
    "v_com",
)
RELATIVE_TOLERANCE = 1e-9


def random_state(rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(base_state, q_joints, v_joints): any orientation (quaternion not normalised, as an
    estimator may hand it over), the trunk anywhere within 10 m, turning at up to 4 rad/s and
    moving at up to 2 m/s, joints anywhere within their limits at up to their velocity limits."""
    quaternion = rng.normal(size=4) * rng.uniform(0.5, 2.0)
    w_WB = rng.normal(size=3)
    w_WB *= rng.uniform(0.0, 4.0) / np.linalg.norm(w_WB)
    v_WB = rng.normal(size=3)
    v_WB *= rng.uniform(0.0, 2.0) / np.linalg.norm(v_WB)
    base = np.concatenate([quaternion, rng.uniform(-10.0, 10.0, 3), w_WB, v_WB])
    q = rng.uniform(robot.Q_LOWER, robot.Q_UPPER)
    v = rng.uniform(-robot.VELOCITY_LIMIT, robot.VELOCITY_LIMIT)
    return base, q, v


def assert_close(actual, desired, name: str) -> None:
    desired = np.asarray(desired)
    scale = float(np.max(np.abs(desired))) if desired.size else 0.0
    np.testing.assert_allclose(actual, desired, rtol=RELATIVE_TOLERANCE, atol=RELATIVE_TOLERANCE * scale, err_msg=name)


def assert_matches_drake(model: ControllerModel, rng: np.random.Generator, num_states: int) -> None:
    """Every snapshot field and every calf's orientation terms, compiled against Drake."""
    for _ in range(num_states):
        base, q, v = random_state(rng)
        reference = model.update_with_drake(base, q, v)
        compiled = model.update(base, q, v)
        for name in SNAPSHOT_FIELDS:
            assert_close(getattr(compiled, name), getattr(reference, name), name)
        for leg in range(4):
            for name, actual, desired in zip(
                ("R_WC", "J_w", "Jdot_w_v"),
                model.calf_orientation(leg),
                model.calf_orientation_with_drake(leg),
                strict=True,
            ):
                assert_close(actual, desired, f"{robot.LEG_NAMES[leg]} calf {name}")


def shipped_prong_design() -> ProngDesign:
    design = load_scenario(scenario_name="stand_with_prongs").robot.prongs
    assert design is not None
    return design


def test_controller_model_uses_the_compiled_path_by_default():
    assert ControllerModel().dynamics is not None
    assert ControllerModel(compiled=False).dynamics is None


def test_every_term_matches_drake_without_prongs():
    assert_matches_drake(ControllerModel(), np.random.default_rng(RNG_SEED), NUM_STATES)


def test_every_term_matches_drake_with_the_shipped_prong_design():
    model = ControllerModel(shipped_prong_design())
    assert model.num_contacts == 6
    assert_matches_drake(model, np.random.default_rng(RNG_SEED + 1), NUM_STATES)


def test_an_asymmetric_prong_design_flows_through_from_the_plant():
    design = ProngDesign(
        attachment_points=[[0.12, 0.03, -0.05], [-0.17, -0.04, -0.057], [0.0, 0.05, 0.02]],
        length=0.13,
        mass=0.21,
    )
    model = ControllerModel(design)
    assert model.num_contacts == 7
    assert_matches_drake(model, np.random.default_rng(RNG_SEED + 2), 50)


def _tilted_go1_plant(prongs_key=None, time_step: float = 0.0):
    """The Go1 with rotated joint frames, a tilted hip axis and a heavier trunk: parameters that
    the shipped model leaves at identity or at round values must come from the plant too."""
    text = (models_dir() / "go1" / "go1.urdf").read_text()
    text = text.replace('<origin xyz="0 -0.08 0" rpy="0 0 0"/>', '<origin xyz="0 -0.08 0" rpy="0.1 -0.2 0.3"/>')
    text = text.replace('<origin xyz="0 0 -0.213" rpy="0 0 0"/>', '<origin xyz="0 0 -0.213" rpy="-0.3 0.1 0.2"/>')
    text = text.replace('<axis xyz="1 0 0"/>', '<axis xyz="0.8 0.6 0"/>')
    text = text.replace('<mass value="5.204"/>', '<mass value="6.5"/>')
    text, count = re.subn(
        r'(<joint name="(FR|RL)_hip_rotor_joint" type="fixed">\s*<origin xyz="[^"]*") rpy="0 0 0"',
        r'\1 rpy="0.4 0.5 0.6"',
        text,
    )
    assert count == 2
    plant = MultibodyPlant(time_step)
    parser = Parser(plant)
    robot.ConfigureParser(parser)
    (model,) = parser.AddModelsFromString(text, "urdf")
    if prongs_key is not None:
        design = ProngDesign(**dict(prongs_key))
        design.attachment_points = [list(p) for p in design.attachment_points]
        robot._add_prongs(plant, model, design)
    plant.Finalize()
    return plant, robot.Go1PlantMap.from_plant(plant, model)


def test_a_changed_urdf_flows_through_from_the_plant(monkeypatch):
    monkeypatch.setattr(robot, "make_go1_plant", _tilted_go1_plant)
    model = ControllerModel(shipped_prong_design())
    assert model.total_mass > robot.TOTAL_MASS + 1.0
    assert_matches_drake(model, np.random.default_rng(RNG_SEED + 3), 50)


def test_merged_bodies_keep_the_plants_mass():
    for prongs in (None, shipped_prong_design()):
        model = ControllerModel(prongs)
        assert model.dynamics.model.mass.sum() == pytest.approx(model.total_mass, rel=1e-14)


def test_compiled_kernel_equals_its_python_source_bit_for_bit():
    dynamics = gd.Go1Dynamics(shipped_prong_design())
    rng = np.random.default_rng(RNG_SEED + 4)
    for _ in range(5):  # the interpreted kernel takes ~2 ms a call
        base, q, v = random_state(rng)
        compiled, reference = dynamics.new_output(), python_records(dynamics.new_output())
        gd.go1_dynamics(dynamics.model_record, base, q, v, compiled)
        gd.go1_dynamics.py_func(python_records(dynamics.model_record), base, q, v, reference)
        for name in compiled.dtype.names:
            np.testing.assert_array_equal(compiled[0][name], reference[0][name], err_msg=name)


def test_earlier_snapshots_stay_valid_after_later_updates():
    model = ControllerModel()
    rng = np.random.default_rng(RNG_SEED + 5)
    base, q, v = random_state(rng)
    first = model.update(base, q, v)
    kept = {name: np.copy(getattr(first, name)) for name in SNAPSHOT_FIELDS}
    model.update(*random_state(rng))
    for name in SNAPSHOT_FIELDS:
        np.testing.assert_array_equal(getattr(first, name), kept[name], err_msg=name)


def test_without_com_bias_both_paths_return_zero_com_bias():
    rng = np.random.default_rng(RNG_SEED + 6)
    base, q, v = random_state(rng)
    model = ControllerModel(com_bias=False)
    np.testing.assert_array_equal(model.update(base, q, v).Jdot_v_com, 0.0)
    np.testing.assert_array_equal(model.update_with_drake(base, q, v).Jdot_v_com, 0.0)
    assert np.any(ControllerModel().update(base, q, v).Jdot_v_com != 0.0)
