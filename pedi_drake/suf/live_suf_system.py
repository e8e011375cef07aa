"""LiveSufSystem: the live SUF of the robot's stance (pedi_drake.suf.live) as a periodic update.

Inputs: `base_state` (the estimate), `position_measured` (12), `contact_set` (the mission's: four
feet, then prong tips) and `suf_request` (the mission's: [leg index or -1, direction (3)]: the
lifted foot to analyse and the direction to report the SUF along). Output: `suf`, the vector of
pedi_drake.suf.live (a state output port: no computation when the mission, the operator feedback
or the log reads it).

Where it runs, and why: its own periodic update at the mission manager's period, offset from the
manager's update (by default 4 ms of a 10 ms period, a multiple of the 2 ms control tick), so the
two never share a control tick: the manager reads the SUF of an update 6 ms old. The update is
one compiled call, warm-started from the previous update's vertices (its Context's abstract
state), with a fixed budget of LPs, so its worst case is bounded by the budget whatever the
stance did; an update that runs out of budget uses the single-direction SUF and counts itself
in the vector's `fallbacks`. No thread and no wall clock: the same inputs give the same SUF, so
a simulation is as deterministic with it as without it.
"""

import dataclasses

import numpy as np
from pydrake.common.value import AbstractValue
from pydrake.systems.framework import LeafSystem

from pedi_drake.estimation.base_state import BASE_STATE_SIZE
from pedi_drake.prongs import ProngDesign
from pedi_drake.suf.live import DEFAULT_MAX_LPS, LiveSuf, idle_vector
from pedi_drake.suf.warm_projection import WarmStart

# [leg index (Unitree order) or -1, direction (3), world]
SUF_REQUEST_SIZE = 4


def suf_request_vector(leg: int, direction: np.ndarray | None) -> np.ndarray:
    """The `suf_request` vector: `leg` (-1: none) and the direction to report along (None: zero,
    meaning the last worst direction)."""
    x = np.zeros(SUF_REQUEST_SIZE)
    x[0] = leg
    if direction is not None:
        x[1:4] = direction
    return x


@dataclasses.dataclass(frozen=True)
class _Memory:
    """The abstract state: the warm start of the next update (None: the next one is cold)."""

    warm: WarmStart | None = None

    def __deepcopy__(self, memo) -> "_Memory":
        return self  # a value: an update stores a new one


class LiveSufSystem(LeafSystem):
    """The live SUF (see the module docstring)."""

    def __init__(
        self,
        prongs: ProngDesign | None,
        *,
        mu: float,
        period: float,
        offset: float,
        max_lps: int = DEFAULT_MAX_LPS,
    ):
        """
        Args:
            prongs: the robot's prongs (their tips are contacts when the contact set loads them).
            mu: the ground's friction coefficient [-] (the contacts' pyramids).
            period: update period [s]; offset: the first update's time [s].
            max_lps: the LP budget of one update (see pedi_drake.suf.live).
        """
        super().__init__()
        self._live = LiveSuf(prongs, mu=mu, max_lps=max_lps)
        self._base_state = self.DeclareVectorInputPort("base_state", BASE_STATE_SIZE)
        self._position = self.DeclareVectorInputPort("position_measured", 12)
        self._contacts = self.DeclareVectorInputPort("contact_set", self._live.num_contacts)
        self._request = self.DeclareVectorInputPort("suf_request", SUF_REQUEST_SIZE)
        self._memory = self.DeclareAbstractState(AbstractValue.Make(_Memory()))
        self._suf = self.DeclareDiscreteState(idle_vector())
        self.DeclarePeriodicUnrestrictedUpdateEvent(period, offset, self._update)
        self.DeclareStateOutputPort("suf", self._suf)

    def _update(self, context, state) -> None:
        request = np.asarray(self._request.Eval(context))
        previous = context.get_discrete_state(self._suf).get_value()
        leg = int(round(request[0]))
        if leg < 0:
            state.get_mutable_discrete_state(self._suf).SetFromVector(idle_vector(previous))
            return
        memory = context.get_abstract_state(self._memory).get_value()
        vector, warm = self._live.update(
            memory.warm,
            previous,
            np.asarray(self._base_state.Eval(context)),
            np.asarray(self._position.Eval(context)),
            np.asarray(self._contacts.Eval(context)),
            leg,
            request[1:4],
        )
        state.get_mutable_discrete_state(self._suf).SetFromVector(vector)
        state.get_mutable_abstract_state(self._memory).set_value(_Memory(warm))
