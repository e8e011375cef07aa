"""Integral action on the trunk's tracking: the load the controllers' model does not know.

Both whole-body controllers compute torques from the Go1 of `pedi_drake.robot`: 13.1 kg, motors
that apply exactly the torque they are sent. A real Go1 carries things, its motors deliver less
than their rating (worn, hot, a low battery) and its joints lose torque to friction. The
controllers' trunk task is a PD (Eq. 1, a = a_ref + kp e + kd e'), so an unmodelled load leaves
a steady error of about (load / mass) / kp: with kp = 100 1/s^2, a 3 kg payload sags the trunk by
2 cm and motors at 60 % of their rating by 4 cm, more than any phase's tolerance.

`TrunkLoadCompensator` sits between the mission's trunk reference and the controller. It
integrates the trunk's tracking error (the estimate against the reference) into an acceleration
it adds to the reference's feed-forward,

    a_ref' = a_ref + b,     b' = ki (p_ref - p),
    alpha_ref' = alpha_ref + beta,   beta' = ki_R rot(R_ref R^T),

so that the controller's PD plus b makes the torques the missing load needs and the steady error
goes to zero. With the PD's closed loop s^2 + kd s + kp, the integral adds a third pole near
-ki / kp (ki / kp = 2 1/s by default: the load is learnt within a second or two, well below the
PD's own poles at -10 1/s; the loop is stable while ki < kp kd).

It learns only the load the legs carry, and only while all four feet stand. A trunk lower than
`CARRIED_HEIGHT` may rest on its belly: nothing is learnt. A loaded prong tip pins the trunk's
position but not its attitude (the trunk pivots about the tip on its feet): the attitude is
learnt, the position not. With a foot lifted nothing is learnt, and what was learnt is held
constant, for two reasons. A lifted foot may push on something (a wall, a box, a button): the
trunk's error then holds that push's reaction, which is not a load. And the feed-forward is an
acceleration the trunk does not make: the lifted leg's torques carry their share of it, which the
joint-torque force estimate reads as a force on that foot (about the leg's mass times the
feed-forward). Held constant, that reading is a constant offset, which a guarded touch removes
with the bias it takes at its start; learning on would move it during the approach and feel a
touch that is not there. What has been learnt is kept, not reset (the payload is still there).
"""

import dataclasses

import numpy as np
from pydrake.systems.framework import BasicVector, Context, DiscreteValues

from pedi_drake.control import references
from pedi_drake.estimation.base_state import BASE_STATE_SIZE
from pedi_drake.leaf_system import LeafSystemWithoutWitnesses
from pedi_drake.vector3 import orientation_error_W, rotation_matrix_wxyz

# A trunk lower than this [m] may be resting on the ground (a Go1 lying on its folded legs holds
# its trunk at 0.09-0.12 m); it is carried by its legs only above.
CARRIED_HEIGHT = 0.12

# Slices of the learnt state: the linear (b) and angular (beta) feed-forward, world frame.
LINEAR = slice(0, 3)
ANGULAR = slice(3, 6)


@dataclasses.dataclass
class TrunkLoadCompensationConfig:
    """Integral action on the trunk's position and attitude tracking (scenario `trunk_load_compensation:`)."""

    # On: the compensator stands between the mission's trunk reference and the controller. Off by
    # default: its feed-forward is an acceleration, and with a foot lifted the joint-torque force
    # estimate reads the lifted leg's share of it as a force on the foot (a guarded touch against
    # the MuJoCo Go1 felt 3 N with nothing there); see the module docstring.
    enabled: bool = False
    # Integral gain of the position error [1/s^3]: b' = ki (p_ref - p).
    position_gain: float = 200.0
    # Integral gain of the attitude error [1/s^3]: beta' = ki_R rot(R_ref R^T).
    orientation_gain: float = 300.0
    # Largest learnt linear feed-forward per axis, x, y, z [m/s^2]: the z bound carries the
    # controllers' model's own weight once more (motors at half their rating, or a 13 kg load);
    # sideways a third of it, a load 5 cm off a 13 kg trunk needs far less.
    max_linear: list[float] = dataclasses.field(default_factory=lambda: [3.0, 3.0, 10.0])
    # Largest learnt angular feed-forward per axis [rad/s^2]: a pair of legs at 60 % of their
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


class TrunkLoadCompensator(LeafSystemWithoutWitnesses):
    """The mission's trunk reference with the learnt feed-forward of the unmodelled load added.

    Inputs: body_reference (19, pedi_drake.control.references), base_state (13, the estimate),
    contact_set (4 feet, then the prong tips). Output: body_reference (19), the input with b
    added to its acceleration and beta to its angular acceleration. State: (b, beta) [m/s^2,
    rad/s^2], updated every `period` [s] (the controller's).
    """

    def __init__(self, config: TrunkLoadCompensationConfig, period: float, num_contacts: int) -> None:
        super().__init__()
        self.config = config
        self.period = period
        self._linear_limit = np.asarray(config.max_linear, dtype=float)
        self.body_reference_port = self.DeclareVectorInputPort("body_reference", references.BODY_REFERENCE_SIZE)
        self.base_state_port = self.DeclareVectorInputPort("base_state", BASE_STATE_SIZE)
        self.contact_set_port = self.DeclareVectorInputPort("contact_set", num_contacts)
        self.learnt_state = self.DeclareDiscreteState(6)
        self.DeclarePeriodicDiscreteUpdateEvent(period, 0.0, self._learn)
        # The same update on demand (CalcForcedDiscreteVariableUpdate), for tests.
        self.DeclareForcedDiscreteUpdateEvent(self._learn)
        self.DeclareVectorOutputPort(
            "body_reference",
            references.BODY_REFERENCE_SIZE,
            self._compensated,
            {self.input_port_ticket(self.body_reference_port.get_index()), self.xd_ticket()},
        )
        self.DeclareStateOutputPort("learnt", self.learnt_state)

    def learning(self, context: Context) -> tuple[bool, bool]:
        """(position, attitude): which of the trunk's tracking errors measure the load now."""
        base = self.base_state_port.Eval(context)
        contact_set = self.contact_set_port.Eval(context)
        standing = bool(np.all(contact_set[:4] >= 0.5))
        carried = self.config.enabled and base[6] > CARRIED_HEIGHT and standing
        on_prongs = bool(np.any(contact_set[4:] >= 0.5))
        return carried and not on_prongs, carried

    def _learn(self, context: Context, discrete_state: DiscreteValues) -> None:
        c = self.config
        position, attitude = self.learning(context)
        if not attitude:
            return
        body = self.body_reference_port.Eval(context)
        base = self.base_state_port.Eval(context)
        if not (np.all(np.isfinite(body)) and np.all(np.isfinite(base))):
            return  # the controller refuses the tick; nothing to learn from it
        learnt = discrete_state.get_mutable_value(self.learnt_state)
        if position:
            position_error = body[0:3] - base[4:7]
            learnt[LINEAR] = np.clip(
                learnt[LINEAR] + c.position_gain * self.period * position_error, -self._linear_limit, self._linear_limit
            )
        attitude_error = orientation_error_W(rotation_matrix_wxyz(body[3:7]), rotation_matrix_wxyz(base[0:4]))
        learnt[ANGULAR] = np.clip(
            learnt[ANGULAR] + c.orientation_gain * self.period * attitude_error, -c.max_angular, c.max_angular
        )

    def _compensated(self, context: Context, output: BasicVector) -> None:
        body = self.body_reference_port.Eval(context).copy()
        learnt = context.get_discrete_state(self.learnt_state).value()
        body[10:13] += learnt[LINEAR]
        body[16:19] += learnt[ANGULAR]
        output.SetFromVector(body)
