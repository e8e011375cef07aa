"""The E-stop button scenario: a scripted operator (the shipped press_estop_button.ops, on an
in-process LCM bus) teleoperates the FR foot onto the button's cap; the judge reads the plunger's
travel and the foot's contact force from the simulation's ground truth and requires the plunger
past its trip travel with the force under the teleop phase's bound, on the HQP with the
joint-torque estimate and on paper 002's controller with its Eq. 11 estimate (the shipped scenario
estop_paper002). The same mission with an operator who stops above the cap (2 cm of the 7 cm
descent) fails on the press alone; the judge's check also fails on synthetic traces (too little
travel, too much force, outside the phase), and the mission file's check is validated on load.
Run with -s to see the measured numbers.
"""

import numpy as np
import pytest

from pedi_drake.apps.teleop_lcm import parse_script
from pedi_drake.benchmarks.estop_button import SCRIPT, run_scripted_press
from pedi_drake.evaluation.button_press import judge_button_press
from pedi_drake.exceptions import MissionFileError
from pedi_drake.mission.spec import ButtonPress, load_mission
from pedi_drake.operator.command import FRAME_WORLD, MODE_AUTONOMOUS
from pedi_drake.resources import missions_dir
from pedi_drake.station.scene import ESTOP_BUTTON_TRIP_TRAVEL
from pedi_drake.station.scene_contact import ROBOT_CONTACT_SOURCES, scene_contact_index

# The press step of the shipped script (down 7 cm at 2 cm/s from 9.94 s) cut to 1 s: the foot stops
# 2 cm lower, still above the cap, holds, and the rest of the script brings it back.
PRESS_STEP = "9.94   none        0     0  -0.02"
STOPS_SHORT = PRESS_STEP + "\n10.94  none        0     0  0"


def _run(script: str, name: str, scenario_name: str = "default") -> dict:
    return run_scripted_press(scenario_name, "", script, name)


def _describe(result: dict) -> str:
    press = result["button_press"]
    return (
        f"plunger in {1000 * press['max_travel_m']:.1f} mm (trips at {1000 * press['trip_travel_m']:.1f} mm) "
        f"at {press['pressed_at_s']} s; largest foot force {press['max_force_n']:.2f} N (bound "
        f"{press['force_bound_n']:.1f} N), {press['force_at_press_n']} N at the trip; phases "
        f"{[(row['name'], row['status'], row['t_end']) for row in result['phases']]}; reason {result['reason']!r}"
    )


@pytest.fixture(scope="module")
def pressed_run():
    return _run(SCRIPT.read_text(), str(SCRIPT))


@pytest.fixture(scope="module")
def paper002_run():
    return _run(SCRIPT.read_text(), "press_estop_button on paper 002's controller", "estop_paper002")


@pytest.fixture(scope="module")
def short_run():
    text = SCRIPT.read_text()
    assert PRESS_STEP in text
    return _run(text.replace(PRESS_STEP, STOPS_SHORT), "press_estop_button, stopping short")


def test_the_operator_presses_the_button_with_the_force_under_the_bound(pressed_run):
    print(f"\nE-stop button pressed: {_describe(pressed_run)}")
    press = pressed_run["button_press"]
    assert press["pressed"] and press["max_travel_m"] >= ESTOP_BUTTON_TRIP_TRAVEL
    assert press["gentle"] and press["max_force_n"] <= press["force_bound_n"]
    assert press["max_force_n"] > 0.0  # the foot, not another part of the leg, pressed it


def test_paper_002s_controller_bounded_by_its_eq_11_estimate_presses_it_under_the_bound(paper002_run):
    print(f"\nE-stop button on paper 002's controller: {_describe(paper002_run)}")
    press = paper002_run["button_press"]
    assert paper002_run["success"], paper002_run["reason"]
    assert press["pressed"] and press["max_force_n"] <= press["force_bound_n"]
    assert paper002_run["controller"] == "projected_impedance"


def test_the_mission_succeeds_and_the_robot_stays_up(pressed_run):
    assert not pressed_run["fell"]
    assert pressed_run["success"], pressed_run["reason"]
    assert [row["status"] for row in pressed_run["phases"]] == ["succeeded"] * 4
    # The operator's request ended the teleop phase (operator silence would fail it, its duration
    # is 40 s): it ends within three mission ticks (10 ms) of the script's first autonomous step.
    steps = parse_script(SCRIPT.read_text(), str(SCRIPT), frame=FRAME_WORLD)
    t_autonomous = next(step.start for step in steps if step.mode_request == MODE_AUTONOMOUS)
    teleop = next(row for row in pressed_run["phases"] if row["name"] == "teleop")
    assert t_autonomous <= teleop["t_end"] <= t_autonomous + 0.03


def test_an_operator_stopping_short_of_the_cap_fails_the_mission(short_run):
    # Every phase runs to its end and the robot stays up: the only thing missing is the press.
    print(f"\nE-stop button, operator stopping short: {_describe(short_run)}")
    press = short_run["button_press"]
    assert not short_run["fell"]
    assert [row["status"] for row in short_run["phases"]] == ["succeeded"] * 4
    assert not press["pressed"] and press["max_travel_m"] < ESTOP_BUTTON_TRIP_TRAVEL
    assert not short_run["success"]
    assert short_run["reason"].startswith("teleop: the FR foot did not press estop_button"), short_run["reason"]


# Synthetic traces for the judge: one button, the phase "teleop" from 1 s to 3 s.
PHASES = [{"name": "teleop", "t_start": 1.0, "t_end": 3.0}]
SCENE = ["estop_button"]
CHECK = ButtonPress(button="estop_button", leg="FR", phase="teleop")
TIMES = np.linspace(0.0, 4.0, 401)


def _judge(travel, force, bound=15.0):
    forces = np.zeros((len(ROBOT_CONTACT_SOURCES), TIMES.size))
    forces[scene_contact_index("estop_button", "FR", SCENE)] = force
    return judge_button_press(CHECK, bound, PHASES, TIMES, travel, SCENE, TIMES, forces)


def _bump(height, centre=2.0, width=0.2):
    return np.where(np.abs(TIMES - centre) < width, height, 0.0)


def test_a_press_past_the_trip_travel_under_the_bound_passes():
    row, problem = _judge(_bump(0.010), _bump(6.0))
    assert problem == "" and row["pressed"] and row["gentle"]
    assert 1.79 < row["pressed_at_s"] < 1.82 and row["force_at_press_n"] == pytest.approx(6.0)


def test_a_plunger_short_of_its_trip_travel_is_not_a_press():
    row, problem = _judge(_bump(0.007), _bump(6.0))
    assert not row["pressed"] and "did not press" in problem and "7.0 mm" in problem


def test_a_press_with_a_force_over_the_bound_fails_naming_the_force():
    row, problem = _judge(_bump(0.012), _bump(16.0))
    assert row["pressed"] and not row["gentle"] and "16.0 N" in problem and "15.0 N" in problem


def test_a_press_outside_the_phase_does_not_count():
    row, problem = _judge(_bump(0.010, centre=3.6), _bump(6.0, centre=3.6))
    assert not row["pressed"] and problem


def test_the_mission_file_check_names_a_bad_button_or_phase(tmp_path):
    source = (missions_dir() / "operator" / "press_estop_button.yaml").read_text()
    for bad, field in (("button: estop_button,", "button: nothing,"), ("phase: teleop}", "phase: 0_stand_up}")):
        path = tmp_path / "bad.yaml"
        path.write_text(source.replace(bad, field))
        name = "button" if "button" in bad else "phase"
        with pytest.raises(MissionFileError, match=rf"button_press\.{name}"):
            load_mission(str(path))
