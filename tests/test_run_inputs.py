"""Bad input to run_sim.py exits 2 before anything is built, naming the flag or field and what is allowed.

run_sim.main runs in this process (one import of pydrake for every case); the stop handlers it
installs at import are put back, so pytest keeps its own Ctrl-C.
"""

import importlib.util
import sys
from pathlib import Path

import pytest

from pedi_drake.evaluation.out_dir import claim_out_dir

REPO = Path(__file__).resolve().parents[1]
FIXTURES = Path(__file__).resolve().parent / "fixtures"


@pytest.fixture(scope="module")
def run_sim():
    spec = importlib.util.spec_from_file_location("run_sim_under_test", REPO / "run_sim.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    module.STOP.restore()
    return module


@pytest.fixture
def main(run_sim, monkeypatch, capsys, tmp_path):
    """main(*args) -> (exit code, stderr); --out defaults to a fresh folder under tmp_path."""

    def call(*args: str, out: Path | None = None):
        out = out if out is not None else tmp_path / "out"
        monkeypatch.setattr(sys, "argv", ["run_sim.py", "--out", str(out), *args])
        code = run_sim.main()
        return code, capsys.readouterr().err

    return call


def _rejected(main, tmp_path, *args, expect=()):
    code, err = main(*args)
    assert code == 2, err
    for text in expect:
        assert text in err, err
    assert "Traceback" not in err
    assert not (tmp_path / "out").exists(), "bad input must not leave an out dir"
    return err


@pytest.mark.parametrize(
    "text, expect",
    [
        ("{plant_config: {contact_model: bogus}}", ["plant_config.contact_model", "hydroelastic", "bogus"]),
        ("{plant_config: {discrete_contact_approximation: bogus}}", ["discrete_contact_approximation", "sap"]),
        ("{whole_body: {stack: bogus}}", ["whole_body.stack", "paper000"]),
        ("{controller: stand_pd}", ["controller", "whole_body"]),
        ("{sensor_noise: {enabled: true, gyro: -0.1}}", ["sensor_noise.gyro", ">= 0"]),
        ("{sensor_noise: {enabled: true}, random_seed: -3}", ["random_seed", "[0, "]),
        ("{visualization_period: -1}", ["visualization_period", "> 0"]),
        ("{lcm_buses: {go1: {lcm_url: 'udpm://bogus'}}}", ["lcm_buses['go1'].lcm_url", "udpm://GROUP:PORT"]),
        ("{lcm_buses: {go1: {lcm_url: 'udpm://239.255.76.67:99999'}}}", ["lcm_url"]),
    ],
)
def test_bad_scenario_text_exits_2_naming_the_field(main, tmp_path, text, expect):
    _rejected(main, tmp_path, "--scenario_text", text, expect=["--scenario_text", *expect])


def test_a_mission_under_stand_pd_exits_2(main, tmp_path):
    _rejected(
        main,
        tmp_path,
        "--mission",
        "hit_target_front",
        "--scenario_text",
        "{controller: stand_pd}",
        expect=["controller", "whole_body"],
    )


def test_a_bad_lcm_url_with_hardware_exits_2_not_a_missing_bridge(main, tmp_path):
    _rejected(
        main,
        tmp_path,
        "--hardware",
        "--scenario_text",
        "{lcm_buses: {go1: {lcm_url: 'tcp://nowhere'}}}",
        expect=["lcm_url", "tcp://nowhere"],
    )


def test_a_scene_object_duplicated_by_the_mission_exits_2(main, tmp_path):
    _rejected(
        main,
        tmp_path,
        "--scenario_name",
        "all_objects",
        "--mission",
        "hit_target_front",
        expect=["scene[8].name", "duplicate object name 'target_panel'"],
    )


def test_a_fixed_obstacle_inside_the_trunk_exits_2(main, tmp_path):
    _rejected(
        main,
        tmp_path,
        "--scenario_name",
        "stand",
        "--scenario_text",
        "{scene: [{kind: fixed_obstacle, position: [0, 0, 0]}]}",
        expect=["scene[0] (fixed_obstacle)", "overlaps the robot at its start pose"],
    )


def test_scene_objects_overlapping_each_other_exit_2(main, tmp_path):
    text = (
        "{scene: [{kind: fixed_obstacle, name: a, position: [0.8, 0, 0]},"
        " {kind: fixed_obstacle, name: b, position: [0.85, 0, 0]}]}"
    )
    _rejected(main, tmp_path, "--scenario_name", "stand", "--scenario_text", text, expect=["(a)", "overlaps", "(b)"])


def test_objects_apart_from_the_robot_and_each_other_pass_the_scene_check(run_sim):
    from pedi_drake.run_checks import check_scene_geometry
    from pedi_drake.scenario import load_scenario

    check_scene_geometry(load_scenario(scenario_name="all_objects"))


@pytest.mark.parametrize(
    "duration, expect",
    [("inf", "finite"), ("0.001", "one control tick"), ("nan", "> 0"), ("-1", "> 0")],
)
def test_a_duration_that_is_not_finite_or_shorter_than_a_tick_exits_2(main, tmp_path, duration, expect):
    _rejected(main, tmp_path, "--duration", duration, expect=["--duration", expect])


def test_out_pointing_at_a_file_exits_2(main, tmp_path):
    target = tmp_path / "a_file"
    target.write_text("mine")
    code, err = main("--scenario_name", "stand", out=target)
    assert code == 2 and "is a file, not a folder" in err and "--out" in err
    assert target.read_text() == "mine"


def test_out_in_a_folder_nobody_can_write_exits_2(main):
    # /proc takes no new files, not even from root (permission bits alone would pass for root).
    code, err = main("--scenario_name", "stand", out=Path("/proc/pedi_drake_out"))
    assert code == 2 and "not writable" in err and "--out" in err


def test_a_300_character_mission_name_exits_2(main, tmp_path):
    err = _rejected(main, tmp_path, "--mission", "m" * 300, expect=["300 characters", "at most 100"])
    assert len(err) < 400


def test_a_mission_scene_model_missing_beside_the_mission_exits_2(main, tmp_path):
    _rejected(
        main,
        tmp_path,
        "--mission",
        str(FIXTURES / "mission_missing_model.yaml"),
        expect=["mission_missing_model.yaml", "scene[0].model", "no_such_box.sdf", str(FIXTURES)],
    )


def test_a_mission_scene_model_is_found_beside_the_mission_not_in_the_current_folder(monkeypatch, tmp_path):
    from pedi_drake.mission.spec import load_mission

    monkeypatch.chdir(tmp_path)  # nothing here: the path must come from the mission's folder
    mission = load_mission(str(FIXTURES / "mission_local_model.yaml"))
    assert Path(mission.scene[0].model) == (FIXTURES / "models" / "local_box.sdf").resolve()


def test_a_world_target_below_the_floor_exits_2(main, tmp_path):
    _rejected(
        main,
        tmp_path,
        "--mission",
        str(FIXTURES / "mission_target_below_floor.yaml"),
        expect=["phases[2].target", "target below the floor", "-0.03"],
    )


def test_a_second_run_into_a_claimed_out_dir_exits_2(main, tmp_path):
    out = tmp_path / "shared"
    with claim_out_dir(out):
        code, err = main("--scenario_name", "stand", "--duration", "0.01", out=out)
    assert code == 2 and "another run" in err, err
    assert not (out / "result.json").exists()


def test_an_internal_error_prints_one_line_writes_error_txt_and_exits_1(main, monkeypatch, tmp_path):
    import pedi_drake.run

    def broken(**kwargs):
        raise ZeroDivisionError("a bug deep inside")

    monkeypatch.setattr(pedi_drake.run, "simulate", broken)
    code, err = main("--scenario_name", "stand", "--duration", "0.01")
    assert code == 1
    lines = err.strip().splitlines()
    assert len(lines) == 1 and "ZeroDivisionError" in lines[0] and "error.txt" in lines[0], err
    trace = (tmp_path / "out" / "error.txt").read_text()
    assert "Traceback" in trace and "a bug deep inside" in trace


def test_every_shipped_scenario_and_mission_passes_the_scene_check(run_sim):
    from pedi_drake.diagram import apply_mission
    from pedi_drake.mission.spec import load_mission, shipped_missions
    from pedi_drake.run_checks import check_scene_geometry
    from pedi_drake.scenario import load_scenario

    for name in ("default", "stand", "stand_with_prongs", "all_objects"):
        check_scene_geometry(load_scenario(scenario_name=name))
    for mission in shipped_missions():
        scenario = load_scenario(scenario_text=f"{{mission: {mission}}}")
        check_scene_geometry(apply_mission(scenario, load_mission(mission)))


def _run_sil(tmp_path, *args: str):
    """`python -m pedi_drake.apps.sil ARGS --out tmp_path/sil` from tmp_path, this checkout importable."""
    import os
    import subprocess

    env = dict(os.environ, PYTHONPATH=os.pathsep.join(filter(None, [str(REPO), os.environ.get("PYTHONPATH")])))
    return subprocess.run(
        [sys.executable, "-m", "pedi_drake.apps.sil", *args, "--out", str(tmp_path / "sil")],
        cwd=tmp_path,
        env=env,
        capture_output=True,
        text=True,
        timeout=300,
    )


def test_sil_with_an_unknown_mission_exits_2_with_the_real_error_before_starting_the_bridge(tmp_path):
    done = _run_sil(tmp_path, "--mission", "nope")
    assert done.returncode == 2, done.stderr
    assert "unknown mission 'nope'" in done.stderr and "hit_target_front" in done.stderr
    assert "Traceback" not in done.stderr and not (tmp_path / "sil").exists()


@pytest.mark.parametrize("rate", ["0", "-1", "nan"])
def test_sil_with_a_rate_that_is_not_positive_exits_2_before_starting_the_bridge(tmp_path, rate):
    done = _run_sil(tmp_path, "--mission", "hit_target_front", "--realtime_rate", rate)
    assert done.returncode == 2, done.stderr
    assert "--realtime_rate" in done.stderr and "Traceback" not in done.stderr
    assert not (tmp_path / "sil").exists()


@pytest.mark.parametrize(("flag", "value"), [("--flood_at", "-1"), ("--flood_rate", "0")])
def test_sil_with_a_flood_that_cannot_be_exits_2_before_starting_the_bridge(tmp_path, flag, value):
    flood = ["--flood_at", "2"] if flag != "--flood_at" else []
    done = _run_sil(tmp_path, "--mission", "hit_target_front", *flood, flag, value)
    assert done.returncode == 2, done.stderr
    assert flag in done.stderr and "Traceback" not in done.stderr
    assert not (tmp_path / "sil").exists()
