"""Friction pyramids about the ground's normal: the rows against hand-worked forces, and both
whole-body controllers keeping a foot's force inside the pyramid of the slope under it."""

import math

import numpy as np
import pytest
from standing_context import standing_context, tick

from pedi_drake.control.config import ProjectedImpedanceConfig, WholeBodyControllerConfig
from pedi_drake.control.projected_impedance_controller import ProjectedImpedanceController
from pedi_drake.control.tick_steps import STATUS_OK
from pedi_drake.control.whole_body_controller import WholeBodyController
from pedi_drake.friction import UP, contact_tangents, friction_pyramid_rows, pyramid_slope
from pedi_drake.scenario import SceneObject
from pedi_drake.terrain import terrain_table

MU = 0.6
SLOPE_DEG = 30.0  # steeper than the inscribed pyramid's half angle, atan(0.6 / sqrt 2) = 23 deg
SLOPE_NORMAL = np.array([-math.sin(math.radians(SLOPE_DEG)), 0.0, math.cos(math.radians(SLOPE_DEG))])
# A 30 degree slope climbing along +x under the standing Go1's front right foot only (its foot
# near x = 0.19, y = -0.13 m; the front left's at y = +0.13, the rear feet's at x = -0.19).
SLOPE_UNDER_FR = SceneObject(kind="slope", name="ramp", position=[0.05, -0.3, 0.0], size=[0.35, 0.4], angle=SLOPE_DEG)


def test_flat_ground_gives_the_axis_aligned_pyramid():
    m = pyramid_slope(MU)
    expected = [[0, 0, -1], [1, 0, -m], [-1, 0, -m], [0, 1, -m], [0, -1, -m]]
    np.testing.assert_array_equal(friction_pyramid_rows(MU), expected)
    t1, t2 = np.empty(3), np.empty(3)
    contact_tangents(UP, t1, t2)
    np.testing.assert_array_equal([t1, t2], [[1, 0, 0], [0, 1, 0]])


@pytest.mark.parametrize("normal", [SLOPE_NORMAL, np.array([0.3, -0.4, math.sqrt(0.75)])])
def test_the_pyramid_stands_on_the_normal(normal):
    rows = friction_pyramid_rows(MU, normal=normal)
    m = pyramid_slope(MU)
    t1, t2 = np.empty(3), np.empty(3)
    contact_tangents(normal, t1, t2)
    np.testing.assert_allclose([t1 @ normal, t2 @ normal, t1 @ t2], 0.0, atol=1e-15)
    np.testing.assert_allclose([t1 @ t1, t2 @ t2], 1.0)
    assert np.all(rows @ (10.0 * normal) < 0.0)  # a push along the normal: strictly inside
    for tangent in (t1, -t1, t2, -t2):
        edge = 10.0 * (normal + m * tangent)
        assert np.max(rows @ edge) == pytest.approx(0.0, abs=1e-12)  # on a face
        assert np.max(rows @ (edge + 0.1 * tangent)) > 0.0  # past it
    assert np.max(rows @ (-normal)) > 0.0  # pulling on the ground


def test_a_vertical_push_on_a_30_degree_slope_slides():
    # The hand-worked case the controllers below meet: the weight's share of a foot on this slope
    # is 30 degrees off the normal, past the pyramid's 23.
    assert np.max(friction_pyramid_rows(MU, normal=SLOPE_NORMAL) @ UP) > 0.0


def _standing(controller):
    _, diag = tick(controller, standing_context(controller), 3)
    assert diag[controller.diag["status"]][0] == STATUS_OK
    forces = diag[controller.diag["contact_forces"]].reshape(-1, 3)
    assert np.sum(forces[:4, 2]) == pytest.approx(controller.model.total_mass * 9.81, rel=0.03)
    return forces


@pytest.mark.parametrize(
    "make",
    [
        lambda terrain: WholeBodyController(WholeBodyControllerConfig(friction=MU), None, terrain),
        lambda terrain: ProjectedImpedanceController(ProjectedImpedanceConfig(friction=MU), None, terrain),
    ],
    ids=["whole_body", "projected_impedance"],
)
def test_a_foot_on_a_slope_pushes_inside_the_slope_s_pyramid(make):
    rows = friction_pyramid_rows(MU, normal=SLOPE_NORMAL)
    on_flat = _standing(make(None))
    # Told nothing of the slope, the controller pushes the front right foot nearly straight
    # down: outside the slope's pyramid (the foot would slide).
    assert np.max(rows @ on_flat[0]) > 0.1 * np.linalg.norm(on_flat[0])
    on_slope = _standing(make(terrain_table([SLOPE_UNDER_FR])))
    fr = on_slope[0]
    assert fr @ SLOPE_NORMAL > 5.0  # still loaded
    assert np.max(rows @ fr) <= 1e-6 * np.linalg.norm(fr)
    # The other feet stand on flat ground: inside the world's pyramid.
    flat_rows = friction_pyramid_rows(MU)
    for force in on_slope[1:4]:
        assert np.max(flat_rows @ force) <= 1e-6 * np.linalg.norm(force)
