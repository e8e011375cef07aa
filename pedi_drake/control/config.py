"""Settings of the whole-body controller, loaded as part of the Scenario (`whole_body:`).

Owned by the whole-body controller; the Scenario only holds an instance.
"""

import dataclasses


@dataclasses.dataclass
class WholeBodyControllerConfig:
    """Whole-body QP controller settings."""

    # Control period [s] (500 Hz default; 1 kHz must also work).
    period: float = 0.002
