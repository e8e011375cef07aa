"""Quintic references (Eq. 2): boundary conditions, derivatives, SO(3) interpolation."""

import numpy as np
import pytest
from pydrake.math import RollPitchYaw, RotationMatrix

from pedi_drake.exceptions import PediError
from pedi_drake.trajectory import (
    PiecewiseQuintic,
    QuinticOrientationSegment,
    QuinticSegment,
    quintic_coefficients,
    smooth_start_time_law,
)


def test_quintic_matches_eq2_polynomial():
    x0, x1, T = 0.3, -0.7, 1.7
    a = quintic_coefficients(x0, x1, T)
    segment = QuinticSegment([x0], [x1], 0.0, T)
    for t in np.linspace(0.0, T, 11):
        powers = np.array([t**k for k in range(6)])
        dpowers = np.array([k * t ** max(k - 1, 0) for k in range(6)])
        ddpowers = np.array([k * (k - 1) * t ** max(k - 2, 0) for k in range(6)])
        sample = segment.sample(t)
        assert sample.position[0] == pytest.approx(a @ powers, abs=1e-12)
        assert sample.velocity[0] == pytest.approx(a @ dpowers, abs=1e-12)
        assert sample.acceleration[0] == pytest.approx(a @ ddpowers, abs=1e-12)


def test_quintic_rest_at_both_ends_and_holds_outside():
    segment = QuinticSegment([0.0, 1.0, 2.0], [1.0, -1.0, 2.5], 2.0, 0.5)
    for t, expected in ((1.0, segment.start), (2.0, segment.start), (2.5, segment.end), (9.0, segment.end)):
        sample = segment.sample(t)
        np.testing.assert_allclose(sample.position, expected, atol=1e-12)
        np.testing.assert_allclose(sample.velocity, 0.0, atol=1e-12)
        np.testing.assert_allclose(sample.acceleration, 0.0, atol=1e-12)


def test_quintic_derivatives_match_finite_differences():
    segment = QuinticSegment([0.1, -0.2], [0.4, 0.3], 0.3, 1.2)
    h = 1e-6
    for t in np.linspace(0.35, 1.45, 9):
        dp = (segment.sample(t + h).position - segment.sample(t - h).position) / (2 * h)
        dv = (segment.sample(t + h).velocity - segment.sample(t - h).velocity) / (2 * h)
        np.testing.assert_allclose(segment.sample(t).velocity, dp, atol=1e-6)
        np.testing.assert_allclose(segment.sample(t).acceleration, dv, atol=1e-5)


def test_orientation_segment_endpoints_and_angular_velocity():
    R0 = RotationMatrix(RollPitchYaw(0.1, -0.2, 0.3))
    R1 = RotationMatrix(RollPitchYaw(-0.3, 0.25, 1.0))
    segment = QuinticOrientationSegment(R0, R1, 0.0, 2.0)
    np.testing.assert_allclose(segment.sample(0.0).rotation.matrix(), R0.matrix(), atol=1e-12)
    np.testing.assert_allclose(segment.sample(2.0).rotation.matrix(), R1.matrix(), atol=1e-9)
    h = 1e-6
    for t in (0.3, 1.0, 1.7):
        Rm, Rp = segment.sample(t - h).rotation.matrix(), segment.sample(t + h).rotation.matrix()
        Rdot = (Rp - Rm) / (2 * h)
        W = Rdot @ segment.sample(t).rotation.matrix().T  # skew(w_W)
        w_fd = np.array([W[2, 1], W[0, 2], W[1, 0]])
        np.testing.assert_allclose(segment.sample(t).angular_velocity, w_fd, atol=1e-6)
        wdot_fd = (segment.sample(t + h).angular_velocity - segment.sample(t - h).angular_velocity) / (2 * h)
        np.testing.assert_allclose(segment.sample(t).angular_acceleration, wdot_fd, atol=1e-5)


def test_piecewise_passes_through_waypoints_at_rest():
    waypoints = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 2.0]])
    path = PiecewiseQuintic.through(waypoints, 1.0, [0.5, 1.0])
    np.testing.assert_allclose(path.sample(1.5).position, waypoints[1], atol=1e-12)
    np.testing.assert_allclose(path.sample(1.5).velocity, 0.0, atol=1e-12)
    np.testing.assert_allclose(path.sample(5.0).position, waypoints[2], atol=1e-12)


def test_invalid_segments_are_rejected():
    with pytest.raises(PediError):
        QuinticSegment([0.0], [1.0], 0.0, 0.0)
    with pytest.raises(PediError):
        QuinticSegment([0.0], [np.nan], 0.0, 1.0)
    with pytest.raises(PediError):
        QuinticSegment([0.0, 1.0], [1.0], 0.0, 1.0)


def test_circular_path_is_closed_at_rest_and_its_derivatives_match():
    from pedi_drake.trajectory import CircularPath

    start = np.array([0.1, -0.05, 0.28])
    path = CircularPath(start, 0.03, 1.0, 6.0, laps=2, phase=0.4)
    for t in (0.0, 1.0, 7.0, 9.0):
        sample = path.sample(t)
        np.testing.assert_allclose(sample.position, start, atol=1e-12)
        np.testing.assert_allclose(sample.velocity, 0.0, atol=1e-12)
    h = 1e-6
    for t in np.linspace(1.2, 6.8, 9):
        sample = path.sample(t)
        assert np.linalg.norm(sample.position - path.centre) == pytest.approx(0.03, abs=1e-12)
        assert sample.position[2] == pytest.approx(start[2])
        np.testing.assert_allclose(
            sample.velocity, (path.sample(t + h).position - path.sample(t - h).position) / (2 * h), atol=1e-6
        )
        np.testing.assert_allclose(
            sample.acceleration, (path.sample(t + h).velocity - path.sample(t - h).velocity) / (2 * h), atol=1e-5
        )


def test_pivoted_position_turns_about_the_pivot_and_its_derivatives_match():
    from pedi_drake.trajectory import PivotedPosition

    R0 = RotationMatrix(RollPitchYaw(0.0, 0.12, 0.0))
    R1 = RotationMatrix(RollPitchYaw(0.08, 0.2, -0.05))
    orientation = QuinticOrientationSegment(R0, R1, 0.5, 1.5)
    pivot, start = np.array([0.16, 0.0, 0.015]), np.array([0.0, 0.0, 0.17])
    path = PivotedPosition(orientation, pivot, start)
    np.testing.assert_allclose(path.sample(0.0).position, start, atol=1e-12)
    h = 1e-6
    for t in np.linspace(0.6, 1.9, 7):
        sample = path.sample(t)
        # A point of the turning body: its offset from the pivot is the start offset, turned.
        lever = orientation.sample(t).rotation.multiply(R0.inverse().multiply(start - pivot))
        np.testing.assert_allclose(sample.position, pivot + lever, atol=1e-12)
        np.testing.assert_allclose(
            sample.velocity, (path.sample(t + h).position - path.sample(t - h).position) / (2 * h), atol=1e-6
        )
        np.testing.assert_allclose(
            sample.acceleration, (path.sample(t + h).velocity - path.sample(t - h).velocity) / (2 * h), atol=1e-5
        )


def test_smooth_start_reaches_unit_speed_without_an_acceleration_step():
    t0, ramp, h = 1.0, 0.1, 1e-6
    # At rest before the start; acceleration zero at both ends of the ramp (no step in it).
    assert smooth_start_time_law(0.5, t0, ramp) == (0.0, 0.0, 0.0)
    assert smooth_start_time_law(t0 + 1e-9, t0, ramp)[2] == pytest.approx(0.0, abs=1e-6)
    assert smooth_start_time_law(t0 + ramp - 1e-9, t0, ramp)[2] == pytest.approx(0.0, abs=1e-6)
    for t in np.linspace(t0 + 0.005, t0 + 0.3, 13):
        s, sd, sdd = smooth_start_time_law(t, t0, ramp)
        assert sd == pytest.approx(
            (smooth_start_time_law(t + h, t0, ramp)[0] - smooth_start_time_law(t - h, t0, ramp)[0]) / (2 * h), abs=1e-6
        )
        assert sdd == pytest.approx(
            (smooth_start_time_law(t + h, t0, ramp)[1] - smooth_start_time_law(t - h, t0, ramp)[1]) / (2 * h), abs=1e-4
        )
    # After the ramp: unit speed, half a ramp behind a motion that started at full speed.
    assert smooth_start_time_law(t0 + 0.5, t0, ramp) == pytest.approx((0.5 - 0.5 * ramp, 1.0, 0.0))
    with pytest.raises(PediError):
        smooth_start_time_law(1.0, 0.0, 0.0)
