"""The mission's packed references: the compiled samplers against their plain-Python source, and
the packed controller vectors against the vectors assembled from the trajectories' samples."""

import numpy as np
import pytest
from pydrake.math import RollPitchYaw, RotationMatrix

from pedi_drake import robot
from pedi_drake.control import references as controller_refs
from pedi_drake.exceptions import PediError
from pedi_drake.mission import reference_table as rt
from pedi_drake.mission.progress import (
    LEG_MODE_FOOT,
    LEG_MODE_FOOT_POSE,
    LEG_MODE_JOINTS,
    LegTrajectory,
    References,
)
from pedi_drake.runtime import jit
from pedi_drake.trajectory import (
    CircularPath,
    PiecewiseQuintic,
    PivotedPosition,
    QuinticOrientationSegment,
    QuinticSegment,
    RampSegment,
    sample_rotation_into,
    sample_vector_into,
    smooth_start_time_law,
)

RNG_SEED = 20261203


def _rotation(rng) -> RotationMatrix:
    return RotationMatrix(RollPitchYaw(*rng.uniform(-np.pi, np.pi, 3)))


def _random_trajectories(rng, t0: float, duration: float) -> list:
    """One of each packed kind, starting at t0 [s]."""
    a, b = rng.normal(0, 0.3, 3), rng.normal(0, 0.3, 3)
    orientation = QuinticOrientationSegment(_rotation(rng), _rotation(rng), t0, duration)
    durations = list(rng.uniform(0.1, 1.0, 3))
    return [
        QuinticSegment(a, b, t0, duration),
        PiecewiseQuintic.through(rng.normal(0, 0.3, (4, 3)), t0, durations),
        RampSegment(a, rng.normal(0, 0.2, 3), t0, duration),
        CircularPath(a, rng.uniform(0.01, 0.1), t0, duration, int(rng.integers(1, 3)), rng.uniform(-3, 3)),
        PivotedPosition(orientation, b, a),
    ]


def _times(rng, t0: float, duration: float) -> list[float]:
    """Before, at the ends of, inside and after [t0, t0 + duration]."""
    return [t0 - 0.3, t0, t0 + duration, t0 + 5.0, *rng.uniform(t0, t0 + duration, 8)]


def test_packed_samplers_equal_their_python_source():
    rng = np.random.default_rng(RNG_SEED)
    for _ in range(60):
        t0, duration = rng.uniform(0, 3), rng.uniform(0.05, 2.0)
        trajectories = _random_trajectories(rng, t0, duration)
        orientation = QuinticOrientationSegment(_rotation(rng), _rotation(rng), t0, duration)
        for t in _times(rng, t0, duration):
            for trajectory in trajectories:
                compiled, interpreted = np.zeros((3, 3)), np.zeros((3, 3))
                sample_vector_into(trajectory.packed, t, *compiled)
                sample_vector_into.py_func(trajectory.packed, t, *interpreted)
                np.testing.assert_allclose(compiled, interpreted, rtol=1e-12, atol=1e-12)
            outputs = [(np.zeros((3, 3)), np.zeros(4), np.zeros(3), np.zeros(3)) for _ in range(2)]
            sample_rotation_into(orientation.packed, t, *outputs[0])
            sample_rotation_into.py_func(orientation.packed, t, *outputs[1])
            for compiled, interpreted in zip(*outputs, strict=True):
                np.testing.assert_allclose(compiled, interpreted, rtol=1e-12, atol=1e-12)


def test_a_sampled_orientation_has_drakes_quaternion():
    rng = np.random.default_rng(RNG_SEED + 1)
    for _ in range(200):
        segment = QuinticOrientationSegment(_rotation(rng), _rotation(rng), 0.0, 1.0)
        for t in (-1.0, rng.uniform(0.0, 1.0), 2.0):
            sample = segment.sample(t)
            expected = sample.rotation.ToQuaternion().wxyz()
            assert sample.wxyz[0] >= 0.0
            np.testing.assert_allclose(sample.wxyz, expected, atol=1e-14)
        # At rest, exactly the end rotations' quaternions as Drake makes them.
        np.testing.assert_array_equal(segment.sample(2.0).wxyz, segment.end.ToQuaternion().wxyz())


def _assembled(refs: References, t: float) -> np.ndarray:
    """body_reference then leg_reference assembled from the trajectories' samples: the controller
    vectors the packed table must give."""
    p = refs.body_position.sample(t)
    R = refs.body_orientation.sample(t)
    body = np.concatenate(
        [p.position, R.quaternion_wxyz(), p.velocity, p.acceleration, R.angular_velocity, R.angular_acceleration]
    )
    entries, gains = {}, {}
    for leg, reference in refs.legs.items():
        sample = reference.trajectory.sample(t)
        last = sample.acceleration if reference.calf_rotation is None else reference.calf_rotation
        entries[leg] = (reference.mode, sample.position, sample.velocity, last)
        if reference.foot_gains is not None:
            gains[leg] = reference.foot_gains
    press = refs.press
    if press is not None and press["frozen_at"] is None:
        s, sd, sdd = smooth_start_time_law(t, press["t0"], press["ramp"])
        d, speed = press["direction"], press["speed"]
        entries[press["leg"]] = (LEG_MODE_FOOT, press["start"] + speed * s * d, speed * sd * d, speed * sdd * d)
    return np.concatenate([body, controller_refs.leg_reference_vector(entries, gains)])


def _random_references(rng, t0: float, duration: float, press: str) -> References:
    refs = References.holding(rng.normal(0, 0.2, 3), _rotation(rng), t0, num_prongs=2)
    refs.body_orientation = QuinticOrientationSegment(_rotation(rng), _rotation(rng), t0, duration)
    position = _random_trajectories(rng, t0, duration)[int(rng.integers(0, 5))]
    if isinstance(position, RampSegment):
        position = QuinticSegment(position.start, position.end, t0, duration)
    refs.body_position = position
    legs = rng.permutation(robot.LEG_NAMES)[: int(rng.integers(0, 4))]
    for k, leg in enumerate(legs):
        trajectory = _random_trajectories(rng, t0, duration)[k % 3]
        if k == 0:
            refs.legs[leg] = LegTrajectory(LEG_MODE_JOINTS, trajectory)
        elif k == 1:
            refs.legs[leg] = LegTrajectory(LEG_MODE_FOOT, trajectory, foot_gains=(300.0, 20.0))
        else:
            refs.legs[leg] = LegTrajectory(LEG_MODE_FOOT_POSE, trajectory, calf_rotation=rng.normal(0, 0.3, 3))
    if press != "none" and len(legs):
        direction = rng.normal(size=3)
        refs.press = dict(
            leg=legs[0],
            start=rng.normal(0, 0.3, 3),
            direction=direction / np.linalg.norm(direction),
            speed=0.05,
            ramp=0.1,
            t0=t0,
            frozen_at=None if press == "driving" else t0 + 0.5,
        )
    return refs


@pytest.mark.parametrize("press", ["none", "driving", "frozen"])
def test_packed_references_equal_the_vectors_assembled_from_samples(press):
    rng = np.random.default_rng(RNG_SEED + 2)
    for _ in range(40):
        t0, duration = rng.uniform(0, 3), rng.uniform(0.05, 2.0)
        refs = _random_references(rng, t0, duration, press)
        table = rt.reference_table(refs)
        for t in _times(rng, t0, duration):
            x = np.full(rt.REFERENCES_SIZE, np.nan)
            rt.references_into(table.body, table.legs, t, x)
            np.testing.assert_allclose(x, _assembled(refs, t), rtol=0, atol=1e-12)
            interpreted = np.full(rt.REFERENCES_SIZE, np.nan)
            rt.references_into.py_func(table.body, table.legs, t, interpreted)
            np.testing.assert_allclose(x, interpreted, rtol=1e-12, atol=1e-12)


def test_a_press_with_a_ramp_that_is_not_positive_is_refused():
    refs = References.holding(np.zeros(3), RotationMatrix(), 0.0, num_prongs=0)
    refs.legs["FR"] = LegTrajectory(LEG_MODE_FOOT, QuinticSegment(np.zeros(3), np.zeros(3), 0.0, 1e-3))
    refs.press = dict(leg="FR", start=np.zeros(3), direction=np.array([1.0, 0, 0]), speed=0.05, ramp=0.0, t0=0.0)
    refs.press["frozen_at"] = None
    with pytest.raises(PediError, match="ramp"):
        rt.reference_table(refs)


def test_the_packed_table_is_a_value_shared_by_state_copies():
    import copy

    table = rt.reference_table(References.holding(np.zeros(3), RotationMatrix(), 0.0, num_prongs=0))
    assert copy.deepcopy(table) is table
    assert not table.body.flags.writeable and not table.legs.flags.writeable


def test_kernels_are_compiled_when_numba_is_installed():
    pytest.importorskip("numba")
    if not jit.ENABLED:
        pytest.skip("PEDI_DRAKE_JIT=0")
    assert rt.references_into.py_func is not rt.references_into
