"""The Go1 LCM types are wire-compatible with the walk-these-ways bridge."""

import struct
import subprocess
import sys

import numpy as np
import pytest

from pedi_drake.go1_driver import constants as c
from pedi_drake.go1_driver.lcmtypes import (
    leg_control_data_lcmt,
    pd_tau_targets_lcmt,
    rc_command_lcmt,
    state_estimator_lcmt,
)

TYPES = (pd_tau_targets_lcmt, leg_control_data_lcmt, state_estimator_lcmt, rc_command_lcmt)


def _rotate_left(value: int) -> int:
    return ((value << 1) & 0xFFFFFFFFFFFFFFFF) + (value >> 63)


@pytest.mark.parametrize("lcm_type", TYPES, ids=lambda t: t.__name__)
def test_fingerprint_matches_the_bridge(lcm_type):
    # The wire fingerprint is the base hash rotated left by one (LCM's rule for primitive-only types).
    expected = _rotate_left(c.REFERENCE_BASE_HASH[lcm_type.__name__])
    assert lcm_type._get_hash_recursive([]) == expected
    assert lcm_type().encode()[:8] == struct.pack(">Q", expected)


@pytest.mark.parametrize("lcm_type", TYPES, ids=lambda t: t.__name__)
def test_encoded_size_matches_the_bridge(lcm_type):
    assert len(lcm_type().encode()) == c.REFERENCE_ENCODED_SIZE[lcm_type.__name__]


def test_command_field_order_on_the_wire():
    # go1.command is (q_des, qd_des, kp, kd, tau_ff); the wire is (q_des, qd_des, tau_ff, kp, kd).
    command = np.arange(60, dtype=float)
    data = c.command_to_message(command, timestamp_us=7, message_id=3).encode()
    doubles = struct.unpack(">60d", data[8 : 8 + 480])
    np.testing.assert_array_equal(doubles[0:24], command[0:24])
    np.testing.assert_array_equal(doubles[24:36], command[48:60])  # tau_ff
    np.testing.assert_array_equal(doubles[36:48], command[24:36])  # kp
    np.testing.assert_array_equal(doubles[48:60], command[36:48])  # kd
    assert struct.unpack(">qq", data[488:504]) == (7, 3)
    decoded = pd_tau_targets_lcmt.decode(data)
    np.testing.assert_array_equal(c.message_to_command(decoded), command)


def test_the_drivers_command_encoder_writes_lcm_gens_bytes():
    rng = np.random.default_rng(7)
    encoder = c.CommandEncoder()
    for _ in range(500):
        command = rng.normal(size=60) * 10.0 ** rng.uniform(-6, 3, 60)
        stamp, message_id = int(rng.integers(0, 2**40)), int(rng.integers(0, 2**31))
        data = encoder.encode(command, stamp, message_id)
        assert data == c.command_to_message(command, stamp, message_id).encode()
        np.testing.assert_array_equal(c.message_to_command(pd_tau_targets_lcmt.decode(data)), command)


@pytest.mark.parametrize("bad", [np.nan, np.inf, -np.inf])
def test_the_drivers_command_encoder_gives_no_bytes_for_a_non_finite_command(bad):
    encoder = c.CommandEncoder()
    for index in (0, 30, 59):
        command = np.ones(60)
        command[index] = bad
        assert encoder.encode(command, 1, 2) is None
    # A finite command after a refused one is encoded whole.
    command = np.arange(60, dtype=float)
    assert encoder.encode(command, 1, 2) == c.command_to_message(command, 1, 2).encode()


def test_status_round_trip_in_float32():
    message = leg_control_data_lcmt()
    message.q = [0.1 * i for i in range(12)]
    decoded = leg_control_data_lcmt.decode(message.encode())
    np.testing.assert_allclose(decoded.q, message.q, rtol=1e-7)


def test_foreign_type_is_rejected_by_decode():
    with pytest.raises(ValueError):
        leg_control_data_lcmt.decode(state_estimator_lcmt().encode())


def test_generated_types_are_up_to_date(tmp_path):
    """The committed Python equals what lcm-gen makes from the committed .lcm files."""
    import pathlib

    folder = pathlib.Path(c.__file__).parent / "lcmtypes"
    lcm_gen = pathlib.Path(sys.executable).parent / "lcm-gen"
    if not lcm_gen.exists():
        import shutil

        found = shutil.which("lcm-gen")
        if found is None:
            pytest.skip("lcm-gen (from the lcm wheel) is not on PATH")
        lcm_gen = pathlib.Path(found)
    sources = sorted(str(p) for p in folder.glob("*.lcm"))
    assert len(sources) == 6  # the four Go1 types and the operator's foot command and feedback
    subprocess.run([str(lcm_gen), "-p", "--ppath", str(tmp_path), *sources], check=True)
    for source in sources:
        name = pathlib.Path(source).stem + ".py"
        assert (tmp_path / name).read_text() == (folder / name).read_text(), name
