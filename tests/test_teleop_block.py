"""A mission file's `teleop:` block is validated on load: a bad value names the file and the
field, and run_sim.py exits 2 before anything is built."""

import subprocess
import sys
from pathlib import Path

import pytest

from pedi_drake.exceptions import MissionFileError
from pedi_drake.mission.mission_manager import ik_legs_of
from pedi_drake.mission.mode_switch import teleop_sequence
from pedi_drake.mission.spec import LegToPedipulation, LegToSupport, Reach, TeleopFoot, load_mission

PHASES = "phases:\n  - {kind: wait, duration: 0.5}\n"


def _mission(tmp_path: Path, teleop: str) -> Path:
    path = tmp_path / "with_teleop.yaml"
    path.write_text(f"teleop: {teleop}\n{PHASES}")
    return path


@pytest.mark.parametrize(
    ("teleop", "field"),
    [
        ("{leg: XX}", "teleop.leg"),
        ("{max_speed: -0.1}", "teleop.max_speed"),
        ("{max_force: .nan}", "teleop.max_force"),
        ("{hold_after: 1.0, return_after: 0.5}", "teleop.return_after"),
        ("{working_depth: 0.0}", "teleop.working_depth"),
        ("{leg_duration: 0}", "teleop.leg_duration"),
        ("{speed_limit: 0.1}", "teleop.speed_limit"),
        ("{max_speed: fast}", "teleop.max_speed"),
    ],
)
def test_a_bad_teleop_value_names_file_and_field(tmp_path, teleop, field):
    path = _mission(tmp_path, teleop)
    with pytest.raises(MissionFileError, match=field.replace(".", r"\.")) as error:
        load_mission(str(path))
    assert str(path) in str(error.value)


def test_the_teleop_block_sets_the_inserted_phases(tmp_path):
    mission = load_mission(
        str(_mission(tmp_path, "{leg: FL, max_speed: 0.08, working_depth: 0.17, leg_duration: 0.9}"))
    )
    assert ik_legs_of(mission) == ("FL",)  # the inserted lift and placing need the leg's IK
    lift, foot, place = teleop_sequence(mission.teleop, lifted=False, p_foot_W=[0.2, 0.1, 0.1], number=3)
    assert isinstance(lift, LegToPedipulation) and lift.working_depth == 0.17 and lift.duration == 0.9
    assert isinstance(foot, TeleopFoot) and foot.leg == "FL" and foot.max_speed == 0.08 and foot.name == "teleop_3"
    assert isinstance(place, LegToSupport) and place.leg == "FL"
    foot, back = teleop_sequence(mission.teleop, lifted=True, p_foot_W=[0.2, 0.1, 0.1], number=1)
    assert isinstance(back, Reach) and back.target == [0.2, 0.1, 0.1] and back.frame == "world"


def test_run_sim_exits_2_on_a_bad_teleop_block(tmp_path):
    path = _mission(tmp_path, "{leg: XX}")
    repo = Path(__file__).resolve().parents[1]
    result = subprocess.run(
        [sys.executable, str(repo / "run_sim.py"), "--mission", str(path), "--out", str(tmp_path / "out")],
        capture_output=True,
        text=True,
        cwd=repo,
        timeout=120,
    )
    assert result.returncode == 2
    assert str(path) in result.stderr and "teleop.leg" in result.stderr
