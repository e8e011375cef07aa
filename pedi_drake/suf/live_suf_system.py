"""LiveSufSystem: the live SUF of the robot's stance (pedi_drake.suf.live) as periodic updates
spread over the control ticks.

Inputs: `base_state` (the estimate), `position_measured` (12), `contact_set` (the mission's: four
feet, then prong tips) and `suf_request` (the mission's: [leg index or -1, direction (3)]: the
lifted foot to analyse and the direction to report the SUF along). Output: `suf`, the vector of
pedi_drake.suf.live (a state output port: no computation when the mission, the operator feedback
or the log reads it).

When it runs: an update starts at the mission manager's period, offset from the manager's update
(by default 4 ms of a 10 ms period), reading its inputs then. Its work (the rows, then the
warm-started exact projection step by step, then the vector) is done in slices of at most
`tick_work` (in LPs; pedi_drake.suf.warm_projection.project_within charges each step) on the
control ticks from its start on, skipping the manager's ticks (`slot_at`: at 500 Hz, 4, 6, 8 and
12 ms of each 10 ms), and the vector is published at the end of the slice that finishes it;
the next update starts at the first start slot after that. A slice is cut at a step's end, never
inside one, so a tick pays at most `tick_work` plus one step (an LP and a point joined to the
hull; a fallback's finishing step, its two single-direction LPs) plus the slice's fixed cost. A
`tick_work` no update reaches (1.0e+9) does every update in its start's tick.

How much older the SUF is: the manager reads it only at its own updates, so an update finished
on a slot before the manager's next update (4, 6 or 8 ms) is read exactly as old as before (6 ms:
the inputs of 4 ms; the vector's `stance_time` says when they were read); one that takes a slot
more is read a period (10 ms) later, and the update after it starts a period late.

The updates are discrete updates, and the update under way lives in a workspace
(pedi_drake.suf.live.LiveSufWorkspace) that is abstract state of the Context, allocated once and
changed in place by them: nothing else reads it, and copying a Context copies it. An unrestricted
update would copy the workspace twice per event (pydrake deep-copies abstract state for it) and
makes the simulator look up every system's witness functions again, a cost of its own on top of
the update's (pedi_drake.benchmarks.suf_offload --replay, `unrestricted` against `one_tick`).

Why slices and not a worker thread: the work is counted, not timed, so a simulation gives the
same SUF sequence at any machine speed, and the tick's share is bounded whatever the operating
system does (a fraction of what the whole update in one tick costs).
A thread (the kernels release the GIL) costs the tick less on average, only the hand-over, but
not a bounded amount: the tick that collects the result waits for the worker, or for the GIL its
Python holds, even with a core to spare; on a 2-core machine it shares the loop's core (the
simulator bridge has the other), under SCHED_FIFO (`go1_driver.realtime_priority`) it would run
at the loop's priority, and its result is a period older. pedi_drake.benchmarks.suf_offload
measures the designs side by side.
"""

import math

import numpy as np
from pydrake.common.value import AbstractValue

from pedi_drake.estimation.base_state import BASE_STATE_SIZE
from pedi_drake.leaf_system import LeafSystemWithoutWitnesses
from pedi_drake.prongs import ProngDesign
from pedi_drake.suf.live import DEFAULT_MAX_LPS, LiveSuf, idle_vector

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


# [s] how close two times must be to count as the same instant (the periods are multiples of 0.5 ms).
_SAME_TIME = 1e-9


def slot_at(t: float, period: float, offset: float, tick: float) -> str | None:
    """What the control tick at `t` [s] is to the live SUF: "start" (the first tick at or after
    `offset` + k `period`: an update may start), "slice" (an update under way goes on) or None
    (before the first start, or a tick at a multiple of `period`: the mission manager's update)."""
    if abs(t / period - round(t / period)) < _SAME_TIME / period:
        return None
    since = t - offset
    if since < -_SAME_TIME:
        return None
    phase = since - math.floor(since / period + _SAME_TIME / period) * period
    return "start" if phase < tick - _SAME_TIME else "slice"


class LiveSufSystem(LeafSystemWithoutWitnesses):
    """The live SUF (see the module docstring)."""

    def __init__(
        self,
        prongs: ProngDesign | None,
        *,
        mu: float,
        period: float,
        offset: float,
        tick: float,
        tick_work: float,
        max_lps: int = DEFAULT_MAX_LPS,
    ):
        """
        Args:
            prongs: the robot's prongs (their tips are contacts when the contact set loads them).
            mu: the ground's friction coefficient [-] (the contacts' pyramids).
            period: update period [s]; offset: the first update's time [s].
            tick: the control period [s]: the update's slices run on the control ticks after
                its start.
            tick_work: the work one control tick may do [LP] (see the module docstring).
            max_lps: the LP budget of one update (see pedi_drake.suf.live).
        """
        super().__init__()
        self._live = LiveSuf(prongs, mu=mu, max_lps=max_lps)
        self._tick_work = float(tick_work)
        self._base_state = self.DeclareVectorInputPort("base_state", BASE_STATE_SIZE)
        self._position = self.DeclareVectorInputPort("position_measured", 12)
        self._contacts = self.DeclareVectorInputPort("contact_set", self._live.num_contacts)
        self._request = self.DeclareVectorInputPort("suf_request", SUF_REQUEST_SIZE)
        # The workspace of the update under way and of the warm start (a LiveSufWorkspace): see
        # the module docstring for why the discrete updates change it in place.
        self._workspace = self.DeclareAbstractState(AbstractValue.Make(self._live.new_workspace()))
        self._suf = self.DeclareDiscreteState(idle_vector())
        # One event on the control ticks themselves (period `tick`, offset 0: the very times of the
        # controller's events): events of their own, at offset + k period plus some ticks, would
        # land a rounding error away from the control tick in about a third of the periods, and
        # the simulator would take a step of its own for them.
        self._schedule = (period, offset, tick)
        self.DeclarePeriodicDiscreteUpdateEvent(tick, 0.0, self._on_tick)
        self.DeclareStateOutputPort("suf", self._suf)

    def _on_tick(self, context, discrete_state) -> None:
        """One control tick's share: the update under way goes on, or, at a start slot with none
        under way, a new one starts (or the idle vector, with no lifted foot)."""
        slot = slot_at(context.get_time(), *self._schedule)
        if slot is None:
            return
        work = context.get_abstract_state(self._workspace).get_value()
        if not work.under_way:
            if slot != "start":
                return
            previous = context.get_discrete_state(self._suf).get_value()
            if not self._start_update(context, work, previous):
                discrete_state.get_mutable_vector(self._suf).SetFromVector(idle_vector(previous))
                return
        self._live.advance(work, self._tick_work)
        if not work.under_way:
            discrete_state.get_mutable_vector(self._suf).SetFromVector(work.result)

    def _start_update(self, context, work, previous: np.ndarray) -> bool:
        """Starts an update in `work` for the lifted foot `suf_request` names, of the stance the
        inputs give now; False (nothing started) when no foot is lifted."""
        request = np.asarray(self._request.Eval(context))
        leg = int(round(request[0]))
        if leg < 0:
            return False
        self._live.start(
            work,
            previous,
            np.asarray(self._base_state.Eval(context)),
            np.asarray(self._position.Eval(context)),
            np.asarray(self._contacts.Eval(context)),
            leg,
            request[1:4],
            stance_time=context.get_time(),
        )
        return True
