"""Prong design optimisation (paper 003, Eq. 7): the stance and trunk height that maximise the SUF.

    max over (x_f, y_f, b_z) of SUF(x_f, y_f, b_z)

with the feet placed symmetrically at (+-x_f, +-y_f), the trunk level at b_z, the prongs (two, on
the trunk's centre line) as long as the trunk height, and the end-effector foot at a fixed point
in the trunk frame. `best_feet` optimises the feet at one height (Nelder-Mead from a grid's best
point), `height_sweep` does it over heights with and without prongs (Fig. 3), `optimise_design`
adds the height (Eq. 7). The affine method is the default objective, as in the paper: it is
conservative and fast (`python -m pedi_drake.benchmarks.suf` times every method).
"""

import dataclasses

import numpy as np
from scipy.optimize import minimize

from pedi_drake.exceptions import SufError
from pedi_drake.suf.methods import smallest_unrejectable_force
from pedi_drake.suf.stances import Go1Stance, stance_problem, with_prongs_at_height

FEET_X_RANGE = (0.12, 0.28)  # [m]
FEET_Y_RANGE = (0.08, 0.20)  # [m]


@dataclasses.dataclass
class DesignPoint:
    """One evaluated design."""

    trunk_height: float  # [m]
    feet_x: float  # [m]
    feet_y: float  # [m]
    prongs: bool
    suf: float  # [N]


def stance_for(height: float, feet_x: float, feet_y: float, prongs: bool, end_effector_B=None) -> Go1Stance:
    """Three feet (FL, RR, RL) and, with `prongs`, both prong tips; the FR foot is the end-effector."""
    stance = Go1Stance(
        height,
        feet_x,
        feet_y,
        ("FL", "RR", "RL"),
        "FR",
        end_effector_B,
        trunk_xy=(-feet_x / 3, feet_y / 3),
    )
    if prongs:
        stance = with_prongs_at_height(stance)
        stance.contacts = stance.contacts + ("prong0", "prong1")
    return stance


def evaluate(height, feet_x, feet_y, prongs, end_effector_B=None, method: str = "affine") -> float:
    """The SUF [N] of a design; 0 when the stance is out of reach or cannot stand."""
    try:
        problem = stance_problem(stance_for(height, feet_x, feet_y, prongs, end_effector_B))
        return smallest_unrejectable_force(problem, method).value
    except SufError:
        return 0.0


def best_feet(height: float, prongs: bool, end_effector_B=None, method: str = "affine", grid: int = 4) -> DesignPoint:
    """The feet placement maximising the SUF at `height` [m]."""
    xs = np.linspace(*FEET_X_RANGE, grid)
    ys = np.linspace(*FEET_Y_RANGE, grid)
    scores = [(evaluate(height, x, y, prongs, end_effector_B, method), x, y) for x in xs for y in ys]
    best_suf, x0, y0 = max(scores)

    def cost(v):
        x, y = v
        if not (FEET_X_RANGE[0] <= x <= FEET_X_RANGE[1] and FEET_Y_RANGE[0] <= y <= FEET_Y_RANGE[1]):
            return 0.0
        return -evaluate(height, x, y, prongs, end_effector_B, method)

    step = [(FEET_X_RANGE[1] - FEET_X_RANGE[0]) / grid, (FEET_Y_RANGE[1] - FEET_Y_RANGE[0]) / grid]
    simplex = np.array([[x0, y0], [x0 + step[0] / 2, y0], [x0, y0 + step[1] / 2]])
    result = minimize(
        cost,
        [x0, y0],
        method="Nelder-Mead",
        options={"initial_simplex": simplex, "xatol": 2e-3, "fatol": 0.05, "maxfev": 60},
    )
    if -result.fun > best_suf:
        best_suf, (x0, y0) = -result.fun, result.x
    return DesignPoint(height, float(x0), float(y0), prongs, float(best_suf))


def height_sweep(heights, end_effector_B=None, method: str = "affine") -> list[dict]:
    """Fig. 3: the best SUF at each trunk height, with and without prongs, and the prongs' benefit [%]."""
    rows = []
    for height in heights:
        without = best_feet(height, False, end_effector_B, method)
        with_prongs = best_feet(height, True, end_effector_B, method)
        benefit = 100.0 * (with_prongs.suf / without.suf - 1.0) if without.suf > 0 else float("inf")
        rows.append(
            {
                "height": float(height),
                "without": dataclasses.asdict(without),
                "with_prongs": dataclasses.asdict(with_prongs),
                "benefit_percent": benefit,
            }
        )
    return rows


def optimise_design(heights, prongs: bool, end_effector_B=None, method: str = "affine") -> DesignPoint:
    """Eq. 7: the best (x_f, y_f, b_z) over the given heights (each with its best feet)."""
    return max((best_feet(h, prongs, end_effector_B, method) for h in heights), key=lambda d: d.suf)
