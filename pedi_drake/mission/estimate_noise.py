"""The noise of a foot force estimate, measured as the mission samples it, and the margin a force
bound keeps below its limit because of it.

A bound that stops the foot where the *estimated* force reaches a limit holds the estimate there,
noise and all; the true force, shaken by the same sensor noise through the controller, then rides
about the limit and crosses it by a few standard deviations at its peaks. So the bound acts a
margin below the limit: NOISE_SIGMAS times the estimate's standard deviation per axis, measured
from the second differences of its samples at the mission updates, f[k] - 2 f[k-1] + f[k-2]: a
force changing at a steady rate (a press) leaves none, and for independent samples of noise sigma
per axis each axis's second difference has the standard deviation sqrt(6) sigma. The deviation is
taken from the median of their magnitudes over the last NOISE_WINDOW updates, so the few updates
of an impact or of a contact made or broken, whose second differences are the force's own, do
not count as noise. An estimate with no noise keeps the whole limit.

Plain state updated once per mission update (the teleop_foot runner holds one per phase).
"""

import math

import numpy as np

# Standard deviations of the estimate kept between the bound's stop and the limit: the largest of
# a few thousand samples of a normal distribution (a held press at the mission's 100 Hz) lies
# within about 3.5 sigma; the true force's noise is about the estimate's.
NOISE_SIGMAS = 4.0
# Mission updates the median is taken over (1 s at the mission's 100 Hz) ...
NOISE_WINDOW = 100
# ... and how many it needs first: until then (the phase's first quarter second, the foot free
# where its lift left it) the noise counts as none and the bound keeps the whole limit.
NOISE_MIN_SAMPLES = 25
# The median of |x| for x normal with standard deviation s is this times s.
_MEDIAN_OF_MAGNITUDE = 0.6744897501960817


class EstimateNoise:
    """The standard deviation per axis [N] of a 3-D force estimate sampled at updates (robust)."""

    def __init__(self) -> None:
        self._previous: list[np.ndarray] = []  # the last two finite samples, oldest first
        self._differences = np.zeros(3 * NOISE_WINDOW)  # |second differences| per axis, a ring
        self._count = 0  # second differences taken (the ring holds the newest NOISE_WINDOW)

    def update(self, force: np.ndarray, dt: float) -> None:
        """Takes the estimate `force` [N] sampled `dt` [s] after the previous one."""
        force = np.asarray(force, float)
        if not np.all(np.isfinite(force)) or dt <= 0.0:
            return
        if len(self._previous) == 2:
            older, old = self._previous
            slot = 3 * (self._count % NOISE_WINDOW)
            self._differences[slot : slot + 3] = np.abs(force - 2.0 * old + older)
            self._count += 1
        self._previous = [*self._previous[-1:], force.copy()]

    @property
    def sigma(self) -> float:
        """The estimate's standard deviation per axis [N] (0 before NOISE_MIN_SAMPLES second
        differences)."""
        if self._count < NOISE_MIN_SAMPLES:
            return 0.0
        taken = self._differences[: 3 * min(self._count, NOISE_WINDOW)]
        return float(np.median(taken)) / (_MEDIAN_OF_MAGNITUDE * math.sqrt(6.0))

    def bounded_limit(self, limit: float) -> float:
        """Where a bound on the estimate stops for a true force under `limit` [N]: NOISE_SIGMAS
        sigma below it, never below 0."""
        return max(limit - NOISE_SIGMAS * self.sigma, 0.0)
