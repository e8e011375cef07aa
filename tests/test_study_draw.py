"""The `draw` factor of study files (joint random draws of several fields) and its binned summary."""

from pathlib import Path

import numpy as np
import pytest

from pedi_drake.batch.results_file import ResultsFile
from pedi_drake.batch.study import StudyError, load_study, scenario_for, study_from_dict
from pedi_drake.batch.summary import DRAW_BINS, factor_names_of, format_summary, main, summarise
from pedi_drake.mission.spec import shipped_missions

REPO = Path(__file__).resolve().parents[1]
FIELDS = {
    "ground_friction": {"uniform": [0.4, 1.0]},
    "model_error.payload_mass": {"uniform": [0.0, 3.0]},
    "model_error.payload_offset": {"ball": 0.05},
    "model_error.motor_strength": {"uniform": [0.6, 1.0], "size": 4},
    "model_error.foot_contact_stiffness": {"log_uniform": [1880.0, 2.0e5]},
    "random_seed": {"integers": [0, 1000]},
    "estimator": {"choice": ["kalman", "ground_truth"]},
}


def _study(fields=FIELDS, count=12, seed=5, missions=("hit_target_front",)):
    return study_from_dict(
        {
            "name": "gap",
            "factors": [
                {"name": "mission", "values": list(missions)},
                {"name": "gap", "draw": {"count": count, "seed": seed, "fields": fields}},
            ],
        },
        "gap",
    )


def test_a_draw_sets_every_field_within_its_distribution_and_labels_it_by_one_number():
    study = _study(count=40)
    assert len(study.tasks) == 40
    for task in study.tasks:
        s, shown = task.settings, task.factors["gap"]
        assert 0.4 <= s["ground_friction"] <= 1.0 and 0.0 <= s["model_error.payload_mass"] <= 3.0
        assert len(s["model_error.payload_offset"]) == 3
        assert np.linalg.norm(s["model_error.payload_offset"]) == pytest.approx(shown["model_error.payload_offset"])
        assert shown["model_error.payload_offset"] <= 0.05
        strength = s["model_error.motor_strength"]
        assert len(strength) == 4 and all(0.6 <= v <= 1.0 for v in strength)
        assert shown["model_error.motor_strength"] == min(strength)
        assert 1880.0 <= s["model_error.foot_contact_stiffness"] <= 2.0e5
        assert isinstance(s["random_seed"], int) and 0 <= s["random_seed"] < 1000
        assert s["estimator"] in ("kalman", "ground_truth")
    # Every task's scenario loads with its drawn values.
    scenario = scenario_for(study.tasks[0])
    assert scenario.model_error.motor_strength == study.tasks[0].settings["model_error.motor_strength"]


def test_draws_are_seeded_and_each_field_has_its_own_stream():
    a, b, c = _study(), _study(), _study(seed=6)
    assert [t.settings for t in a.tasks] == [t.settings for t in b.tasks]
    assert [t.settings for t in a.tasks] != [t.settings for t in c.tasks]
    fewer = _study(fields={k: v for k, v in FIELDS.items() if k != "ground_friction"})
    for full, partial in zip(a.tasks, fewer.tasks, strict=True):
        assert partial.settings["model_error.payload_mass"] == full.settings["model_error.payload_mass"]


def test_every_mission_gets_the_same_draws():
    study = _study(missions=("hit_target_front", "open_door"))
    front = [t.settings for t in study.tasks if t.settings["mission"] == "hit_target_front"]
    door = [t.settings for t in study.tasks if t.settings["mission"] == "open_door"]
    assert [dict(s, mission=None) for s in front] == [dict(s, mission=None) for s in door]


@pytest.mark.parametrize(
    "draw, where",
    [
        ({"count": 0, "fields": FIELDS}, "draw.count"),
        ({"count": 3, "seed": -1, "fields": FIELDS}, "draw.seed"),
        ({"count": 3, "fields": {}}, "draw.fields"),
        ({"count": 3}, "draw"),
        ({"count": 3, "fields": {"ground_friction": {"uniform": [1.0, 0.4]}}}, "fields.ground_friction.uniform"),
        ({"count": 3, "fields": {"ground_friction": {"normal": [1.0, 0.4]}}}, "fields.ground_friction"),
        ({"count": 3, "fields": {"ground_friction": {"log_uniform": [0.0, 1.0]}}}, "log_uniform"),
        ({"count": 3, "fields": {"model_error.payload_offset": {"ball": -0.05}}}, "ball"),
        ({"count": 3, "fields": {"model_error.motor_strength": {"uniform": [0.6, 1.0], "size": 0}}}, "size"),
        ({"count": 3, "fields": {"estimator": {"choice": []}}}, "choice"),
        ({"count": 3, "fields": {"model_error.bogus": {"uniform": [0.0, 1.0]}}}, "model_error.bogus"),
        # A drawn value the scenario refuses: motor strength 2 is outside (0, 1.5].
        ({"count": 3, "fields": {"model_error.motor_strength": {"uniform": [1.8, 2.0], "size": 4}}}, "motor_strength"),
    ],
)
def test_a_bad_draw_names_the_factor_and_the_field(draw, where):
    with pytest.raises(StudyError, match="factors\\[0\\]|task") as error:
        study_from_dict({"name": "bad", "factors": [{"name": "gap", "draw": draw}]}, "bad.yaml")
    assert where in str(error.value) and "bad.yaml" in str(error.value)


def test_a_draw_takes_no_field_or_labels_of_its_own():
    factor = {"name": "gap", "field": "ground_friction", "draw": {"count": 2, "fields": FIELDS}}
    with pytest.raises(StudyError, match="no field, no labels"):
        study_from_dict({"factors": [factor]}, "bad.yaml")


def test_the_summary_bins_each_drawn_field_and_splits_each_bin_by_mission():
    study = _study(count=40, missions=("hit_target_front", "open_door"))
    rows = []
    for task in study.tasks:
        # A made-up outcome: success whenever the payload is under 1.5 kg.
        ok = task.settings["model_error.payload_mass"] < 1.5
        rows.append(
            {"status": "ok", "success": ok, **{f"factor.{name}": value for name, value in task.factors.items()}}
        )
    assert factor_names_of(rows) == ["mission", "gap"]
    summary = summarise(rows, ["mission", "gap"])
    groups = summary["gap: model_error.payload_mass"]
    assert len(groups) == DRAW_BINS and sum(g["n"] for g in groups) == 80
    assert groups[0]["rate"] == 1.0 and groups[-1]["rate"] == 0.0
    assert set(groups[0]["by"]["mission"]) == {"hit_target_front", "open_door"}
    assert sum(g["by"]["mission"]["open_door"]["n"] for g in groups) == 40
    assert "rate by mission" in format_summary(summary)


def test_the_summary_command_summarises_a_results_folder_again(tmp_path, capsys):
    study = _study(count=8, missions=("hit_target_front", "open_door"))
    results = ResultsFile(tmp_path / "study")
    for task in study.tasks:
        ok = task.settings["ground_friction"] > 0.7
        results.append(
            {"task_id": task.task_id, "status": "ok", "success": ok}
            | {f"factor.{name}": value for name, value in task.factors.items()}
        )
    assert main([str(tmp_path / "study")]) == 0
    assert "gap: ground_friction" in capsys.readouterr().out
    for name in ("summary.json", "summary.txt", "success_vs_gap_ground_friction.png", "success_vs_mission.png"):
        assert (tmp_path / "study" / name).is_file(), name
    assert main([str(tmp_path / "nothing")]) == 2


def test_the_reality_gap_study_draws_at_least_30_gaps_for_every_shipped_mission():
    study = load_study(REPO / "studies" / "reality_gap.yaml")
    missions = [t.settings["mission"] for t in study.tasks]
    assert set(missions) == set(shipped_missions())
    assert all(missions.count(m) >= 30 for m in set(missions))
    for task in study.tasks:
        s = task.settings
        assert 0.0 <= s["model_error.payload_mass"] <= 3.0 and np.linalg.norm(s["model_error.payload_offset"]) <= 0.05
        assert 0.4 <= s["ground_friction"] <= 1.0 and all(0.6 <= v <= 1.0 for v in s["model_error.motor_strength"])
        assert 0.0 <= s["model_error.command_latency"] <= 0.010 and 0.0 <= s["model_error.joint_friction"] <= 0.3


@pytest.mark.parametrize("name", ["reality_gap_slice", "reality_gap_prongs"])
def test_a_slice_of_the_reality_gap_study_draws_the_whole_studys_gaps_for_its_missions(name):
    whole = {
        (t.settings["mission"], t.task_id): t.settings for t in load_study(REPO / "studies" / "reality_gap.yaml").tasks
    }
    part = load_study(REPO / "studies" / f"{name}.yaml").tasks
    assert len(part) == 30 * len({t.settings["mission"] for t in part})
    for task in part:
        expected = whole[(task.settings["mission"], task.task_id)]
        assert set(task.settings) == set(expected)
        for field, value in task.settings.items():
            assert np.all(np.asarray(value) == np.asarray(expected[field])), (task.task_id, field)
