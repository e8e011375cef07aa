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

    def problems(self) -> list[tuple[str, str]]:
        """(field, problem) for every invalid value; empty when valid."""
        found = []
        if not (isinstance(self.max_lps, int) and self.max_lps >= 1):
            found.append(("max_lps", f"must be an integer >= 1, got {self.max_lps!r}"))
        if not (math.isfinite(self.offset) and self.offset >= 0.0):
            found.append(("offset", f"must be a finite number >= 0 s, got {self.offset}"))
        return found
