"""The Mission Manager's safety polygon: the stance's support polygon shrunk by a margin, and the
capture point's margin to it as result.json reports it."""

import numpy as np
import pytest
from pydrake.math import RigidTransform, RollPitchYaw, RotationMatrix
from pydrake.systems.analysis import Simulator

from pedi_drake import robot
from pedi_drake.control.references import SAFETY_POLYGON_SIZE, safety_polygon_vector, safety_polygon_vertices_W
from pedi_drake.control.whole_body_controller import diagnostics_layout
from pedi_drake.estimation.base_state import BaseState
from pedi_drake.estimation.leg_odometry import leg_offsets
from pedi_drake.evaluation.capture_point import polygon_margin, three_leg_margin
from pedi_drake.exceptions import PediError
from pedi_drake.mission.mission_manager import MissionManager
from pedi_drake.mission.robot_view import RobotView
from pedi_drake.mission.spec import MissionSpec, StandUp
from pedi_drake.mission.stance_polygon import prong_tips_B, stance_polygon_kernel, stance_safety_polygon
from pedi_drake.polygon import polygon_halfplanes, shrink_polygon
from pedi_drake.prongs import ProngDesign
from pedi_drake.run import run
from pedi_drake.scenario import load_scenario

MARGIN = 0.03  # [m]
X_WB = RigidTransform(RollPitchYaw(0.0, 0.0, 0.6), [0.3, -0.2, 0.28])


def _standing_view(X: RigidTransform = X_WB) -> RobotView:
    quaternion = X.rotation().ToQuaternion().wxyz()
    base = BaseState(quaternion, X.translation(), np.zeros(3), np.zeros(3))
    zeros = np.zeros(12)
    return RobotView(0.0, base, robot.STANDING_Q.copy(), zeros, zeros, np.full(4, 30.0))


def _stance_polygon(view: RobotView, contacts: np.ndarray, tips_B: np.ndarray | None = None) -> np.ndarray:
    tips_B = prong_tips_B(None) if tips_B is None else tips_B
    base = view.base
    return stance_safety_polygon(base.quaternion_wxyz, base.p_WB, view.q, contacts, tips_B, MARGIN)


def test_shrunk_triangle_has_every_edge_moved_in_by_the_margin():
    triangle = np.array([[0.0, 0.0], [0.4, 0.0], [0.0, 0.3]])
    # The 3-4-5 triangle's edges moved in by 0.03 m: legs at x = y = 0.03, the hypotenuse
    # 0.3 x + 0.4 y = 0.12 - 0.5 * 0.03.
    expected = np.array([[0.03, 0.03], [0.31, 0.03], [0.03, 0.24]])
    np.testing.assert_allclose(shrink_polygon(triangle, MARGIN), expected, atol=1e-12)


def test_a_margin_beyond_the_inradius_leaves_no_polygon():
    triangle = np.array([[0.0, 0.0], [0.4, 0.0], [0.0, 0.3]])  # inradius 0.1 m
    assert shrink_polygon(triangle, 0.11).shape == (0, 2)


def test_three_foot_stance_polygon_is_the_feet_triangle_shrunk_and_turned_with_the_trunk():
    view = _standing_view()
    contacts = np.array([0.0, 1.0, 1.0, 1.0])  # FR lifted
    x = _stance_polygon(view, contacts)
    assert x[0] == 3
    np.testing.assert_allclose(x[3], 0.6, atol=1e-12)  # the trunk's yaw
    vertices_W = safety_polygon_vertices_W(x)
    feet_xy = np.array([view.foot_W(leg)[:2] for leg in ("FL", "RR", "RL")])
    N, d = polygon_halfplanes(feet_xy)
    slack = d[None, :] - vertices_W @ N.T  # (vertex, edge) distance inside each feet edge [m]
    # Each vertex lies on two of the moved edges and well inside the third.
    np.testing.assert_allclose(np.sort(slack, axis=1)[:, :2], MARGIN, atol=1e-12)
    assert np.all(np.sort(slack, axis=1)[:, 2] > MARGIN)
    # The frame sits at the vertices' centroid.
    np.testing.assert_allclose(x[1:3], vertices_W.mean(axis=0), atol=1e-12)


def test_four_foot_stance_polygon_is_the_support_rectangle_shrunk_by_the_margin():
    view = _standing_view()
    x = _stance_polygon(view, np.ones(4))
    assert x[0] == 4
    feet_xy = np.array([view.foot_W(leg)[:2] for leg in robot.LEG_NAMES])
    np.testing.assert_allclose(safety_polygon_vertices_W(x), shrink_polygon(feet_xy, MARGIN), atol=1e-12)


def test_fewer_than_three_supports_select_the_controllers_default():
    x = _stance_polygon(_standing_view(), np.array([0.0, 1.0, 1.0, 0.0]))
    np.testing.assert_array_equal(x, safety_polygon_vector())


def _stance_polygon_through_drake(view: RobotView, contacts: np.ndarray, tips_B: np.ndarray) -> np.ndarray:
    """The same polygon made the slow way, as the manager once made it: the feet and tips through
    the RobotView's pydrake pose, the shrink, Drake's yaw, the vertices turned by a numpy product."""
    X_WB = view.X_WB
    points = [view.foot_W(leg) for k, leg in enumerate(robot.LEG_NAMES) if contacts[k] > 0.5]
    points += [X_WB @ tip for k, tip in enumerate(tips_B) if contacts[4 + k] > 0.5]
    if len(points) < 3:
        return safety_polygon_vector()
    vertices_W = shrink_polygon(np.array(points)[:, :2], MARGIN)
    if len(vertices_W) < 3:
        return safety_polygon_vector()
    origin = vertices_W.mean(axis=0)
    yaw = RollPitchYaw(X_WB.rotation()).yaw_angle()
    c, s = np.cos(yaw), np.sin(yaw)
    return safety_polygon_vector((vertices_W - origin) @ np.array([[c, -s], [s, c]]), origin, yaw)


@pytest.mark.parametrize("prongs", [None, ProngDesign()], ids=["feet", "prongs"])
def test_compiled_stance_polygon_equals_the_one_made_through_drake(prongs):
    rng = np.random.default_rng(7)
    tips_B = prong_tips_B(prongs)
    defaults = 0
    for _ in range(300):
        rpy = RollPitchYaw(rng.uniform(-0.3, 0.3), rng.uniform(-0.3, 0.3), rng.uniform(-np.pi, np.pi))
        X = RigidTransform(RotationMatrix(rpy), rng.uniform(-1.0, 1.0, 3))
        view = _standing_view(X)
        q = robot.STANDING_Q + rng.uniform(-0.3, 0.3, 12)
        view = RobotView(0.0, view.base, q, view.qd, view.tau, view.foot_force)
        contacts = (rng.uniform(size=4 + len(tips_B)) < 0.75).astype(float)
        x = _stance_polygon(view, contacts, tips_B)
        np.testing.assert_allclose(x, _stance_polygon_through_drake(view, contacts, tips_B), rtol=0, atol=1e-12)
        defaults += x[0] == 0
    assert 0 < defaults < 150  # both the default and real polygons were compared


def test_a_contact_vector_of_the_wrong_length_is_refused():
    with pytest.raises(PediError, match="5 contact flags expected"):
        _stance_polygon(_standing_view(), np.ones(4), prong_tips_B(ProngDesign())[:1])


def test_compiled_stance_polygon_equals_its_python_source_bit_for_bit():
    rng = np.random.default_rng(8)
    tips_B = prong_tips_B(ProngDesign())
    kernel = stance_polygon_kernel
    for _ in range(200):
        quaternion = rng.normal(size=4)
        p_WB, q = rng.uniform(-1.0, 1.0, 3), robot.STANDING_Q + rng.uniform(-0.5, 0.5, 12)
        contacts = (rng.uniform(size=8) < 0.8).astype(float)
        outs = [np.empty(SAFETY_POLYGON_SIZE), np.empty(SAFETY_POLYGON_SIZE)]
        counts = [
            k(quaternion, p_WB, q, leg_offsets(), contacts, tips_B, MARGIN, out)
            for k, out in zip((kernel, kernel.py_func), outs, strict=True)
        ]
        assert counts[0] == counts[1]
        np.testing.assert_array_equal(outs[0], outs[1])


def test_the_managers_safety_polygon_output_is_the_measured_stance_shrunk():
    manager = MissionManager(MissionSpec("stand", "", [StandUp(name="stand")], [], None, "test"), safety_margin=MARGIN)
    simulator = Simulator(manager)
    context = simulator.get_mutable_context()
    view = _standing_view()
    manager.GetInputPort("base_state").FixValue(context, view.base.to_vector())
    manager.GetInputPort("position_measured").FixValue(context, view.q)
    for name in ("velocity_measured", "torque_estimated"):
        manager.GetInputPort(name).FixValue(context, np.zeros(12))
    manager.GetInputPort("foot_contact").FixValue(context, view.foot_force)
    simulator.AdvanceTo(0.02)
    expected = _stance_polygon(view, np.ones(4))
    np.testing.assert_allclose(manager.GetOutputPort("safety_polygon").Eval(context), expected, atol=1e-12)


def test_polygon_margin_is_the_distance_to_the_nearest_edge_and_negative_outside():
    square = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]])
    assert polygon_margin([0.5, 0.2], square) == pytest.approx(0.2, abs=1e-12)
    assert polygon_margin([1.3, 0.5], square) == pytest.approx(-0.3, abs=1e-12)


def test_three_leg_margin_judges_only_samples_with_three_feet_loaded():
    layout = diagnostics_layout(4)
    times = np.array([0.0, 0.1, 0.2])
    diagnostics = np.zeros((layout["contact_ramp"].stop, 3))
    diagnostics[layout["capture_point"]] = [[5.0, 0.5, 0.9], [5.0, 0.5, 0.5]]  # far out on four feet
    square = safety_polygon_vector(np.array([[-0.5, -0.5], [0.5, -0.5], [0.5, 0.5], [-0.5, 0.5]]), (0.5, 0.5))
    polygons = np.column_stack([square] * 3)
    contacts = np.array([[1.0, 0.0, 0.0], [1.0, 1.0, 1.0], [1.0, 1.0, 1.0], [1.0, 1.0, 1.0]])
    phases = [{"name": "lift", "t_start": 0.05, "t_end": None}]
    margin = three_leg_margin(times, diagnostics, polygons, contacts, phases)
    assert margin == {"min": pytest.approx(0.1, abs=1e-12), "t": 0.2, "phase": "lift", "samples": 2}


def test_the_capture_point_stays_inside_the_triangle_while_a_leg_is_lifted(tmp_path):
    mission = tmp_path / "lift.yaml"
    mission.write_text(
        """phases:
  - {kind: stand_up, height: 0.28, duration: 1.5, timeout: 3.0}
  - {kind: leg_to_pedipulation, leg: FR, duration: 1.0, timeout: 4.0}
  - {kind: wait, duration: 0.5}
"""
    )
    scenario = load_scenario(scenario_text=f"{{mission: {mission}, controller: whole_body, simulation_duration: 8.0}}")
    result = run(scenario=scenario, name="lift", out_dir=tmp_path / "out", quiet=True, replay=False)
    assert result["success"], result["reason"]
    margin = result["three_leg_capture_point_margin_m"]
    # Samples over the lift and the wait (2 ms apart), every one inside by more than a centimetre.
    assert margin["samples"] > 1000
    assert margin["min"] > 0.01, margin
