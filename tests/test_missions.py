"""Every shipped mission, end to end in simulation (default scenario, seed 0), against the
missions' floors: success, reach errors, trunk drift, no fall, and each mission's own check.

The mission benchmark (python -m pedi_drake.benchmarks.missions) runs the same with sensor noise
over more seeds, every mission in full. Here the longest run their short versions (`SHORT_VERSIONS`)
or are left to the test that already runs their short version (`SHORT_VERSION_TESTED_IN`).
"""

from pathlib import Path

import pytest

from pedi_drake.batch.study import study_from_dict
from pedi_drake.batch.tasks import run_task
from pedi_drake.benchmarks.missions import EXPECTED_OBSTACLES, mission_study, obstacle_calls, result_of
from pedi_drake.mission.spec import shipped_missions
from pedi_drake.resources import missions_dir

MAX_FOOT_ERROR = 0.010  # [m] every reach phase
MAX_DRIFT = 0.010  # [m] trunk drift while pedipulating


# Missions whose short version (missions/quick/, from standing, the same phases once) runs here.
SHORT_VERSIONS = {
    "prong_pivot_rotations": "quick/pivot_rotations_once.yaml",
    "torso_circle_foot_hold": "quick/torso_circle_one_lap.yaml",
}
# Missions whose short version another test runs and judges.
SHORT_VERSION_TESTED_IN = {
    "box_lift_side_legs": "tests/test_paper003_evaluations.py",
    "push_recovery_prongs": "tests/test_paper003_evaluations.py",
    "push_recovery_no_prongs": "tests/test_paper003_evaluations.py",
}


def short_version_task(name: str):
    """The study task of `name`'s short version: from standing, seed 0, no noise."""
    study = study_from_dict(
        {
            "name": "missions_short",
            "kind": "mission",
            "base": {"scenario_text": "{simulation_duration: 60.0, robot: {initial_pose: standing}}"},
            "factors": [
                {"name": "mission", "values": [str(missions_dir() / SHORT_VERSIONS[name])]},
                {"name": "noise", "values": [{"random_seed": 0, "sensor_noise.enabled": False}]},
            ],
        },
        __name__,
    )
    (task,) = study.tasks
    return task


@pytest.fixture(scope="module", params=[m for m in shipped_missions() if m not in SHORT_VERSION_TESTED_IN])
def mission_result(request):
    if request.param in SHORT_VERSIONS:
        task = short_version_task(request.param)
    else:
        (task,) = mission_study([request.param], noise_seeds=[]).tasks
    return request.param, result_of(run_task(task))


def test_the_missions_left_out_are_shipped_and_their_short_versions_tested():
    shipped = set(shipped_missions())
    assert set(SHORT_VERSIONS) <= shipped and set(SHORT_VERSION_TESTED_IN) <= shipped
    for name, test_file in SHORT_VERSION_TESTED_IN.items():
        assert (Path(__file__).parent.parent / test_file).exists(), name


def test_mission_succeeds_without_falling(mission_result):
    name, result = mission_result
    assert result["success"], f"{name}: {result['reason']}"
    assert not result["fell"]


def test_mission_reaches_every_target_within_1cm(mission_result):
    name, result = mission_result
    for row in result["foot_errors_m"]:
        assert row["error"] < MAX_FOOT_ERROR, f"{name} {row['phase']}: {1000 * row['error']:.1f} mm"


# Missions whose point is to move the trunk while a leg works (a body_path phase): the drift floor
# is about holding the trunk still, and these have floors of their own (paper 002's IV-A, on its
# controller: tests/test_paper002_evaluations.py). The HQP, which solves trunk and 5-D foot in one
# level, gives up about 2 cm of the trunk's path there.
TRUNK_PATH_MISSIONS = {"torso_circle_foot_hold"}


def test_mission_keeps_the_trunk_within_1cm_while_pedipulating(mission_result):
    name, result = mission_result
    if name in TRUNK_PATH_MISSIONS:
        pytest.skip(f"{name} moves the trunk on purpose while pedipulating")
    assert result["max_base_drift_m"] < MAX_DRIFT, f"{name}: {1000 * result['max_base_drift_m']:.1f} mm"


def test_mission_specific_outcome(mission_result):
    name, result = mission_result
    if name == "open_door":
        assert result["door"]["opened_deg"] >= 20.0
    if name == "prong_push_box":
        assert result["box"]["moved_m"] >= 0.02
    if name in EXPECTED_OBSTACLES:
        assert obstacle_calls(result["presses"]) == EXPECTED_OBSTACLES[name]
    if name == "push_box_away_on_prongs":
        assert result["object_push"]["moved_m"] >= 0.20
        assert max(result["object_push"]["stance_feet_slide_m"].values()) <= 0.01
    if name == "push_light_box":
        assert result["object_push"]["moved_m"] >= 0.10
        assert max(result["object_push"]["stance_feet_slide_m"].values()) <= 0.01
