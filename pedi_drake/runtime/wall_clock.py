"""WallClock: the host's wall-clock time as a signal, to align logs of separate processes."""

import time

from pydrake.systems.framework import BasicVector

from pedi_drake.leaf_system import LeafSystemWithoutWitnesses


class WallClock(LeafSystemWithoutWitnesses):
    """Output `wall_clock` (1): time.time() [s since the epoch] when evaluated.

    Deliberately not a function of the Context: it is for logging only (a VectorLogSink samples it
    with the signals it is to be aligned with), never an input of a controller.
    """

    def __init__(self) -> None:
        super().__init__()
        self.clock = self.DeclareVectorOutputPort("wall_clock", 1, self._calc)

    def _calc(self, context, output: BasicVector) -> None:
        output.SetAtIndex(0, time.time())
