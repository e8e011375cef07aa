"""What a run's result says is what physically happened, and what it writes is this run's only."""

import io
import json
import math

import numpy as np
import pytest

from pedi_drake.evaluation.judge import STAND_HEIGHT_TOLERANCE, _stand_reason, commanded_stand_height
from pedi_drake.evaluation.out_dir import OWNED_FILES
from pedi_drake.evaluation.result_file import rounded_result
from pedi_drake.mission.phases import target_problem
from pedi_drake.mission.progress import RUNNING, SUCCEEDED, MissionProgress, PhaseRecord
from pedi_drake.mission.spec import load_mission
from pedi_drake.run import phase_label, run
from pedi_drake.run_logs import read_run_logs
from pedi_drake.scenario import load_scenario


def _run(tmp_path, scenario_name="stand", text="{}", duration=None, mission=None, **options):
    scenario = load_scenario(scenario_name=scenario_name, scenario_text=text)
    if mission is not None:
        scenario.mission, scenario.controller = mission, "whole_body"
    if duration is not None:
        scenario.simulation_duration = duration
    result = run(scenario=scenario, name=scenario_name, out_dir=tmp_path, quiet=True, **options)
    assert json.loads((tmp_path / "result.json").read_text())["success"] == result["success"]
    return result


def test_a_stand_whose_trunk_never_reaches_the_commanded_height_fails(tmp_path):
    # Motor gains far too weak to lift the trunk: nothing fell, but the robot did not stand.
    result = _run(tmp_path, text="{stand: {kp: 3.0, kd: 0.3}}", duration=2.0, replay=False)
    assert result["fell"] is False
    assert result["success"] is False and "did not stand" in result["reason"], result["reason"]
    assert result["final_trunk_height_m"] < commanded_stand_height(load_scenario(scenario_name="stand")) - 0.05


def test_the_stand_judgement_needs_the_commanded_height_within_the_tolerance():
    scenario = load_scenario(scenario_name="stand")
    target = commanded_stand_height(scenario)
    assert _stand_reason(scenario, target - 0.5 * STAND_HEIGHT_TOLERANCE, 3.0) == ""
    assert "did not stand" in _stand_reason(scenario, 0.013, 3.0)
    assert "before the stand did" in _stand_reason(scenario, target, 0.5 * scenario.stand.duration)


def test_huge_sensor_noise_blames_the_estimate_not_the_robot(tmp_path):
    text = "{sensor_noise: {enabled: true, orientation: 2.0, gyro: 5.0, accelerometer: 20.0}}"
    result = _run(tmp_path, scenario_name="default", text=text, duration=1.5, replay=False)
    assert result["fell"] is False and result["estimate_fell"] is True
    assert result["success"] is False
    assert "the state estimate failed, not the robot" in result["reason"], result["reason"]
    assert "the robot did not fall (ground truth)" in result["reason"]


def test_friction_too_low_to_stand_is_named_as_the_cause(tmp_path):
    result = _run(tmp_path, scenario_name="default", text="{ground_friction: 0.001}", duration=5.0, replay=False)
    assert result["success"] is False
    assert result["reason"].startswith("friction too low to stand"), result["reason"]
    assert "0.001" in result["reason"]


def test_a_target_below_the_floor_or_inside_the_trunk_is_named():
    from pydrake.math import RigidTransform

    X_WB = RigidTransform([0.0, 0.0, 0.28])
    assert "target below the floor" in target_problem(np.array([0.4, -0.13, -0.03]), X_WB)
    assert "target inside the robot" in target_problem(X_WB @ np.array([0.05, 0.0, 0.0]), X_WB)
    assert target_problem(np.array([0.447, -0.13, 0.20]), X_WB) is None  # hit_target_front's


def test_a_run_of_one_control_tick_writes_a_valid_result(tmp_path):
    result = _run(tmp_path, duration=0.002)
    assert result["sim_time_s"] == pytest.approx(0.002)
    assert result["success"] is False and "before the stand did" in result["reason"]
    assert (tmp_path / "replay.html").exists() and (tmp_path / "joint_positions.png").exists()


def test_a_rerun_removes_the_previous_runs_files_and_keeps_the_users(tmp_path):
    (tmp_path / "leg_tracking.png").write_bytes(b"a previous mission run's plot")
    (tmp_path / "error.txt").write_text("a previous run's crash")
    (tmp_path / "notes.txt").write_text("mine")
    _run(tmp_path, duration=0.01, replay=False)
    assert not (tmp_path / "leg_tracking.png").exists() and not (tmp_path / "error.txt").exists()
    assert (tmp_path / "notes.txt").read_text() == "mine"
    written = {path.name for path in tmp_path.iterdir() if not path.name.startswith(".")} - {"notes.txt"}
    assert written <= set(OWNED_FILES), written - set(OWNED_FILES)


def test_result_times_snap_to_the_control_period_and_lengths_to_a_tenth_of_a_millimetre():
    raw = {
        "sim_time_s": 2.5000000000000004,
        "phases": [{"t_start": 2.0100000000000002, "t_end": 4.0120001}],
        "foot_errors_m": [{"error": 0.0123456, "target_W": [0.44712345, -0.13, 0.2], "t_end": 6.3400000001}],
        "max_base_drift_m": 0.0098765,
        "final_trunk_height_m": float("nan"),
        "real_time_factor": 0.123456,
    }
    clean = rounded_result(raw, time_step=0.002)
    assert json.dumps(clean["phases"]) == '[{"t_start": 2.01, "t_end": 4.012}]'
    assert clean["sim_time_s"] == 2.5 and clean["foot_errors_m"][0]["t_end"] == 6.34
    assert clean["foot_errors_m"][0]["error"] == 0.0123 and clean["foot_errors_m"][0]["target_W"][0] == 0.4471
    assert clean["max_base_drift_m"] == 0.0099 and clean["final_trunk_height_m"] is None
    assert clean["real_time_factor"] == 0.123456  # not a time or a length: left alone


def test_plots_start_at_the_first_valid_estimate_not_the_initial_sample(tmp_path, monkeypatch):
    from pedi_drake.evaluation.judge import _from_first_estimate
    from pedi_drake.viz import plots

    starts = []
    original = plots.plot_foot_forces

    def spy(t, *args, **kwargs):
        starts.append(float(t[0]))
        return original(t, *args, **kwargs)

    monkeypatch.setattr(plots, "plot_foot_forces", spy)
    _run(tmp_path, scenario_name="default", duration=0.2, replay=False)
    logs = read_run_logs(tmp_path)
    # The log keeps the initial sample (the mission's reference there is not yet made: z = 0) ...
    assert logs["mission.body_reference"].times[0] == 0.0 and logs["mission.body_reference"].data[2, 0] == 0.0
    # ... the plots start after it, where the reference holds the measured trunk.
    assert starts and starts[0] > 0.0
    trimmed = _from_first_estimate(logs)
    assert all(log.times[0] > 0.0 for log in trimmed.values())
    assert trimmed["mission.body_reference"].data[2, 0] > 0.05


def test_the_progress_label_names_the_phase_being_run_with_its_own_index():
    mission = load_mission("hit_target_front")
    progress = MissionProgress(index=1, status=RUNNING)
    # Between phases: the index has moved on, the last record is still the finished stand-up.
    progress.records = [PhaseRecord("0_stand_up", "stand_up", SUCCEEDED, 0.0, 2.01)]
    assert phase_label(progress, mission) == "phase 1/5 0_stand_up (succeeded)"
    progress.records.append(PhaseRecord("1_leg_to_pedipulation", "leg_to_pedipulation", RUNNING, 2.01))
    assert phase_label(progress, mission) == "phase 2/5 1_leg_to_pedipulation (running)"


def test_the_progress_is_a_bar_on_a_terminal_and_plain_lines_otherwise(tmp_path, monkeypatch, capsys):
    class Terminal(io.StringIO):
        def isatty(self):
            return True

    terminal = Terminal()
    monkeypatch.setattr("sys.stdout", terminal)
    scenario = load_scenario(scenario_name="default")
    scenario.simulation_duration = 2.5
    run(scenario=scenario, name="bar", out_dir=tmp_path / "tty", replay=False)
    shown = terminal.getvalue()
    assert "\r  [" in shown and "x real time" in shown and "phase 1/5 0_stand_up" in shown
    assert "  t = " not in shown
    monkeypatch.undo()
    run(scenario=scenario, name="plain", out_dir=tmp_path / "pipe", replay=False)
    lines = capsys.readouterr().out
    assert "\r" not in lines and "  t =   2.0 s  phase 1/5 0_stand_up" in lines


def test_the_replay_camera_frames_the_robot_and_every_object_of_each_shipped_mission():
    from pedi_drake.diagram import apply_mission
    from pedi_drake.mission.spec import shipped_missions
    from pedi_drake.viz.meshcat_camera import FIELD_OF_VIEW, camera_pose

    for name in shipped_missions():
        scenario = apply_mission(load_scenario(), load_mission(name))
        camera, target = camera_pose(scenario)
        view = (target - camera) / np.linalg.norm(target - camera)
        x, y = scenario.robot.initial_xy
        points = [np.array([x, y, 0.1])] + [np.asarray(o.position, float) for o in scenario.scene]
        for point in points:
            to_point = (point - camera) / np.linalg.norm(point - camera)
            angle = math.acos(np.clip(view @ to_point, -1.0, 1.0))
            assert angle < FIELD_OF_VIEW / 2, (name, point)
        assert np.linalg.norm(camera - target) < 3.0, name  # near enough for the robot to be large
