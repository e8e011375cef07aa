"""RobotView's whole-robot quantities: the model's values, computed in a reused plant Context."""

import numpy as np
from pydrake.math import RollPitchYaw

from pedi_drake import robot
from pedi_drake.estimation.base_state import BaseState
from pedi_drake.leg_kinematics import foot_jacobian_B
from pedi_drake.mission.robot_view import RobotView

RNG_SEED = 20261204


def _random_view(rng) -> RobotView:
    quaternion = RollPitchYaw(*rng.uniform(-0.3, 0.3, 3)).ToQuaternion().wxyz()
    base = BaseState(quaternion, rng.normal([0.0, 0.0, 0.28], 0.05), np.zeros(3), np.zeros(3))
    q = robot.STANDING_Q + rng.normal(0, 0.2, 12)
    return RobotView(0.0, base, q, np.zeros(12), rng.normal(0, 5.0, 12), np.zeros(4))


def test_the_force_estimate_is_the_quasi_static_balance_of_the_model():
    rng = np.random.default_rng(RNG_SEED)
    plant, plant_map = robot.make_go1_plant()
    for _ in range(20):
        view = _random_view(rng)
        context = plant.CreateDefaultContext()
        q = plant_map.full_positions(view.base.quaternion_wxyz, view.base.p_WB, view.q, plant.num_positions())
        plant.SetPositions(context, q)
        tau_g = plant.CalcGravityGeneralizedForces(context)[plant_map.v_index]
        for leg in robot.LEG_NAMES:
            J_W = view.X_WB.rotation().matrix() @ foot_jacobian_B(leg, view.leg_q(leg))
            k = robot.leg_slice(leg)
            expected = -np.linalg.solve(J_W.T, view.tau[k] + tau_g[k])
            np.testing.assert_allclose(view.foot_external_force_W(leg), expected, rtol=1e-9, atol=1e-9)


def test_a_view_does_not_see_the_previous_views_state():
    rng = np.random.default_rng(RNG_SEED + 1)
    first, second = _random_view(rng), _random_view(rng)
    com, force = first.com_W(), first.foot_external_force_W("FR")
    second.com_W()
    second.foot_external_force_W("RL")
    np.testing.assert_array_equal(first.com_W(), com)
    np.testing.assert_array_equal(first.foot_external_force_W("FR"), force)
