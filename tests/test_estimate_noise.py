"""The force estimate's noise as the teleoperated foot's force bound measures it, and its margin."""

import numpy as np
import pytest

from pedi_drake.mission.estimate_noise import NOISE_SIGMAS, EstimateNoise

DT = 0.01  # [s] the mission's update period


@pytest.mark.parametrize("sigma", [0.2, 0.5, 1.5])
def test_the_measured_sigma_is_the_estimates_per_axis_noise_under_a_slow_ramp(sigma):
    rng = np.random.default_rng(7)
    noise = EstimateNoise()
    # A press rising 10 N/s along z: the force's own change is well under the noise per update.
    for k in range(500):
        noise.update(np.array([1.0, -0.5, 10.0 * k * DT]) + rng.normal(0.0, sigma, 3), DT)
    assert noise.sigma == pytest.approx(sigma, rel=0.15)
    assert noise.bounded_limit(15.0) == pytest.approx(15.0 - NOISE_SIGMAS * noise.sigma)


def test_an_estimate_without_noise_keeps_the_whole_limit_and_the_margin_never_goes_below_zero():
    noise = EstimateNoise()
    for k in range(100):
        noise.update(np.array([0.0, 0.0, 0.05 * k]), DT)
    assert noise.sigma < 1e-9
    assert noise.bounded_limit(15.0) == pytest.approx(15.0)
    loud = EstimateNoise()
    rng = np.random.default_rng(3)
    for _ in range(100):
        loud.update(rng.normal(0.0, 10.0, 3), DT)
    assert loud.bounded_limit(15.0) == 0.0


def test_a_nan_sample_is_skipped_and_impacts_are_not_taken_for_noise():
    rng = np.random.default_rng(5)
    noise = EstimateNoise()
    for _ in range(200):
        noise.update(rng.normal(0.0, 0.3, 3), DT)
    noise.update(np.full(3, np.nan), DT)
    assert np.isfinite(noise.sigma)
    quiet = noise.sigma
    # The foot strikes a wall every half second: 8 N jumps in 10 ms, and off again.
    for k in range(400):
        on = (k // 50) % 2 == 1
        noise.update(np.array([0.0, 0.0, 8.0 if on else 0.0]) + rng.normal(0.0, 0.3, 3), DT)
        assert noise.sigma == pytest.approx(quiet, rel=0.3)
