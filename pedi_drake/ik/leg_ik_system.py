"""LegIkSystem: the leg IK solver as a Drake LeafSystem (a thin adapter around solve_leg_ik).

Ports:
    input  foot_target_W  (3)       foot-centre target in the world frame [m]
    input  X_WB           (7)       estimated trunk pose: quaternion (w, x, y, z), p_WB [m]
                                    (the first 7 entries of the base-state vector)
    input  leg            abstract  str, one of FR, FL, RR, RL
    input  q_measured     (12)      joint angles the solve starts from, Unitree motor order [rad]
                                    (the measured ones, or a client's seed: see below)
    output leg_q_goal     (3)       the selected leg's goal (hip, thigh, calf) [rad]
    output solved         (1)       1.0 if the last solve reached the target within tol, else 0.0
    output ik_error       (1)       foot-to-target distance of the last solve [m]
    output solved_target_B (3)      the trunk-frame target of the last solve [m] (NaN before the
                                    first one, or for a non-finite target)

The system solves on an initialization event and on periodic discrete updates, and only when
the target changed: a different leg, or the foot target expressed in the trunk frame moved by
more than `retarget_tolerance` (a new world target or a trunk displacement; estimator noise
below the tolerance does not trigger a solve). The solve starts from the measured angles of
the selected leg. The memo of the last solved target, the goal and the flags live in the
discrete state, so the system has no mutable Python members and contexts can be cloned.
A non-finite target or pose gives solved = 0 and holds the measured leg angles as the goal.

The check runs at every update (most find nothing to do), so it is one compiled kernel
(`_retarget`): the target in the trunk frame and its comparison with the last one.

A client that asks for several targets in turn (the MissionManager) reads `solved_target_B` to
tell the answer to its request from the previous one: the answer is its own once that output is
within `retarget_tolerance` of the requested trunk-frame target. Such a client may feed its own
seed into `q_measured` (e.g. the previous waypoint's answer) to chain solves along a path.
"""

import math

import numpy as np
from pydrake.common.value import AbstractValue
from pydrake.systems.framework import BasicVector, Context, DiscreteValues, EventStatus

from pedi_drake import robot
from pedi_drake.ik.fabrik import DEFAULT_MAX_ITERATIONS, solve_leg_ik
from pedi_drake.leaf_system import LeafSystemWithoutWitnesses
from pedi_drake.runtime.jit import kernel

# Layout of the discrete state vector.
_TARGET_B = slice(0, 3)  # trunk-frame target of the last solve [m] (NaN before the first one)
_LEG = 3  # index of the leg of the last solve in LEG_NAMES (-1 before the first one)
_Q_GOAL = slice(4, 7)  # goal (hip, thigh, calf) [rad]
_SOLVED = 7  # 1.0 or 0.0
_ERROR = 8  # [m]
_SOLVE_COUNT = 9  # number of solves so far (diagnostics and tests)
_STATE_SIZE = 10
# Trunk-frame target motion that triggers a new solve [m]; also the distance within which a
# client matches an answer to its request (see the module docstring).
RETARGET_TOLERANCE = 1e-4


@kernel
def _retarget(p_WF, pose, state, leg_index, tolerance, p_target_B) -> bool:
    """Whether a new solve is due; writes the target in the trunk frame into p_target_B (3) [m].

    p_WF (3): the world target [m]; pose (7): quaternion (w, x, y, z) and p_WB [m]; state: the
    discrete state (layout above). The trunk-frame target is R_WB^T (p_WF - p_WB), NaN when the
    target or the pose is not finite or the quaternion is near zero. A solve is due for another
    leg, or when the target moved by more than `tolerance` [m] in any coordinate (two targets
    that are both NaN are the same).
    """
    finite = True
    for i in range(3):
        finite = finite and math.isfinite(p_WF[i])
    for i in range(7):
        finite = finite and math.isfinite(pose[i])
    w, x, y, z = pose[0], pose[1], pose[2], pose[3]
    norm_squared = w * w + x * x + y * y + z * z
    if not (finite and math.sqrt(norm_squared) > 1e-9):
        p_target_B[:] = np.nan
    else:
        # R_WB of the normalised quaternion, as Drake's RotationMatrix(Quaternion).
        s = 2.0 / norm_squared
        xx, yy, zz, xy, xz, yz = x * x * s, y * y * s, z * z * s, x * y * s, x * z * s, y * z * s
        wx, wy, wz = w * x * s, w * y * s, w * z * s
        d0, d1, d2 = p_WF[0] - pose[4], p_WF[1] - pose[5], p_WF[2] - pose[6]
        # R^T d, column by column of R.
        p_target_B[0] = (1.0 - yy - zz) * d0 + (xy + wz) * d1 + (xz - wy) * d2
        p_target_B[1] = (xy - wz) * d0 + (1.0 - xx - zz) * d1 + (yz + wx) * d2
        p_target_B[2] = (xz + wy) * d0 + (yz - wx) * d1 + (1.0 - xx - yy) * d2
    if int(state[_LEG]) != leg_index:
        return True
    new_valid, old_valid = True, True
    for i in range(3):
        new_valid = new_valid and math.isfinite(p_target_B[i])
        old_valid = old_valid and math.isfinite(state[i])
    if not new_valid and not old_valid:
        return False
    for i in range(3):
        if not abs(p_target_B[i] - state[i]) <= tolerance:
            return True
    return False


class LegIkSystem(LeafSystemWithoutWitnesses):
    """Joint-space goal of the selected leg for a world-frame foot target (see the module doc)."""

    def __init__(
        self,
        *,
        period: float = 0.002,
        tol: float = 1e-3,
        max_iterations: int = DEFAULT_MAX_ITERATIONS,
        retarget_tolerance: float = RETARGET_TOLERANCE,
    ):
        """
        Args:
            period: discrete update period [s] at which the inputs are checked for a new target.
            tol: IK success threshold on the foot-to-target distance [m].
            max_iterations: FABRIK iteration budget per solve.
            retarget_tolerance: trunk-frame target motion that triggers a new solve [m].
        """
        super().__init__()
        self._tol = float(tol)
        self._max_iterations = int(max_iterations)
        self._retarget_tolerance = float(retarget_tolerance)

        self._foot_target_W = self.DeclareVectorInputPort("foot_target_W", 3)
        self._X_WB = self.DeclareVectorInputPort("X_WB", 7)
        self._leg = self.DeclareAbstractInputPort("leg", AbstractValue.Make(""))
        self._q_measured = self.DeclareVectorInputPort("q_measured", robot.NUM_JOINTS)

        initial = np.zeros(_STATE_SIZE)
        initial[_TARGET_B] = np.nan
        initial[_LEG] = -1.0
        initial[_Q_GOAL] = robot.STANDING_Q[0:3]
        self._state_index = self.DeclareDiscreteState(initial)
        self.DeclarePeriodicDiscreteUpdateEvent(period, 0.0, self._update)
        self.DeclareInitializationDiscreteUpdateEvent(self._update)
        # Compiled (or loaded) here, not in a control tick; with the argument types of `_update`
        # (a Context's discrete state is a read-only array).
        state = initial.copy()
        state.flags.writeable = False
        _retarget(np.zeros(3), np.array([1.0, 0, 0, 0, 0, 0, 0]), state, 0, self._retarget_tolerance, np.empty(3))

        state_ticket = {self.discrete_state_ticket(self._state_index)}
        self._leg_q_goal = self.DeclareVectorOutputPort(
            "leg_q_goal", 3, self._calc_leg_q_goal, prerequisites_of_calc=state_ticket
        )
        self._solved = self.DeclareVectorOutputPort("solved", 1, self._calc_solved, prerequisites_of_calc=state_ticket)
        self._ik_error = self.DeclareVectorOutputPort(
            "ik_error", 1, self._calc_ik_error, prerequisites_of_calc=state_ticket
        )
        self._solved_target_B = self.DeclareVectorOutputPort(
            "solved_target_B", 3, self._calc_solved_target_B, prerequisites_of_calc=state_ticket
        )

    def _update(self, context: Context, discrete_state: DiscreteValues) -> EventStatus:
        leg = self._leg.Eval(context)
        leg_index = robot.LEG_NAMES.index(leg) if leg in robot.LEG_NAMES else None
        if leg_index is None:
            # A wiring error, not a bad target: fail loudly with the offending value.
            robot.leg_slice(leg)
        state = context.get_discrete_state(self._state_index).get_value()
        p_target_B = np.empty(3)
        due = _retarget(
            self._foot_target_W.Eval(context),
            self._X_WB.Eval(context),
            state,
            leg_index,
            self._retarget_tolerance,
            p_target_B,
        )
        if not due:
            return EventStatus.DidNothing()

        q_leg = np.asarray(self._q_measured.Eval(context), dtype=float)[robot.leg_slice(leg)]
        new_state = state.copy()
        new_state[_TARGET_B] = p_target_B
        new_state[_LEG] = leg_index
        new_state[_SOLVE_COUNT] += 1
        if np.all(np.isfinite(q_leg)):
            result = solve_leg_ik(leg, p_target_B, q_leg, tol=self._tol, max_iterations=self._max_iterations)
            new_state[_Q_GOAL] = result.q
            new_state[_SOLVED] = 1.0 if result.success else 0.0
            new_state[_ERROR] = result.error
        else:  # no trustworthy start: keep the previous goal and report failure
            new_state[_SOLVED] = 0.0
            new_state[_ERROR] = np.inf
        discrete_state.get_mutable_vector(self._state_index).SetFromVector(new_state)
        return EventStatus.Succeeded()

    def _state(self, context: Context) -> np.ndarray:
        return context.get_discrete_state(self._state_index).get_value()

    def _calc_leg_q_goal(self, context: Context, output: BasicVector) -> None:
        output.SetFromVector(self._state(context)[_Q_GOAL])

    def _calc_solved(self, context: Context, output: BasicVector) -> None:
        output.SetAtIndex(0, self._state(context)[_SOLVED])

    def _calc_ik_error(self, context: Context, output: BasicVector) -> None:
        output.SetAtIndex(0, self._state(context)[_ERROR])

    def _calc_solved_target_B(self, context: Context, output: BasicVector) -> None:
        output.SetFromVector(self._state(context)[_TARGET_B])

    def solve_count(self, context: Context) -> int:
        """How many IK solves this context has seen (diagnostics)."""
        return int(self._state(context)[_SOLVE_COUNT])
