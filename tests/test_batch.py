"""Batch studies: study files, the serial and Ray engines, resuming, failures as rows, summaries."""

import json
import os
import signal
import subprocess
import sys
import textwrap
import threading
import time
from pathlib import Path

import pytest

from pedi_drake.batch.engines import RayEngine, SerialEngine, longest_first
from pedi_drake.batch.results_file import read_rows
from pedi_drake.batch.runner import run_study
from pedi_drake.batch.study import StudyError, load_study, scenario_for, study_from_dict
from pedi_drake.batch.summary import wilson_interval
from pedi_drake.batch.tasks import run_task
from pedi_drake.benchmarks.batch import deterministic, differing_fields
from pedi_drake.benchmarks.suf import height_sweep_rows
from pedi_drake.suf.design import height_sweep

REPO = Path(__file__).resolve().parents[1]

STANDS = {
    "name": "stands",
    "kind": "mission",
    # A stand succeeds once the trunk is at its height: a quick blend, and time to get there.
    "base": {"scenario_name": "stand", "scenario_text": "{simulation_duration: 0.8, stand: {duration: 0.5}}"},
    "factors": [
        {"name": "ground_friction", "values": [0.6, 0.9]},
        {"name": "seed", "field": "random_seed", "values": [0, 1]},
    ],
}


def _write(tmp_path: Path, text: str) -> Path:
    path = tmp_path / "study.yaml"
    path.write_text(textwrap.dedent(text))
    return path


@pytest.mark.parametrize(
    "body, field",
    [
        ("kind: mission\nfactors:\n  - {name: bogus_field, values: [1]}\n", "bogus_field"),
        ("kind: mission\nfactors:\n  - {name: ground_friction, values: [fast]}\n", "ground_friction"),
        ("kind: mission\nfactors:\n  - {name: ground_friction, random: {low: 1, high: 1, count: 3}}\n", "random"),
        ("kind: mission\nfactors:\n  - {name: ground_friction, values: []}\n", "values"),
        ("kind: bogus\nfactors:\n  - {name: ground_friction, values: [1]}\n", "kind"),
        ("kind: suf\nfactors:\n  - {name: method, values: [magic]}\n", "method"),
        ("kind: mission\nfactors:\n  - {name: ground_friction, values: [0.5, 0.9], labels: [low]}\n", "labels"),
        ("kind: mission\nfactors:\n  - {name: push, field: pushes, values: [[{force: -3.0}]]}\n", "pushes"),
    ],
)
def test_a_bad_study_file_names_the_file_and_the_field(tmp_path, body, field):
    path = _write(tmp_path, body)
    with pytest.raises(StudyError, match=field) as error:
        load_study(path)
    assert str(path) in str(error.value)


def test_a_push_factor_sets_the_scenario_pushes_and_rows_carry_its_labels(tmp_path):
    push = "{force: 30.0, body: trunk, direction: [0.0, -1.0, 0.0], start: 5.0, ramp: 0.5, duration: 2.0}"
    path = _write(
        tmp_path,
        f"""
        kind: mission
        factors:
          - {{name: mission, values: [hit_target_front]}}
          - {{name: push, field: pushes, values: [[], [{push}]], labels: [none, 30 N]}}
        """,
    )
    study = load_study(path)
    assert [task.factors["push"] for task in study.tasks] == ["none", "30 N"]
    pushes = [scenario_for(task).pushes for task in study.tasks]
    assert pushes[0] == [] and pushes[1][0].force == 30.0 and pushes[1][0].direction == [0.0, -1.0, 0.0]


def test_a_bad_study_file_exits_2_before_any_task_runs(tmp_path):
    path = _write(tmp_path, "kind: mission\nfactors:\n  - {name: ground_friction, range: {start: 0, stop: 1}}\n")
    out = tmp_path / "results"
    done = subprocess.run(
        [sys.executable, "-m", "pedi_drake.batch", str(path), "--engine", "serial", "--out", str(out)],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert done.returncode == 2
    assert "range" in done.stderr and str(path) in done.stderr and "Traceback" not in done.stderr
    assert not out.exists()


def test_a_grid_has_every_combination_and_a_list_zips():
    assert len(study_from_dict(STANDS, "stands").tasks) == 4
    zipped = dict(STANDS, design="list")
    assert [t.settings for t in study_from_dict(zipped, "zipped").tasks] == [
        {"ground_friction": 0.6, "random_seed": 0},
        {"ground_friction": 0.9, "random_seed": 1},
    ]


def test_ray_gets_the_longest_missions_first_and_equal_ones_in_study_order():
    study = study_from_dict(
        {
            "name": "order",
            "factors": [
                {"name": "mission", "values": ["hit_target_front", "prong_pivot_rotations", "open_door"]},
                {"name": "random_seed", "values": [0, 1]},
            ],
        },
        "order",
    )
    ordered = longest_first(study.tasks)
    # Planned durations: prong_pivot_rotations 29.4 s, open_door 10 s, hit_target_front 8 s.
    assert [t.settings["mission"] for t in ordered] == ["prong_pivot_rotations"] * 2 + ["open_door"] * 2 + [
        "hit_target_front"
    ] * 2
    assert [t.settings["random_seed"] for t in ordered] == [0, 1] * 3
    assert sorted(t.task_id for t in ordered) == sorted(t.task_id for t in study.tasks)


def test_four_runs_on_a_local_ray_with_two_workers_give_the_serial_rows(tmp_path):
    study = study_from_dict(STANDS, "stands")
    serial = run_study(study, tmp_path / "serial", SerialEngine(), quiet=True).rows
    on_ray = run_study(study, tmp_path / "ray", RayEngine(num_cpus=2), quiet=True).rows
    assert len(serial) == len(on_ray) == 4
    by_id = {row["task_id"]: deterministic(row) for row in serial}
    assert {row["task_id"]: deterministic(row) for row in on_ray} == by_id
    assert all(row["status"] == "ok" and row["success"] for row in on_ray)
    # The rows came from worker processes, not from this one.
    assert {row["worker_pid"] for row in on_ray} - {os.getpid()}


def test_a_task_past_its_timeout_is_a_row_with_the_reason():
    study = study_from_dict(
        {"name": "slow", "kind": "noop", "timeout": 0.2, "factors": [{"name": "duration_s", "values": [2.0]}]}, "slow"
    )
    start = time.perf_counter()
    row = run_task(study.tasks[0])
    assert time.perf_counter() - start < 1.0
    assert row["status"] == "timeout" and "0.2 s" in row["reason"]


def test_a_mission_that_fails_is_a_row_with_its_reason_not_a_lost_study():
    # Friction 0.001: the robot cannot stand, the mission fails, the task still returns its row.
    study = study_from_dict(
        {
            "name": "slippery",
            "kind": "mission",
            "base": {"scenario_text": "{simulation_duration: 3.0}"},
            "factors": [{"name": "mission", "values": ["give_paw"]}, {"name": "ground_friction", "values": [0.001]}],
        },
        "slippery",
    )
    row = run_task(study.tasks[0])
    assert row["status"] == "failed" and not row["success"] and row["reason"]


def _cli(study: Path, out: Path, *extra: str) -> subprocess.Popen:
    return subprocess.Popen(
        [sys.executable, "-m", "pedi_drake.batch", str(study), "--out", str(out), "--quiet", *extra],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )


def test_an_interrupted_study_keeps_its_rows_and_resume_runs_only_the_rest(tmp_path):
    path = _write(
        tmp_path,
        """
        name: waits
        kind: noop
        factors:
          - {name: duration_s, values: [0.4, 0.41, 0.42, 0.43, 0.44, 0.45, 0.46, 0.47]}
        """,
    )
    out = tmp_path / "results"
    process = _cli(path, out, "--engine", "serial")
    deadline = time.time() + 60
    while time.time() < deadline and not (out / "results.jsonl").exists():
        time.sleep(0.05)
    time.sleep(0.5)
    process.send_signal(signal.SIGINT)
    assert process.wait(timeout=30) == 130
    first = read_rows(out)
    assert 1 <= len(first) < 8
    resumed = _cli(path, out, "--engine", "serial", "--resume")
    assert resumed.wait(timeout=60) == 0
    rows = read_rows(out)
    assert len(rows) == 8 and len({row["task_id"] for row in rows}) == 8
    assert rows[: len(first)] == first  # the finished rows were kept, not run again


def _ray_task_processes() -> list[int]:
    pids = []
    for entry in Path("/proc").iterdir():
        if entry.name.isdigit():
            try:
                if (entry / "cmdline").read_bytes().startswith(b"ray::run_task"):
                    pids.append(int(entry.name))
            except OSError:
                continue
    return pids


def test_a_killed_worker_loses_only_its_task_which_is_retried(tmp_path):
    study = study_from_dict(
        {"name": "waits", "kind": "noop", "factors": [{"name": "duration_s", "values": [3.0, 3.1]}]}, "waits"
    )
    killed = []

    def kill_one():
        deadline = time.time() + 60
        while time.time() < deadline and not killed:
            pids = _ray_task_processes()
            if pids:
                time.sleep(0.5)  # let the task start its sleep
                os.kill(pids[0], signal.SIGKILL)
                killed.append(pids[0])
            time.sleep(0.1)

    killer = threading.Thread(target=kill_one, daemon=True)
    killer.start()
    rows = run_study(study, tmp_path / "results", RayEngine(num_cpus=2, max_retries=2), quiet=True).rows
    killer.join(timeout=5)
    assert killed, "no Ray worker was found to kill"
    assert len(rows) == 2 and all(row["status"] == "ok" for row in rows)
    assert killed[0] not in {row["worker_pid"] for row in rows}


def test_wilson_interval_at_the_edges():
    low, high = wilson_interval(0, 10)
    assert low == 0.0 and high == pytest.approx(0.2775, abs=1e-3)
    low, high = wilson_interval(10, 10)
    assert high == pytest.approx(1.0, abs=1e-12) and low == pytest.approx(0.7225, abs=1e-3)


def test_the_height_sweep_study_gives_the_design_module_s_figures(tmp_path):
    study = study_from_dict(
        {
            "name": "sweep",
            "kind": "suf",
            "factors": [
                {"name": "trunk_height", "values": [0.22]},
                {"name": "prongs", "values": [False, True]},
                {"name": "optimise_feet", "values": [True]},
            ],
        },
        "sweep",
    )
    rows = run_study(study, tmp_path / "results", SerialEngine(), quiet=True).rows
    (from_study,) = height_sweep_rows(rows)
    (direct,) = height_sweep([0.22])
    assert json.dumps(from_study, sort_keys=True) == json.dumps(direct, sort_keys=True)


def test_differing_fields_names_each_field_and_counts_its_tasks():
    row = {"task_id": "a", "code_version": "1 (abc)", "worker_pid": 7, "result": {"error_mm": 1.0, "wall_time_s": 3.0}}
    other = {**row, "code_version": "1 (abc+dirty)", "worker_pid": 8, "result": {"error_mm": 1.5, "wall_time_s": 9.0}}
    assert differing_fields([row], [dict(row, worker_pid=9)]) == {}
    assert differing_fields([row], [other]) == {"code_version": 1, "result.error_mm": 1}
    assert differing_fields([row], []) == {"task_id": 1}
