"""register_phase_kind: a phase kind added at run time loads from a mission file, and a
registration that would replace or break a kind is refused."""

import dataclasses

import pytest

from pedi_drake.exceptions import MissionFileError
from pedi_drake.mission import phases, spec
from pedi_drake.mission.progress import SUCCEEDED


@dataclasses.dataclass
class Pause(spec.PhaseBase):
    """Holds still for `duration` [s]."""

    duration: float = 0.2


class PauseRunner(phases.PhaseRunner):
    def step(self, phase, progress, view, env):
        return SUCCEEDED


def test_a_registered_kind_loads_from_a_mission_file(tmp_path, phase_tables_restored):
    phases.register_phase_kind("pause", Pause, PauseRunner())
    path = tmp_path / "pause.yaml"
    path.write_text("phases:\n  - {kind: stand_up}\n  - {kind: pause, duration: 0.5}\n")
    mission = spec.load_mission(str(path))
    assert isinstance(mission.phases[1], Pause) and mission.phases[1].duration == 0.5
    assert phases.kind_name(mission.phases[1]) == "pause"
    assert isinstance(phases.RUNNERS[Pause], PauseRunner)


def test_a_registered_kind_gets_the_common_value_checks(tmp_path, phase_tables_restored):
    phases.register_phase_kind("pause", Pause, PauseRunner())
    path = tmp_path / "pause.yaml"
    path.write_text("phases:\n  - {kind: pause, duration: -1.0}\n")
    with pytest.raises(MissionFileError, match=r"phases\[0\]\.duration"):
        spec.load_mission(str(path))


def test_an_existing_kind_is_never_replaced(phase_tables_restored):
    with pytest.raises(MissionFileError, match="already registered"):
        phases.register_phase_kind("reach", Pause, PauseRunner())
    phases.register_phase_kind("pause", Pause, PauseRunner())
    with pytest.raises(MissionFileError, match="already registered"):
        phases.register_phase_kind("pause_again", Pause, PauseRunner())


@pytest.mark.parametrize(
    "name,spec_class,runner,pattern",
    [
        ("two words", Pause, PauseRunner(), "identifier"),
        ("plain", dict, PauseRunner(), "dataclass deriving from PhaseBase"),
        ("plain", Pause, object(), "PhaseRunner"),
    ],
)
def test_a_malformed_registration_is_refused(name, spec_class, runner, pattern, phase_tables_restored):
    with pytest.raises(MissionFileError, match=pattern):
        phases.register_phase_kind(name, spec_class, runner)
    assert name not in spec.PHASE_KINDS
