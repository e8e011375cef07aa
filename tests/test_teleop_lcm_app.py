"""The command-line operator (pedi_drake.apps.teleop_lcm): its script format, the messages it
publishes (decoded back), and its keys."""

import subprocess
import sys

import numpy as np
import pytest
from pydrake.lcm import DrakeLcm

from pedi_drake.apps.teleop_lcm import KeyboardOperator, ScriptError, parse_script, play_script
from pedi_drake.go1_driver.lcmtypes import foot_command_lcmt
from pedi_drake.operator.command import FRAME_TRUNK, MODE_AUTONOMOUS, MODE_NONE, MODE_TELEOP
from pedi_drake.operator.message_stream import write_lcm_log
from pedi_drake.operator.messages import foot_command_in_range, foot_command_vector

SCRIPT = """# t_s mode vx vy vz
0.0 teleop 0 0 0
0.1 none 0.05 0 0   # forward
0.2 autonomous 0 0 0
0.3 estop 0 0 0
"""


def test_a_script_becomes_its_steps():
    steps = parse_script(SCRIPT)
    assert [s.start for s in steps] == [0.0, 0.1, 0.2, 0.3]
    assert [s.mode_request for s in steps] == [MODE_TELEOP, MODE_NONE, MODE_AUTONOMOUS, MODE_NONE]
    assert steps[1].value == (0.05, 0.0, 0.0) and [s.estop for s in steps] == [False, False, False, True]


def test_a_friction_line_keeps_the_command_and_adds_the_request():
    steps = parse_script(SCRIPT.replace("0.2 autonomous", "0.15 friction 0.2\n0.2 autonomous"))
    assert steps[2].start == 0.15 and steps[2].friction_request == 0.2
    assert (steps[2].mode_request, steps[2].value) == (steps[1].mode_request, steps[1].value)


@pytest.mark.parametrize(
    ("text", "problem"),
    [
        ("0 teleop 0 0", "expected 't_s mode vx vy vz'"),
        ("0 walk 0 0 0", "mode must be one of"),
        ("0 teleop 0 nan 0", "finite"),
        ("0 teleop x 0 0", "numbers"),
        ("1 teleop 0 0 0\n0.5 none 0 0 0", "increasing"),
        ("# nothing", "no steps"),
        ("0 teleop 0 0 0\n1 friction 2.0", r"friction coefficient must be in \[0.05, 1.5\]"),
        ("0 teleop 0 0 0\n1 friction wet", "numbers"),
    ],
)
def test_a_bad_script_line_is_named(text, problem):
    with pytest.raises(ScriptError, match=problem) as error:
        parse_script(text, "ops.txt")
    assert str(error.value).startswith("ops.txt")


def test_the_script_is_published_as_valid_foot_commands():
    lcm = DrakeLcm("memq://")
    received = []
    lcm.Subscribe("operator_foot_command", lambda data: received.append(foot_command_lcmt.decode(data)))
    count = play_script(parse_script(SCRIPT), lcm, "operator_foot_command", rate=50.0, sleep=lambda _: None)
    lcm.HandleSubscriptions(0)
    assert count == len(received) == 16  # 0.3 s at 50 Hz, both ends
    vectors = np.array([foot_command_vector(m) for m in received])
    assert all(foot_command_in_range(v) for v in vectors)
    assert [m.sequence for m in received] == list(range(1, 17))
    assert np.allclose(vectors[5], [MODE_NONE, FRAME_TRUNK, 0, 0.05, 0.0, 0.0, 0.0, 0.0, 0.0])  # t = 0.1 s
    assert vectors[0][0] == MODE_TELEOP and vectors[10][0] == MODE_AUTONOMOUS and vectors[-1][6] == 1.0


def test_the_keys_set_velocity_mode_stop_and_estop():
    operator = KeyboardOperator(speed=0.05, frame=FRAME_TRUNK)
    operator.press("t")
    operator.press("d")
    assert operator.step.mode_request == MODE_TELEOP and operator.step.value == (0.0, -0.05, 0.0)
    operator.press(" ")
    assert operator.step.value == (0.0, 0.0, 0.0) and operator.step.mode_request == MODE_TELEOP
    operator.press("g")
    operator.press("e")
    assert operator.step.mode_request == MODE_AUTONOMOUS and operator.step.estop
    assert operator.press("q") is False


def test_the_app_exits_2_on_a_bad_script(tmp_path):
    script = tmp_path / "ops.txt"
    script.write_text("0 teleop 0 0 0\n0.1 dance 0 0 0\n")
    result = subprocess.run(
        [sys.executable, "-m", "pedi_drake.apps.teleop_lcm", "--script", str(script), "--lcm_url", "memq://"],
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert result.returncode == 2 and f"{script}:2" in result.stderr


def test_the_app_exits_2_on_a_missing_or_empty_message_log(tmp_path):
    empty = write_lcm_log([], tmp_path / "empty.lcmlog")
    for path in (tmp_path / "missing.lcmlog", empty):
        result = subprocess.run(
            [sys.executable, "-m", "pedi_drake.apps.teleop_lcm", "--lcm_log", str(path), "--lcm_url", "memq://"],
            capture_output=True,
            text=True,
            timeout=60,
        )
        assert result.returncode == 2 and result.stderr.strip(), (path, result.stderr)


def test_the_feedback_line_shows_the_force_the_balance_margin_and_the_suf():
    from pedi_drake.apps.teleop_lcm import feedback_text
    from pedi_drake.operator.feedback import feedback_message, feedback_vector

    message = feedback_message(feedback_vector(0, np.array([-6.0, 0.0, 8.0]), 14.0, 22.5, 1, True), 3.0, 7)
    text = feedback_text(message)
    assert "FR foot force  10.0 N" in text and "margin   4.0 N" in text and "SUF  22.5 N" in text
    assert "BOUND ACTING" in text
    off = feedback_message(feedback_vector(0, np.zeros(3), float("nan"), float("nan"), 0, False), 3.0, 8)
    assert "balance bound off" in feedback_text(off) and "SUF" not in feedback_text(off)
    assert feedback_text(None) == "no feedback yet"
    assert feedback_text(feedback_message(feedback_vector(-1, None, 0.0, 0.0, 0, False), 3.0, 9)) == "no foot driven"
