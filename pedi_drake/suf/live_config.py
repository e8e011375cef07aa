"""Settings of the live SUF (the Scenario field `live_suf:`; pedi_drake.suf.live_suf_system)."""

import dataclasses
import math


@dataclasses.dataclass
class LiveSufConfig:
    """Whether a mission run computes the live SUF of its lifted-leg stances, and its budget."""

    # Compute it (the balance bound of teleop_foot and press phases needs it).
    enabled: bool = True
    # LPs one update may solve; beyond them that update uses the single-direction SUF [-].
    max_lps: int = 60
    # Time of the first update [s]: it then runs at the mission manager's period, this long after
    # each of the manager's updates, so that the two never share a control tick (a multiple of the
    # 2 ms control period, below the manager's 10 ms).
    offset: float = 0.004
    # Work of the update one control tick may do, in LPs (a vertex or facet check and a point
    # joined to the hull count as fractions of one; pedi_drake.suf.warm_projection): an update
    # that needs more goes on in the next control ticks, the manager's excepted; a budget no
    # update reaches (1.0e+9) does every update in its start's tick [LP].
    tick_work: float = 15.0

    def problems(self) -> list[tuple[str, str]]:
        """(field, problem) for every invalid value; empty when valid."""
        found = []
        if not (isinstance(self.max_lps, int) and self.max_lps >= 1):
            found.append(("max_lps", f"must be an integer >= 1, got {self.max_lps!r}"))
        if not (math.isfinite(self.offset) and self.offset >= 0.0):
            found.append(("offset", f"must be a finite number >= 0 s, got {self.offset}"))
        if isinstance(self.tick_work, bool) or not (isinstance(self.tick_work, int | float) and self.tick_work > 0.0):
            found.append(("tick_work", f"must be a number > 0 LPs, got {self.tick_work!r}"))
        return found
