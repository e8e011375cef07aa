"""What a press tells of the obstacle it pressed: rigid or soft, fixed or mobile (paper 000, Fig. 5).

A press drives the foot along a direction at a set speed until the foot force (an estimate, its
bias removed) or the displacement reaches its limit, and records the force against the
displacement (`PressRunner`). Two features of that curve classify the obstacle:

- **rigid or soft**: how steeply the force rises once the foot meets it, the slope between the
  first displacements where the force reaches 25 % and 75 % of its peak. A rigid obstacle loads
  the foot over millimetres (the foot's and the leg's own compliance), a soft one over
  centimetres; the free travel before contact does not count.
- **fixed or mobile**: whether the obstacle gave way. Past the rise, a fixed obstacle's force
  keeps growing with the displacement; a mobile one's levels off at its sliding friction while
  the foot keeps advancing. The press is mobile when it ended by displacement, the foot
  advanced at least MOBILE_TRAVEL beyond the rise, and the force grew over that travel by less
  than LEVELLED_SHARE of what the rise's slope predicts.
"""

import dataclasses

import numpy as np

RIGID_STIFFNESS = 1500.0  # [N/m] a force rising more steeply than this is a rigid obstacle
CONTACT_FORCE = 2.0  # [N] a press whose force never reached this touched nothing
MOBILE_TRAVEL = 0.01  # [m] travel beyond the rise over which a mobile obstacle shows it gave way
LEVELLED_SHARE = 0.3  # [-] of the force growth the rise predicts, below which the force levelled


@dataclasses.dataclass(frozen=True)
class ObstacleResponse:
    """The classification of one press from its force-displacement curve."""

    peak_force_n: float  # the largest force along the press [N]
    rise_stiffness_n_per_m: float  # slope of the force's rise, 25 % to 75 % of the peak [N/m]
    travel_beyond_rise_m: float  # displacement from where the force first reached 75 % of its peak [m]
    force_growth_n: float  # force gained over that travel [N]
    stiffness_class: str  # "rigid", "soft" or "nothing" (no contact felt)
    mobility: str  # "fixed", "mobile" or "nothing"


def _first_at_least(values: np.ndarray, level: float) -> int:
    return int(np.argmax(values >= level))


def classify_press(displacement_m: np.ndarray, force_n: np.ndarray, stopped_by: str) -> ObstacleResponse:
    """Classifies the obstacle a press met from its curve: `displacement_m` along the press [m] and
    `force_n` the force against it [N], sample by sample, and what stopped the press ("force",
    "displacement" or "balance")."""
    displacement_m, force_n = np.asarray(displacement_m, float), np.asarray(force_n, float)
    if len(displacement_m) == 0 or len(displacement_m) != len(force_n):
        raise ValueError(f"a press curve needs matching samples, got {len(displacement_m)} and {len(force_n)}")
    peak = float(np.max(force_n))
    if peak < CONTACT_FORCE:
        return ObstacleResponse(peak, 0.0, 0.0, 0.0, "nothing", "nothing")
    low, high = _first_at_least(force_n, 0.25 * peak), _first_at_least(force_n, 0.75 * peak)
    # A rise within one sample is as steep as the samples can tell: a tenth of a millimetre.
    rise_length = max(displacement_m[high] - displacement_m[low], 1e-4)
    rise_stiffness = 0.5 * peak / rise_length
    travel = float(displacement_m[-1] - displacement_m[high])
    growth = float(force_n[-1] - force_n[high])
    levelled = growth < LEVELLED_SHARE * rise_stiffness * travel
    mobile = stopped_by == "displacement" and travel >= MOBILE_TRAVEL and levelled
    return ObstacleResponse(
        peak_force_n=peak,
        rise_stiffness_n_per_m=float(rise_stiffness),
        travel_beyond_rise_m=travel,
        force_growth_n=growth,
        stiffness_class="rigid" if rise_stiffness > RIGID_STIFFNESS else "soft",
        mobility="mobile" if mobile else "fixed",
    )
