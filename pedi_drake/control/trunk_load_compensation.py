"""Integral action on the trunk's tracking: the load the controllers' model does not know.

Both whole-body controllers compute torques from the Go1 of `pedi_drake.robot`: 13.1 kg, motors
that apply exactly the torque they are sent. A real Go1 carries things, its motors deliver less
than their rating (worn, hot, a low battery) and its joints lose torque to friction. The
controllers' trunk task is a PD (Eq. 1, a = a_ref + kp e + kd e'), so an unmodelled load leaves
a steady error of about (load / mass) / kp: with kp = 100 1/s^2, a 3 kg payload sags the trunk by
2 cm and motors at 60 % of their rating by 4 cm, more than any phase's tolerance.

`TrunkLoadCompensator` learns that load from the trunk's tracking error (the estimate against
the mission's reference) and hands it to the controller as an external wrench on the trunk, a
term of the dynamics the controller's model lacks:

    M vdot + h - J_trunk^T w = S tau + J_c^T f,      w = -(m b, I beta),
    b' = ki (p_ref - p),     beta' = ki_R rot(R_ref R^T),

with m and I the model's mass and rotational inertia about the trunk origin, so that b and beta
are the accelerations the load would give the model's robot. At steady state the legs carry the
load and the trunk's error goes to zero. With the PD's closed loop s^2 + kd s + kp, the integral
adds a third pole near -ki / kp (ki / kp = 2 1/s by default: the load is learnt within a second or
two, well below the PD's own poles at -10 1/s; the loop is stable while ki < kp kd).

A wrench, not an acceleration. Added to the trunk task's reference, the same correction would be
an acceleration the trunk does not make: a lifted leg's torques would carry their share of it
(the leg's mass times it), and the joint-torque force estimate would read that as a force on the
foot (a guarded touch against the MuJoCo Go1 felt 3 N with nothing there). A wrench on the trunk
enters only the floating base's rows of the dynamics; a lifted leg's torques do not change.

It learns only while the legs carry the trunk, the trunk higher than `CARRIED_HEIGHT` (lower, it
may rest on its belly), on four feet, or on three with the lifted leg moving freely (a joint
reference: a reach, a lift, a placing). A loaded prong tip pins the trunk's position but not its
attitude (the trunk pivots about the tip on its feet): the attitude is learnt, the position not.
On three feet the load the legs must make up changes (motors of different strength carry a
different share of it), so it must be learnt there too. A lifted foot on a foot task may be
pushing on something (a wall, an obstacle, a teleoperated press): the trunk's error then holds
that push's reaction, which the push's own bounds (the balance bound of the live SUF) were set
against, so nothing is learnt. Then, and with fewer feet down, what was learnt is held. It is
kept, not reset (the payload is still there).
"""

import dataclasses
import math

import numpy as np
from pydrake.systems.framework import BasicVector, Context, DiscreteValues

from pedi_drake.control import references
from pedi_drake.estimation.base_state import BASE_STATE_SIZE
from pedi_drake.leaf_system import LeafSystemWithoutWitnesses
from pedi_drake.runtime.jit import kernel
from pedi_drake.vector3 import orientation_error_kernel, rotation_matrix_kernel

# A trunk lower than this [m] may be resting on the ground (a Go1 lying on its folded legs holds
# its trunk at 0.09-0.12 m); it is carried by its legs only above.
CARRIED_HEIGHT = 0.12

# Slices of the learnt state: the linear (b) and angular (beta) feed-forward, world frame.
LINEAR = slice(0, 3)
ANGULAR = slice(3, 6)


@dataclasses.dataclass
class TrunkLoadCompensationConfig:
    """Integral action on the trunk's position and attitude tracking (scenario `trunk_load_compensation:`)."""

    # On: the controller is told the load it learns. Off: the controller's model is taken as the
    # robot (a Go1 exactly as modelled, or a study of what the load does without it).
    enabled: bool = True
    # Integral gain of the position error [1/s^3]: b' = ki (p_ref - p).
    position_gain: float = 200.0
    # Integral gain of the attitude error [1/s^3]: beta' = ki_R rot(R_ref R^T).
    orientation_gain: float = 300.0
    # Largest learnt linear acceleration of the load per axis, x, y, z [m/s^2]: the z bound carries the
    # controllers' model's own weight once more (motors at half their rating, or a 13 kg load);
    # sideways a third of it, a load 5 cm off a 13 kg trunk needs far less.
    max_linear: list[float] = dataclasses.field(default_factory=lambda: [3.0, 3.0, 10.0])
    # Largest learnt angular acceleration of the load per axis [rad/s^2]: a pair of legs at 60 % of their
    # rating leaves about 4 N m of pitch to carry, 10 rad/s^2 of the model's trunk.
    max_angular: float = 30.0

    def problems(self) -> list[tuple[str, str]]:
        """(field, problem) for every value out of its range."""
        found = []
        for name in ("position_gain", "orientation_gain", "max_angular"):
            value = getattr(self, name)
            if not (np.isfinite(value) and value >= 0.0):
                found.append((name, f"must be a finite number >= 0, got {value!r}"))
        limits = np.asarray(self.max_linear, dtype=float)
        if limits.shape != (3,) or not np.all(np.isfinite(limits)) or np.any(limits < 0.0):
            found.append(("max_linear", f"expected [x, y, z] >= 0 in m/s^2, got {self.max_linear!r}"))
        return found


@kernel
def _learning_kernel(
    base: np.ndarray, contact_set: np.ndarray, leg_reference: np.ndarray, enabled: bool
) -> tuple[bool, bool]:
    """`TrunkLoadCompensator.learning` on its inputs' values: base_state (13), contact_set (4 feet,
    then the prong tips), leg_reference (48)."""
    down = 0
    lifted_free = True
    for k in range(4):
        if contact_set[k] >= 0.5:
            down += 1
        elif round(leg_reference[k * references.LEG_BLOCK]) != references.LEG_MODE_JOINTS:
            lifted_free = False
    standing = down == 4 or (down == 3 and lifted_free)
    carried = enabled and base[6] > CARRIED_HEIGHT and standing
    on_prongs = False
    for k in range(4, contact_set.shape[0]):
        on_prongs = on_prongs or contact_set[k] >= 0.5
    return carried and not on_prongs, carried


@kernel
def _learn_kernel(
    learnt: np.ndarray,
    body: np.ndarray,
    base: np.ndarray,
    contact_set: np.ndarray,
    leg_reference: np.ndarray,
    enabled: bool,
    position_step: float,
    orientation_step: float,
    linear_limit: np.ndarray,
    max_angular: float,
) -> None:
    """One learning step of (b, beta) `learnt` (6,) in place: b += ki T (p_ref - p) and
    beta += ki_R T rot(R_ref R^T) (`position_step`, `orientation_step`: the gains times the period
    [1/s^2]), each bounded, when `_learning_kernel` says the errors measure the load; nothing on a
    non-finite reference or estimate (the controller refuses that tick)."""
    position, attitude = _learning_kernel(base, contact_set, leg_reference, enabled)
    if not attitude:
        return
    for k in range(body.shape[0]):
        if not math.isfinite(body[k]):
            return
    for k in range(base.shape[0]):
        if not math.isfinite(base[k]):
            return
    if position:
        for k in range(3):
            value = learnt[k] + position_step * (body[k] - base[4 + k])
            learnt[k] = min(max(value, -linear_limit[k]), linear_limit[k])
    error = np.empty(3)
    orientation_error_kernel(rotation_matrix_kernel(body[3:7]), rotation_matrix_kernel(base[0:4]), error)
    for k in range(3):
        value = learnt[3 + k] + orientation_step * error[k]
        learnt[3 + k] = min(max(value, -max_angular), max_angular)


@kernel
def _wrench_kernel(learnt: np.ndarray, base: np.ndarray, inertia_B: np.ndarray, mass: float, out: np.ndarray) -> None:
    """The learnt load `learnt` (b, beta) as the wrench [torque; force] on the trunk, world frame,
    into `out` (6,): -(R I R^T beta, m b), R the estimate's attitude (identity before it has one)."""
    known = base[0] != 0.0 or base[1] != 0.0 or base[2] != 0.0 or base[3] != 0.0
    for k in range(4):
        known = known and math.isfinite(base[k])
    R = rotation_matrix_kernel(base[0:4]) if known else np.eye(3)
    torque = R @ (inertia_B @ (R.T @ learnt[3:6]))
    for k in range(3):
        out[k] = -torque[k]
        out[3 + k] = -mass * learnt[k]


class TrunkLoadCompensator(LeafSystemWithoutWitnesses):
    """The unmodelled load on the trunk, learnt, as an external wrench for the controller.

    Inputs: body_reference (19, pedi_drake.control.references), leg_reference (48), base_state
    (13, the estimate), contact_set (4 feet, then the prong tips). Output: trunk_external_wrench (6), [torque; force]
    on the trunk at its origin, world frame [N m, N] (the controllers' input of that name). State:
    (b, beta), the load's accelerations of the model's robot [m/s^2, rad/s^2], updated every
    `period` [s] (the controller's). `mass` [kg] and `rotational_inertia` (3, 3) [kg m^2] about
    the trunk origin in the trunk frame are the controller's model's, standing.
    """

    def __init__(
        self,
        config: TrunkLoadCompensationConfig,
        period: float,
        num_contacts: int,
        mass: float,
        rotational_inertia: np.ndarray,
    ) -> None:
        super().__init__()
        self.config = config
        self.period = period
        self.mass = float(mass)
        self.rotational_inertia = np.asarray(rotational_inertia, dtype=float).reshape(3, 3)
        self._linear_limit = np.asarray(config.max_linear, dtype=float)
        self.body_reference_port = self.DeclareVectorInputPort("body_reference", references.BODY_REFERENCE_SIZE)
        self.leg_reference_port = self.DeclareVectorInputPort("leg_reference", references.LEG_REFERENCE_SIZE)
        self.base_state_port = self.DeclareVectorInputPort("base_state", BASE_STATE_SIZE)
        self.contact_set_port = self.DeclareVectorInputPort("contact_set", num_contacts)
        self.learnt_state = self.DeclareDiscreteState(6)
        self.DeclarePeriodicDiscreteUpdateEvent(period, 0.0, self._learn)
        # The same update on demand (CalcForcedDiscreteVariableUpdate), for tests.
        self.DeclareForcedDiscreteUpdateEvent(self._learn)
        self.wrench_port = self.DeclareVectorOutputPort(
            "trunk_external_wrench",
            6,
            self._wrench,
            {self.input_port_ticket(self.base_state_port.get_index()), self.xd_ticket()},
        )
        self.DeclareStateOutputPort("learnt", self.learnt_state)
        # Its kernels are compiled (or loaded from the cache) here, not in the first control tick.
        context = self.CreateDefaultContext()
        for port in (self.body_reference_port, self.leg_reference_port, self.base_state_port, self.contact_set_port):
            port.FixValue(context, np.zeros(port.size()))
        self._learn(context, context.get_mutable_discrete_state())
        self.wrench(context)

    def learning(self, context: Context) -> tuple[bool, bool]:
        """(position, attitude): which of the trunk's tracking errors measure the load now."""
        return _learning_kernel(
            self.base_state_port.Eval(context),
            self.contact_set_port.Eval(context),
            self.leg_reference_port.Eval(context),
            self.config.enabled,
        )

    def _learn(self, context: Context, discrete_state: DiscreteValues) -> None:
        c = self.config
        _learn_kernel(
            discrete_state.get_mutable_value(self.learnt_state),
            self.body_reference_port.Eval(context),
            self.base_state_port.Eval(context),
            self.contact_set_port.Eval(context),
            self.leg_reference_port.Eval(context),
            c.enabled,
            c.position_gain * self.period,
            c.orientation_gain * self.period,
            self._linear_limit,
            float(c.max_angular),
        )

    def wrench(self, context: Context) -> np.ndarray:
        """The learnt load as the external wrench on the trunk, [torque; force] world [N m, N]."""
        out = np.empty(6)
        _wrench_kernel(
            context.get_discrete_state(self.learnt_state).value(),
            self.base_state_port.Eval(context),
            self.rotational_inertia,
            self.mass,
            out,
        )
        return out

    def _wrench(self, context: Context, output: BasicVector) -> None:
        output.SetFromVector(self.wrench(context))
