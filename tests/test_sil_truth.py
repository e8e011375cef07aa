"""apps.sil's judgement by the robot side's truth log: touches by contact force, the estimate's trunk
height, and the mission's physical checks on the plant's state."""

import numpy as np
import pytest

from pedi_drake.apps.bridge_options import bridge_scenario
from pedi_drake.apps.sil import estimator_height_error, truth_checks, truth_touches
from pedi_drake.mission.spec import Touch
from pedi_drake.run_logs import SignalLog
from pedi_drake.scenario import load_scenario
from pedi_drake.station.scene import root_body
from pedi_drake.station_interface import MakeStation

PERIOD = 0.002  # [s] controller tick


def _controller_logs(wall_start: float, n: int, z_estimated: np.ndarray) -> dict[str, SignalLog]:
    times = PERIOD * np.arange(n)
    base = np.zeros((13, n))
    base[6] = z_estimated
    return {"wall_clock": SignalLog(times, (wall_start + times)[np.newaxis, :]), "base_state": SignalLog(times, base)}


def test_a_touch_counts_in_its_phase_on_the_controllers_clock():
    logs = _controller_logs(1000.0, 1000, np.zeros(1000))  # the controller ran from wall 1000 to 1002
    wall = 999.0 + 0.01 * np.arange(400)  # the bridge from 999 to 1003
    forces = np.zeros((400, 10))  # two objects
    forces[(wall > 1001.2) & (wall < 1001.3), 5] = 3.0  # panel (object 1), FR, at t = 1.2..1.3 s
    forces[wall < 1000.0, 9] = 50.0  # before the controller ran: not judged
    truth = {"wall_time": wall, "scene_names": np.array(["box", "panel"]), "scene_contact_forces": forces}
    phases = [{"name": "reach", "t_start": 1.0, "t_end": 1.5}, {"name": "early", "t_start": 0.0, "t_end": 0.5}]
    touches = [Touch(object="panel", leg="FR", phase="reach", force=1.0)]
    rows, problem = truth_touches({"phases": phases}, touches, logs, truth)
    assert problem == ""
    assert rows[0]["touched"] and rows[0]["max_normal_force_n"] == 3.0
    assert abs(rows[0]["max_force_at_s"] - 1.21) < 0.011
    missed, problem = truth_touches({"phases": phases}, [Touch("panel", "other", "early", 1.0)], logs, truth)
    assert not missed[0]["touched"] and "did not touch panel" in problem


def test_a_touch_of_an_object_the_truth_does_not_know_is_a_problem():
    logs = _controller_logs(0.0, 10, np.zeros(10))
    truth = {"wall_time": 0.01 * np.arange(3), "scene_names": np.array([]), "scene_contact_forces": np.zeros((3, 0))}
    rows, problem = truth_touches({"phases": []}, [Touch("panel", "FR", "reach", 1.0)], logs, truth)
    assert rows == [] and "panel" in problem


def test_the_height_error_counts_only_while_standing():
    n = 1000
    wall = 50.0 + 0.01 * np.arange(200)
    p_WB = np.zeros((200, 3))
    p_WB[:, 2] = np.where(wall < 51.0, 0.1, 0.28)  # lying for a second, then standing
    # The estimate 10 mm below the truth throughout, 1 m below it at the first tick while lying.
    z_estimated = np.interp(50.0 + PERIOD * np.arange(n), wall, p_WB[:, 2]) - 0.01
    z_estimated[1] -= 1.0
    logs = _controller_logs(50.0, n, z_estimated)
    error = estimator_height_error(logs, {"wall_time": wall, "p_WB": p_WB})
    assert abs(error["median_m"] - 0.01) < 1e-9 and abs(error["max_m"] - 0.01) < 1e-9  # not the lying one
    assert 0 < error["samples"] < n
    never = estimator_height_error(logs, {"wall_time": wall, "p_WB": np.zeros((200, 3))})
    assert never["median_m"] is None and never["samples"] == 0


def test_the_height_error_leaves_out_a_trunk_rising_or_lowering():
    # Standing, then lowered from 0.28 to 0.22 m at 5 cm/s (a lean on the prongs), then still: the
    # estimate lags the motion by 20 mm while it moves and is 1 mm off while still.
    n = 1000
    wall = 50.0 + 0.01 * np.arange(200)
    z_true = np.interp(wall, [50.0, 50.5, 51.7, 52.0], [0.28, 0.28, 0.22, 0.22])
    p_WB = np.zeros((200, 3))
    p_WB[:, 2] = z_true
    t = 50.0 + PERIOD * np.arange(n)
    moving = (t > 50.5) & (t < 51.7)
    z_estimated = np.interp(t, wall, z_true) + np.where(moving, 0.02, 0.001)
    error = estimator_height_error(_controller_logs(50.0, n, z_estimated), {"wall_time": wall, "p_WB": p_WB})
    assert abs(error["max_m"] - 0.001) < 1e-6


def _push_light_box_truth(box_shift: float) -> tuple[object, dict, dict]:
    """The robot side's scenario of push_light_box, the controller's logs (wall 1000 to 1003 s) and
    a truth log from wall 999 to 1004 s in which the box moves `box_shift` [m] along x during the
    push phase (1-2 s on the controller's clock)."""
    scenario = bridge_scenario(load_scenario(), "push_light_box")
    plant = MakeStation(scenario).GetSubsystemByName("plant")
    q0 = plant.GetPositions(plant.CreateDefaultContext())
    wall = 999.0 + 0.01 * np.arange(501)
    ramp = np.clip(wall - 1001.0, 0.0, 1.0)
    states = np.zeros((len(wall), plant.num_multibody_states()))
    states[:, : len(q0)] = q0
    box = root_body(plant, plant.GetModelInstanceByName("light_box"))
    states[:, box.floating_positions_start() + 4] += box_shift * ramp
    truth = {
        "wall_time": wall,
        "plant_states": states,
        "scene_names": np.array([obj.instance_name for obj in scenario.scene]),
        "scene_contact_forces": np.zeros((len(wall), 5 * len(scenario.scene))),
        "foot_contact_forces": np.zeros((len(wall), 12)),
    }
    return scenario, _controller_logs(1000.0, 1500, np.zeros(1500)), truth


def test_the_truth_logs_plant_state_judges_the_missions_object_push():
    phases = [{"name": "push_box", "kind": "press", "t_start": 1.0, "t_end": 2.0}]
    scenario, logs, truth = _push_light_box_truth(0.12)
    rows, problem = truth_checks("push_light_box", scenario, {"phases": phases}, logs, truth)
    assert problem == "" and rows["object_push"]["moved_m"] == pytest.approx(0.12, abs=1e-3)
    scenario, logs, truth = _push_light_box_truth(0.04)
    rows, problem = truth_checks("push_light_box", scenario, {"phases": phases}, logs, truth)
    assert "light_box moved 4.0 cm" in problem
    # The MuJoCo robot's truth log has no plant state: nothing more to judge.
    del truth["plant_states"]
    assert truth_checks("push_light_box", scenario, {"phases": phases}, logs, truth) == ({}, "")
