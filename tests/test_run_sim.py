"""run_sim.py from the command line: exit codes and the files it writes."""

import importlib.util
import json
import re
import subprocess
import sys
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]


def _run(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "run_sim.py", *args], cwd=REPO, capture_output=True, text=True, timeout=600)


def test_run_sim_writes_result_json_replay_and_plots(tmp_path):
    done = _run("--scenario_name", "stand", "--out", str(tmp_path), "--duration", "2.5")
    assert done.returncode == 0, done.stderr
    result = json.loads((tmp_path / "result.json").read_text())
    for key in ("mission", "scenario", "success", "phases", "fell", "sim_time_s", "wall_time_s", "real_time_factor"):
        assert key in result
    assert result["success"] is True and result["fell"] is False
    assert result["sim_time_s"] == 2.5
    html = (tmp_path / "replay.html").read_text()
    assert len(html) > 10_000 and "<html" in html.lower()
    assert (tmp_path / "joint_positions.png").stat().st_size > 0


def test_run_sim_unknown_mission_exits_2_listing_the_library(tmp_path):
    done = _run("--mission", "fly_to_the_moon", "--out", str(tmp_path))
    assert done.returncode == 2
    assert "shipped missions" in done.stderr and "hit_target_front" in done.stderr


def test_run_sim_bad_input_exits_2_naming_the_field(tmp_path):
    done = _run("--out", str(tmp_path), "--scenario_text", "{robot: {initial_pos: lying}}")
    assert done.returncode == 2
    assert "robot.initial_pos" in done.stderr
    assert not (tmp_path / "result.json").exists()


def _graph_edges(dot: str) -> set[tuple[str, str]]:
    """(source, destination) system names of every connection in a GetGraphvizString drawing."""
    names = dict(re.findall(r"^(s\d+) \[shape=none, border=0, label=<.*?name=([^<\n]+)", dot, re.M | re.S))
    return {(names[a], names[b]) for a, b in re.findall(r"^(s\d+):y\d+:e -> (s\d+):u\d+:w", dot, re.M)}


def test_run_sim_graphviz_draws_the_run_wired_station_to_controller(tmp_path):
    dot = tmp_path / "diagram.dot"
    args = ("--mission", "hit_target_front", "--duration", "0.05", "--graphviz", str(dot), "--out", str(tmp_path))
    done = _run(*args)
    assert "diagram written" in done.stdout, done.stderr
    edges = _graph_edges(dot.read_text())
    for edge in (
        ("station", "estimator"),
        ("estimator", "mission"),
        ("station", "mission"),
        ("mission", "ik.FR"),
        ("ik.FR", "mission"),
        ("mission", "controller"),
        ("estimator", "controller"),
        ("controller", "station"),
    ):
        assert edge in edges, (edge, sorted(edges))


def _prepared(*argv: str):
    spec = importlib.util.spec_from_file_location("run_sim_script", REPO / "run_sim.py")
    script = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(script)
    return script, script._prepare(script.command_line().parse_args(list(argv)))


def test_teleop_runs_the_teleoperated_mission_as_the_readme_starts_it():
    script, (scenario, _, _) = _prepared("--teleop")
    assert scenario.mission == script.TELEOP_MISSION and scenario.operator.source == "meshcat"


def test_teleop_with_a_mission_runs_that_mission_under_the_panel():
    _, (scenario, _, _) = _prepared("--teleop", "--mission", "give_paw")
    assert scenario.mission == "give_paw" and scenario.operator.source == "meshcat"


def test_teleop_on_a_scenario_with_an_operator_mission_runs_it_on_the_scenarios_controller():
    # estop_paper002 names paper 002's controller, its Eq. 11 estimate and the E-stop mission.
    _, (scenario, _, _) = _prepared("--teleop", "--scenario_name", "estop_paper002")
    assert scenario.mission == "operator/press_estop_button" and scenario.operator.source == "meshcat"
    assert scenario.controller == "projected_impedance" and scenario.force_estimate == "impedance"


def test_a_mission_named_on_the_command_line_keeps_the_scenarios_controller():
    _, (scenario, _, _) = _prepared("--scenario_name", "teleop_paper002", "--mission", "give_paw")
    assert scenario.mission == "give_paw" and scenario.controller == "projected_impedance"
    _, (scenario, _, _) = _prepared("--mission", "give_paw")
    assert scenario.controller == "whole_body"
