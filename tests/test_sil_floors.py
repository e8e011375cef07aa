"""pedi_drake.benchmarks.sil_floors: a run is judged against every floor of a run at real time."""

import pytest

from pedi_drake.benchmarks.sil_floors import (
    FOOT_ERROR_FLOOR_MM,
    LONGEST_MISS_FLOOR_MS,
    MISSES_FLOOR_PER_1000,
    meets_floors,
)

GOOD = {
    "success": True,
    "latched": None,
    "max_true_foot_error_mm": 2.0,
    "deadline_misses_per_1000": 0.5,
    "longest_miss_ms": 6.0,
}


def test_a_run_within_every_floor_meets_them():
    assert meets_floors(GOOD)


@pytest.mark.parametrize(
    ("field", "value"),
    [
        ("success", False),
        ("latched", "status_timeout"),
        ("max_true_foot_error_mm", FOOT_ERROR_FLOOR_MM),
        ("max_true_foot_error_mm", None),
        ("deadline_misses_per_1000", MISSES_FLOOR_PER_1000),
        ("longest_miss_ms", LONGEST_MISS_FLOOR_MS + 0.1),
    ],
)
def test_a_run_outside_one_floor_does_not_meet_them(field, value):
    assert not meets_floors({**GOOD, field: value})
