"""Paper 002's 6-D shank task on both controllers: the lifted FL shank holds its world pose, all
three axes of the calf included, while the trunk moves (python -m pedi_drake.benchmarks.shank_hold
runs it beside the 5-D task)."""

import pytest

from pedi_drake.benchmarks.shank_hold import ORIENTATION_FLOOR_DEG, POSITION_FLOOR_M, floors_met, one_run


@pytest.mark.parametrize("controller", ["whole_body", "projected_impedance"])
def test_the_shank_holds_in_6d_while_the_trunk_moves_a_centimetre(controller, tmp_path):
    row = one_run(controller, "6-D", tmp_path)
    print(f"\n{row}")
    assert row["success"], row["reason"]
    assert row["trunk_displacement_max_m"] >= 0.01
    assert row["foot_position_error_max_m"] < POSITION_FLOOR_M
    assert max(row["calf_roll_error_max_deg"], row["calf_pitch_error_max_deg"], row["calf_yaw_error_max_deg"]) < (
        ORIENTATION_FLOOR_DEG
    )
    assert floors_met(row)
