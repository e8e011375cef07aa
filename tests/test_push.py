"""Pushes: the scenario's and the mission's disturbances, applied by the simulated station only."""

import numpy as np
import pytest

from pedi_drake.diagram import LOG_MULTIPLEXER, MakePedipulationDiagram
from pedi_drake.exceptions import MissionFileError, ScenarioError
from pedi_drake.mission.spec import load_mission
from pedi_drake.run import simulate
from pedi_drake.scenario import Push, Scenario, load_scenario
from pedi_drake.station.disturbance import push_force_W, push_scale
from pedi_drake.station_interface import MakeStation


def test_push_ramps_up_holds_and_ramps_down():
    push = Push(force=30.0, start=1.0, ramp=0.5, duration=2.0)
    times = [0.99, 1.0, 1.25, 1.5, 2.5, 3.5, 3.75, 4.0, 4.01]
    assert [push_scale(push, t) for t in times] == pytest.approx([0, 0, 0.5, 1, 1, 1, 0.5, 0, 0])
    assert push.end() == pytest.approx(4.0)


def test_a_step_push_has_full_force_from_its_start():
    push = Push(force=5.0, direction=[0.0, 0.0, -1.0], start=0.2, ramp=0.0, duration=0.3)
    np.testing.assert_allclose(push_force_W(push, 0.2), [0.0, 0.0, -5.0])
    np.testing.assert_allclose(push_force_W(push, 0.51), 0.0)


def test_the_run_logs_the_applied_push_as_sim_push_force():
    push = Push(force=20.0, direction=[0.6, 0.8, 0.0], start=0.1, ramp=0.1, duration=0.1)
    scenario = Scenario(simulation_duration=0.5, estimator="ground_truth", pushes=[push])
    record = simulate(scenario=scenario, name="push", quiet=True, replay=False)
    log = record.logs["sim.push_force"]
    expected = np.array([push_force_W(push, t) for t in log.times]).T
    np.testing.assert_allclose(log.data, expected, atol=1e-9)
    assert np.max(np.linalg.norm(log.data, axis=0)) == pytest.approx(20.0)


def test_no_controller_estimator_or_mission_reads_the_push():
    built = MakePedipulationDiagram(load_scenario(scenario_text="{controller: whole_body, mission: hit_target_front}"))
    diagram = built.diagram
    station = diagram.GetSubsystemByName("station")
    push_port = station.GetOutputPort("sim.push_force")
    readers = [
        system.get_name()
        for (system, _), (source, index) in diagram.connection_map().items()
        if source is station and index == push_port.get_index()
    ]
    assert readers == [LOG_MULTIPLEXER]


def _scenario_file(tmp_path, push: str):
    path = tmp_path / "pushy.yaml"
    path.write_text(f"s:\n  pushes:\n    - {push}\n")
    return path


@pytest.mark.parametrize(
    "push,pattern",
    [
        (
            "{force: 10.0, direction: [1.0, 1.0, 0.0]}",
            r"pushy\.yaml \[s\]: pushes\[0\]\.direction: must be a unit vector",
        ),
        ("{force: -1.0}", r"pushy\.yaml \[s\]: pushes\[0\]\.force: must be a finite number >= 0"),
        ("{force: 1.0, point: [0.0, 0.1]}", r"pushes\[0\]\.point: expected \[x, y, z\]"),
        ("{force: 1.0, strat: 2.0}", r"pushes\[0\]\.strat: unknown field"),
    ],
)
def test_a_bad_scenario_push_names_the_file_and_field(tmp_path, push, pattern):
    with pytest.raises(ScenarioError, match=pattern):
        load_scenario(filename=_scenario_file(tmp_path, push), scenario_name="s")


def test_a_push_on_an_unknown_body_names_the_field_when_the_station_is_built():
    with pytest.raises(ScenarioError, match=r"pushes\[0\]\.body: 'tail': no body has that name"):
        MakeStation(Scenario(pushes=[Push(force=1.0, body="tail")]))


def test_a_bad_mission_push_names_the_file_and_field(tmp_path):
    path = tmp_path / "m.yaml"
    path.write_text("pushes:\n  - {force: 5.0, ramp: -0.5}\nphases:\n  - {kind: wait}\n")
    with pytest.raises(MissionFileError, match=r"m\.yaml: pushes\[0\]\.ramp: must be a finite number >= 0"):
        load_mission(str(path))


def test_a_mission_push_is_added_to_the_scenario_s():
    push = load_mission("demos/push_prongs").pushes[0]
    assert push.force == 30.0 and push.body == "trunk" and push.direction == [0.0, -1.0, 0.0]
