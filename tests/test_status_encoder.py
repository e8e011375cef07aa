"""The simulator bridge's status encoder writes the same bytes as the generated messages."""

import numpy as np
import pytest

from pedi_drake.apps.sim_bridge import status_messages
from pedi_drake.apps.status_encoder import StatusEncoder, field_offsets
from pedi_drake.apps.status_sample import IMU_QUATERNION, SAMPLE_SIZE
from pedi_drake.go1_driver.lcmtypes import leg_control_data_lcmt, rc_command_lcmt, state_estimator_lcmt


def test_encoded_status_equals_the_generated_messages_bytes():
    rng = np.random.default_rng(3)
    encoder = StatusEncoder()
    for tick in [0, 1, 7, 2**40] + rng.integers(0, 10**6, 200).tolist():
        sample = rng.normal(scale=5.0, size=SAMPLE_SIZE)
        sample[IMU_QUATERNION] = rng.normal(size=4)  # any quaternion: both normalise it
        leg, estimator = status_messages(sample, tick)
        assert encoder.encode(sample, tick) == (leg.encode(), estimator.encode())


def test_field_offsets_follow_the_declaration_order():
    offsets = field_offsets(leg_control_data_lcmt)
    assert offsets["q"] == (8, 12, "float")
    assert offsets["tau_est"] == (8 + 4 * 48, 12, "float")
    assert offsets["id"] == (8 + 4 * 60 + 8, 1, "int64_t")
    last = field_offsets(state_estimator_lcmt)["robot_id"]
    assert last[0] + 8 == len(state_estimator_lcmt().encode())


def test_a_type_with_fields_of_other_kinds_is_refused():
    # rc_command has int16 fields, which the encoder does not write.
    with pytest.raises(ValueError, match="rc_command_lcmt"):
        field_offsets(rc_command_lcmt)
