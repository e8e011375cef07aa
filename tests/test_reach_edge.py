"""The lifted foot driven beyond the edge of its reach and back, on both controllers
(missions/evaluations/reach_edge.yaml; python -m pedi_drake.benchmarks.reach_edge plots it)."""

import pytest

from pedi_drake.benchmarks.reach_edge import AFTER_ERROR_FLOOR_M, STRETCH_ERROR_FLOOR_M, floors_met, one_run


@pytest.mark.parametrize("controller", ["whole_body", "projected_impedance"])
def test_the_foot_passes_the_edge_of_its_reach_without_instability(controller):
    row, trace = one_run(controller)
    print(f"\n{row}")
    assert row["success"] and not row["fell"], row["reason"]
    # The reference really left the leg's reach, for longer than a second, and the knee went to
    # (paper 002's controller: onto) its limit or the HQP's margin before it.
    assert row["beyond_reach_s"] > 1.0
    assert row["knee_min_rad"] > row["knee_limit_rad"] - 0.1
    assert row["torque_share_of_limit_max"] < 1.0
    assert row["foot_error_beyond_reach_max_m"] < STRETCH_ERROR_FLOOR_M
    assert row["foot_error_after_max_m"] < AFTER_ERROR_FLOOR_M
    # No spike: no torque jumps at the edge by more than it does at the lift or the touch-down.
    assert row["torque_step_in_sweep_max_nm"] < row["torque_step_elsewhere_max_nm"]
    assert floors_met(row)
