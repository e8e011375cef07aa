"""LogHold: a sample-and-hold in front of a logger, so a logged signal is computed once a tick.

Drake dispatches a tick's publish events (VectorLogSink) after its discrete updates, at the next
plant state; a sensor evaluated there is computed a second time (the first was for the estimator,
at the tick's state). LogHold samples its input with the tick's updates instead, so the logger
records what the estimator read, from the same cache entry. Unlike Drake's ZeroOrderHold it also
latches its input at initialisation, so the t = 0 sample is the initial value, not zeros.
"""

import numpy as np
from pydrake.systems.framework import Context, DiscreteValues

from pedi_drake.leaf_system import LeafSystemWithoutWitnesses


class LogHold(LeafSystemWithoutWitnesses):
    """input `u` (size) -> output `y` (size): u sampled every `period` [s] and at initialisation."""

    def __init__(self, size: int, period: float):
        super().__init__()
        self._input = self.DeclareVectorInputPort("u", size)
        self._state = self.DeclareDiscreteState(np.zeros(size))
        self.DeclareInitializationDiscreteUpdateEvent(self._sample)
        self.DeclarePeriodicDiscreteUpdateEvent(period, 0.0, self._sample)
        self.DeclareStateOutputPort("y", self._state)

    def _sample(self, context: Context, discrete_state: DiscreteValues) -> None:
        discrete_state.get_mutable_vector(self._state).SetFromVector(self._input.Eval(context))
