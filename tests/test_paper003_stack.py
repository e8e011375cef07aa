"""Paper 003's five-level stack: its priorities, shown on single controller instants.

The trunk resting on the two default prongs with all four feet down is pinned but for a roll
about the line through the prong tips, so its lateral position can only change by rolling: a
lateral trunk position error and a level attitude reference then conflict. The paper-003 stack
ranks the attitude first, so the translational level gives way (paper 003, Sec. VI: "when the
prongs contact the ground, this layer has no effect on the outcome"); the paper-000 stack, which
solves both in one level, trades one against the other.
"""

import numpy as np
import pytest
from pydrake.math import RigidTransform
from reference_hqp import solve_hqp
from reference_stacks import ResolvedInputs
from reference_whole_body_tick import ReferenceTick

from pedi_drake import robot
from pedi_drake.control import references
from pedi_drake.control.config import WholeBodyControllerConfig
from pedi_drake.control.whole_body_controller import WholeBodyController
from pedi_drake.ik.analytic import solve_leg_ik_analytic
from pedi_drake.leg_kinematics import foot_position_B
from pedi_drake.prongs import ProngDesign

LATERAL_ERROR = 0.02  # [m] trunk position reference offset along y
# A residual this small [rad/s^2] or [m/s^2] is the solver's tolerance, not a trade-off.
SOLVER_TOLERANCE = 1e-6


def _resting_state(prongs: ProngDesign | None) -> tuple[np.ndarray, np.ndarray]:
    """(base_state, joint angles) of the level trunk at the prongs' contact height, the four feet
    on the ground where the standing pose puts them (x, y), at rest."""
    height = ProngDesign().ground_contact_height()
    q = robot.STANDING_Q.copy()
    for leg in robot.LEG_NAMES:
        s = robot.leg_slice(leg)
        p_B = foot_position_B(leg, q[s])
        p_B[2] = -(height - robot.FOOT_RADIUS)
        q[s] = solve_leg_ik_analytic(leg, p_B, q_near=q[s])
    X_WB = RigidTransform([0.0, 0.0, height])
    base = np.concatenate([X_WB.rotation().ToQuaternion().wxyz(), X_WB.translation(), np.zeros(6)])
    return base, q


def _trunk_task_residuals(stack: str, prongs: ProngDesign | None) -> dict[str, float]:
    """The trunk attitude and position tasks' residuals |A x - b| at one instant of `stack` with the
    trunk reference LATERAL_ERROR to the side of the trunk, the attitude reference level."""
    controller = WholeBodyController(WholeBodyControllerConfig(stack=stack), prongs)
    base, q = _resting_state(prongs)
    snapshot = controller.model.update(base, q, np.zeros(12))
    nc = controller.num_contacts
    p_ref = snapshot.p_WB + np.array([0.0, LATERAL_ERROR, 0.0])
    inputs = ResolvedInputs(
        body=references.parse_body_reference(references.body_reference_vector(p_ref, RigidTransform().rotation())),
        legs=references.parse_leg_reference(np.zeros(references.LEG_REFERENCE_SIZE)),
        ramp=np.ones(nc),
        no_motion=np.ones(nc, dtype=bool),
        polygon_N=np.zeros((0, 2)),
        polygon_d=np.zeros(0),
        friction=controller.config.friction,
        ground_height=0.0,
    )
    oracle = ReferenceTick(controller)
    levels = oracle.builder.levels(snapshot, inputs)
    x = solve_hqp(levels, oracle.layout.size, oracle.hqp_settings).x
    tasks = {task.name: task for level in levels for task in level.equalities}
    return {
        name: float(np.linalg.norm(tasks[name].A @ x - tasks[name].b))
        for name in ("trunk_orientation", "trunk_position")
    }


@pytest.fixture(scope="module")
def position_demand() -> float:
    """|b| of the trunk position task: the acceleration the lateral error asks for [m/s^2]."""
    return WholeBodyControllerConfig().trunk_position.kp * LATERAL_ERROR


def test_on_prongs_the_translational_level_gives_way_to_the_attitude(position_demand):
    residuals = _trunk_task_residuals("paper003", ProngDesign())
    # The attitude is met exactly; the position is left with all of its demand (no effect at all).
    assert residuals["trunk_orientation"] < SOLVER_TOLERANCE
    assert residuals["trunk_position"] == pytest.approx(position_demand, rel=1e-3)


def test_on_prongs_the_paper000_stack_trades_attitude_for_position(position_demand):
    # The same instant with both trunk tasks in one level: the trunk rolls about the prong tips to
    # buy some of the lateral acceleration, so the two tasks really do conflict here. The tips lie
    # 0.155 m below the trunk origin, so a roll buys little: the least-squares compromise rolls at
    # about 0.3 rad/s^2 for about 0.05 m/s^2.
    residuals = _trunk_task_residuals("paper000", ProngDesign())
    assert residuals["trunk_orientation"] > 0.1
    assert position_demand - residuals["trunk_position"] > 0.01


def test_on_four_feet_alone_the_paper003_stack_tracks_both_trunk_tasks():
    # Without prongs the feet leave the trunk all six directions: nothing conflicts, and the
    # translational level is met as fully as the attitude.
    residuals = _trunk_task_residuals("paper003", None)
    assert residuals["trunk_orientation"] < SOLVER_TOLERANCE
    assert residuals["trunk_position"] < SOLVER_TOLERANCE
