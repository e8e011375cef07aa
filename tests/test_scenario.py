"""Scenario loading: shipped scenarios load; every kind of mistake names the file and the field."""

from pathlib import Path

import pytest

from pedi_drake.exceptions import ScenarioError
from pedi_drake.scenario import default_scenario_file, load_scenario


def _write(tmp_path: Path, body: str) -> Path:
    path = tmp_path / "bad.yaml"
    path.write_text(body)
    return path


def test_every_shipped_scenario_loads():
    from pydrake.common.yaml import yaml_load

    names = yaml_load(filename=str(default_scenario_file())).keys()
    assert "default" in names
    for name in names:
        load_scenario(scenario_name=name)


def test_unknown_key_names_file_and_field(tmp_path):
    path = _write(tmp_path, "s:\n  robot:\n    initial_pos: lying\n")
    with pytest.raises(ScenarioError, match=r"bad\.yaml.*robot\.initial_pos: unknown field"):
        load_scenario(filename=path, scenario_name="s")


def test_wrong_type_names_file_and_field(tmp_path):
    path = _write(tmp_path, "s:\n  scene:\n    - {kind: box, position: left}\n")
    with pytest.raises(ScenarioError, match=r"bad\.yaml.*scene\[0\]\.position: expected a list"):
        load_scenario(filename=path, scenario_name="s")


def test_missing_model_file_names_file_and_field(tmp_path):
    path = _write(tmp_path, "s:\n  scene:\n    - {kind: box, model: no_such_box.sdf}\n")
    with pytest.raises(ScenarioError, match=r"bad\.yaml.*scene\[0\]\.model: model file not found"):
        load_scenario(filename=path, scenario_name="s")


def test_model_path_relative_to_the_scenario_file_is_resolved(tmp_path):
    box = (Path(__file__).parents[1] / "models" / "scenes" / "box.sdf").read_text()
    (tmp_path / "my_box.sdf").write_text(box)
    path = _write(tmp_path, "s:\n  scene:\n    - {kind: box, model: my_box.sdf}\n")
    scenario = load_scenario(filename=path, scenario_name="s")
    assert Path(scenario.scene[0].model) == (tmp_path / "my_box.sdf").resolve()


def test_unknown_prong_field_names_file_and_field(tmp_path):
    path = _write(tmp_path, "s:\n  robot:\n    prongs: {lenght: 0.1}\n")
    with pytest.raises(ScenarioError, match=r"bad\.yaml.*robot\.prongs\.lenght: unknown field"):
        load_scenario(filename=path, scenario_name="s")


def test_invalid_prong_value_names_the_field(tmp_path):
    path = _write(tmp_path, "s:\n  robot:\n    prongs: {tip_radius: -0.01}\n")
    with pytest.raises(ScenarioError, match=r"bad\.yaml.*robot\.prongs\.tip_radius"):
        load_scenario(filename=path, scenario_name="s")


def test_value_outside_allowed_set_lists_the_choices(tmp_path):
    path = _write(tmp_path, "s:\n  scene:\n    - {kind: piano}\n")
    with pytest.raises(ScenarioError, match=r"scene\[0\]\.kind: must be one of"):
        load_scenario(filename=path, scenario_name="s")


def test_unknown_scenario_name_lists_the_available_ones():
    with pytest.raises(ScenarioError, match=r"no scenario named 'nope'; available: .*default"):
        load_scenario(scenario_name="nope")


def test_missing_scenario_file_is_named(tmp_path):
    with pytest.raises(ScenarioError, match=r"nothere\.yaml: scenario file not found"):
        load_scenario(filename=tmp_path / "nothere.yaml")


def test_scenario_text_overrides_and_is_validated():
    scenario = load_scenario(scenario_text="{simulation_duration: 1.5, robot: {initial_pose: standing}}")
    assert scenario.simulation_duration == 1.5 and scenario.robot.initial_pose == "standing"
    with pytest.raises(ScenarioError, match=r"--scenario_text: simulation_duration: expected a number"):
        load_scenario(scenario_text="{simulation_duration: soon}")
