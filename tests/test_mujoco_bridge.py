"""The MuJoCo robot side (pedi_drake.apps.mujoco_go1, mujoco_scene, mujoco_bridge): the model, the wire, the scenes."""

import importlib.util
import subprocess
import sys

import mujoco
import numpy as np
import pytest
from pydrake.lcm import DrakeLcm
from pydrake.systems.analysis import Simulator

from pedi_drake import robot
from pedi_drake.apps.bridge_options import bridge_scenario
from pedi_drake.apps.mujoco_bridge import MujocoBridge
from pedi_drake.apps.mujoco_go1 import HOLD_KD, HOLD_KP, MJCF_PATH, MujocoGo1
from pedi_drake.apps.sim_bridge import DRAKE_ONLY_TRUTH, MakeSimBridgeDiagram, write_truth_log
from pedi_drake.apps.status_sample import SAMPLE
from pedi_drake.go1_command import pack_command, split_command
from pedi_drake.go1_driver import constants as c
from pedi_drake.go1_driver.config import Go1BridgeConfig
from pedi_drake.go1_driver.lcmtypes import leg_control_data_lcmt, state_estimator_lcmt
from pedi_drake.mission.spec import load_mission, shipped_missions
from pedi_drake.prongs import ProngDesign
from pedi_drake.scenario import Push, SceneObject, load_scenario
from pedi_drake.station.scene import SCENE_MODELS
from pedi_drake.station.scene_contact import scene_contact_index

STAND_KP, STAND_KD = 80.0, 3.0  # [N m/rad], [N m s/rad]


def _generator():
    spec = importlib.util.spec_from_file_location("generate_go1_mjcf", MJCF_PATH.with_name("generate_go1_mjcf.py"))
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def _scenario(**robot_fields):
    scenario = load_scenario()
    for name, value in robot_fields.items():
        setattr(scenario.robot, name, value)
    return scenario


def _stand(go1: MujocoGo1, seconds: float, q=robot.STANDING_Q) -> None:
    go1.apply_command(pack_command(q, 0.0, STAND_KP, STAND_KD, 0.0))
    for _ in range(int(round(seconds / go1.period))):
        go1.tick()


def test_the_shipped_mjcf_is_what_the_generator_writes():
    generator = _generator()
    assert generator.make_mjcf(generator.URDF.read_text()) == MJCF_PATH.read_text()


def test_mass_joint_order_and_limits_match_the_drake_model(go1_plant):
    plant, _ = go1_plant
    model = mujoco.MjModel.from_xml_path(str(MJCF_PATH))
    assert np.isclose(model.body_mass.sum(), plant.CalcTotalMass(plant.CreateDefaultContext()), atol=1e-9)
    actuated = [model.joint(model.actuator_trnid[k, 0]).name for k in range(model.nu)]
    assert actuated == list(robot.JOINT_NAMES)
    ranges = np.array([model.jnt_range[model.joint(name).id] for name in robot.JOINT_NAMES])
    np.testing.assert_allclose(ranges[:, 0], robot.Q_LOWER)
    np.testing.assert_allclose(ranges[:, 1], robot.Q_UPPER)
    np.testing.assert_allclose(model.actuator_ctrlrange[:, 1], robot.EFFORT_LIMIT)
    np.testing.assert_allclose(model.actuator_ctrlrange[:, 0], -robot.EFFORT_LIMIT)


def test_the_prong_variant_has_the_drake_prong_mass():
    design = ProngDesign()
    go1 = MujocoGo1(_scenario(prongs=design))
    plant, _ = robot.make_go1_plant(robot.design_key(design))
    assert np.isclose(go1.model.body_mass.sum(), plant.CalcTotalMass(plant.CreateDefaultContext()), atol=1e-9)
    assert go1.model.geom("prong_1_tip").size[0] == design.tip_radius


def test_standing_feet_sink_about_17_mm():
    """Standing at (0, 0.9, -1.8) under a PD hold, the 0.023 m rubber feet sink 16.7 (front) to 17.0 mm (rear)."""
    go1 = MujocoGo1(_scenario(initial_pose="standing"))
    _stand(go1, 1.5)
    sink = 0.023 - go1.truth_sample().p_WF[:, 2]
    assert np.all((0.012 < sink) & (sink < 0.022)), sink


def test_standing_feet_do_not_creep_under_a_steady_push():
    """30 N forward on the trunk (a quarter of the friction limit) for 1 s: the stance feet stay put."""
    scenario = _scenario(initial_pose="standing")
    scenario.pushes = [Push(force=30.0, body="trunk", direction=[1.0, 0.0, 0.0], start=1.0, duration=1.0)]
    go1 = MujocoGo1(scenario)
    _stand(go1, 1.0)
    before = go1.truth_sample().p_WF
    _stand(go1, 1.0)
    assert np.abs(go1.truth_sample().p_WF - before)[:, :2].max() < 0.003


def test_the_run_starts_at_rest_where_the_scenario_places_the_robot():
    for prongs in (None, ProngDesign()):
        scenario = _scenario(prongs=prongs)
        scenario.robot.initial_xy = [0.3, -0.2]
        go1 = MujocoGo1(scenario)
        assert go1.time == 0.0
        np.testing.assert_allclose(go1.truth_sample().p_WB[:2], [0.3, -0.2], atol=1e-12)
        assert np.abs(go1.data.qvel).max() < 0.05  # at rest under the hold
        assert go1.data.ncon > 0  # on its soft feet (and prongs), not in the air
        deepest = 0.023 - min(go1.truth_sample().p_WF[:, 2])
        assert deepest < 0.025  # sunk, not through the floor


def test_status_messages_decode_with_the_projects_lcmtypes():
    go1 = MujocoGo1(_scenario(initial_pose="standing"))
    lcm = DrakeLcm("memq://")
    received = {}
    for channel, kind in (
        (c.LEG_CONTROL_CHANNEL, leg_control_data_lcmt),
        (c.STATE_ESTIMATOR_CHANNEL, state_estimator_lcmt),
    ):
        lcm.Subscribe(
            channel, lambda data, channel=channel, kind=kind: received.__setitem__(channel, kind.decode(data))
        )
    bridge = MujocoBridge(go1, lcm, Go1BridgeConfig())
    for _ in range(400):  # standing still after landing on its soft feet
        bridge.tick()
    lcm.HandleSubscriptions(0)
    leg, estimator = received[c.LEG_CONTROL_CHANNEL], received[c.STATE_ESTIMATOR_CHANNEL]
    sample = go1.status_sample()
    np.testing.assert_allclose(leg.q, sample[SAMPLE["go1.position_measured"]], atol=1e-2)
    assert leg.id == 399
    np.testing.assert_allclose(estimator.quat, [1, 0, 0, 0], atol=0.05)
    assert 8.0 < estimator.aBody[2] < 11.0  # specific force: up, about g, standing
    assert sum(estimator.contact_estimate) == pytest.approx(9.81 * go1.model.body_mass.sum(), rel=0.1)
    assert list(estimator.p) == [0.0, 0.0, 0.0]  # world-frame fields stay 0, as on the real bridge


def test_a_command_on_the_wire_moves_its_joint_its_way():
    go1 = MujocoGo1(_scenario(initial_pose="standing"))
    lcm = DrakeLcm("memq://")
    bridge = MujocoBridge(go1, lcm, Go1BridgeConfig())
    joint = robot.JOINT_NAMES.index("FL_hip_joint")
    for offset in (0.0, 0.15):
        q_des = robot.STANDING_Q.copy()
        q_des[joint] += offset
        lcm.Publish(c.COMMAND_CHANNEL, c.command_to_message(pack_command(q_des, 0.0, STAND_KP, STAND_KD, 0.0)).encode())
        for _ in range(250):
            bridge.tick()
        q = go1.joint_positions()
        if offset == 0.0:
            q_before = q
    assert bridge.commands_received() == 2
    moved = q - q_before
    assert moved[joint] > 0.08
    assert np.abs(np.delete(moved, joint)).max() < 0.5 * moved[joint]


def test_the_first_measured_pose_is_held_until_the_first_command():
    go1 = MujocoGo1(_scenario())
    q0 = go1.joint_positions()
    q_des, qd_des, kp, kd, tau = split_command(go1.applied_command())
    np.testing.assert_allclose(q_des, q0)
    assert np.all(kp == HOLD_KP) and np.all(kd == HOLD_KD) and np.all(tau == 0.0)
    for _ in range(250):
        go1.tick()
    assert np.abs(go1.joint_positions() - q0).max() < 0.2
    command = pack_command(robot.STANDING_Q, 0.0, STAND_KP, STAND_KD, 1.0)
    go1.apply_command(command)
    np.testing.assert_array_equal(go1.applied_command(), command)


def test_a_lock_step_pd_stand_up_stands_level():
    go1 = MujocoGo1(_scenario())
    q_start = go1.joint_positions()
    for k in range(1, 501):  # 1 s from the lying pose to standing, then 1 s holding
        s = min(1.0, k / 500)
        go1.apply_command(pack_command((1 - s) * q_start + s * robot.STANDING_Q, 0.0, STAND_KP, STAND_KD, 0.0))
        go1.tick()
    _stand(go1, 1.0)
    truth = go1.truth_sample()
    assert 0.22 < truth.p_WB[2] < 0.28
    assert abs(truth.quaternion_WB[0]) > 0.995
    tau = go1.status_sample()[SAMPLE["go1.torque_estimated"]]
    assert np.all(np.abs(tau) <= robot.EFFORT_LIMIT + 1e-9)


@pytest.mark.parametrize("mission", shipped_missions())
def test_every_shipped_missions_scene_loads(mission):
    scenario = bridge_scenario(load_scenario(), mission)
    go1 = MujocoGo1(scenario)
    assert go1.scene_names == [obj.instance_name for obj in scenario.scene]
    for _ in range(10):
        go1.tick()
    assert go1.truth_sample().scene_contact_forces.shape == (5 * len(scenario.scene),)
    assert np.isfinite(go1.data.qpos).all()


def test_every_scene_kind_converts_and_stands_still():
    kinds = sorted(SCENE_MODELS) + ["wide_box", "lift_box"]
    scene = []
    for k, kind in enumerate(kinds):
        extra = (
            {"kind": "box", "model": f"package://pedi_drake/scenes/{kind}.sdf"} if "_box" in kind else {"kind": kind}
        )
        position = [0.0, 0.0, 0.0] if kind == "back_object" else [1.0 + 0.8 * k, 1.5, 0.0]
        scene.append(SceneObject(name=f"{kind}_{k}", position=position, **extra))
    scenario = load_scenario()
    scenario.scene = scene
    go1 = MujocoGo1(scenario)
    x0 = {name: go1.data.xpos[go1.model.body(name).id].copy() for obj in go1.scene for name in obj.bodies}
    for _ in range(250):
        go1.tick()
    for name, x in x0.items():
        if not name.startswith("back_object"):  # it rides the trunk, which settles on its lying legs
            assert np.linalg.norm(go1.data.xpos[go1.model.body(name).id] - x) < 0.01, name


def test_the_back_object_presses_on_the_trunk_with_its_weight():
    scenario = bridge_scenario(load_scenario(), "remove_object_from_back")
    go1 = MujocoGo1(scenario)
    for _ in range(250):
        go1.tick()
    forces = go1.truth_sample().scene_contact_forces
    assert forces[scene_contact_index("back_object", "other", go1.scene_names)] == pytest.approx(0.981, rel=0.1)
    assert forces[scene_contact_index("back_object", "FR", go1.scene_names)] == 0.0


def test_the_soft_obstacle_plate_springs_and_the_door_opens_as_placed():
    scenario = bridge_scenario(load_scenario(), "open_door")
    scenario.scene[0].initial_angle = 0.3
    go1 = MujocoGo1(scenario)
    hinge = go1.model.joint("door/hinge")
    assert go1.data.qpos[hinge.qposadr[0]] == pytest.approx(0.3)
    scenario = bridge_scenario(load_scenario(), "obstacle_sensing")
    go1 = MujocoGo1(scenario)
    slide = go1.model.joint(f"{next(o.name for o in scenario.scene if o.kind == 'soft_obstacle')}/slide")
    assert go1.model.jnt_stiffness[slide.id] == 400.0


def test_the_door_swings_through_its_range_without_meeting_its_own_post():
    # Drake filters contact between bodies a joint connects; MuJoCo must too, or the leaf
    # would stop against its post at about 0.9 rad and the push through it would end short.
    scenario = bridge_scenario(load_scenario(), "open_door")
    scenario.scene[0].initial_angle = 1.2
    go1 = MujocoGo1(scenario)
    hinge = go1.model.joint("door/hinge")
    assert go1.data.qpos[hinge.qposadr[0]] == pytest.approx(1.2)
    scenario.scene[0].initial_angle = 0.6
    go1 = MujocoGo1(scenario)
    go1.data.qvel[hinge.dofadr[0]] = 1.5  # [rad/s], opening; its damping alone would stop it past 1.6 rad
    for _ in range(round(0.5 / go1.period)):
        go1.tick()
    assert go1.data.qpos[hinge.qposadr[0]] > 1.1


def test_the_truth_log_has_sim_bridges_keys_and_the_contact_forces(tmp_path):
    scenario = bridge_scenario(load_scenario(), "hit_target_front")
    go1 = MujocoGo1(scenario)
    bridge = MujocoBridge(go1, DrakeLcm("memq://"), Go1BridgeConfig())
    for _ in range(20):
        bridge.tick()
    path = bridge.truth.write(tmp_path / "truth.npz")
    with np.load(path) as truth:
        keys = {"wall_time", "p_WB", "quaternion_WB", "p_WF", "scene_names", "scene_contact_forces", "foot_radius"}
        assert set(truth.files) == keys
        assert float(truth["foot_radius"]) == pytest.approx(0.023)
        assert list(truth["scene_names"]) == ["target_panel"]
        assert truth["p_WF"].shape == (4, 4, 3)
        assert truth["scene_contact_forces"].shape == (4, 5)
    assert load_mission("hit_target_front").touches[0].object in go1.scene_names


def test_both_bridges_log_the_back_objects_weight_under_the_same_keys(tmp_path):
    scenario = bridge_scenario(load_scenario(), "remove_object_from_back")
    names = [obj.instance_name for obj in scenario.scene]
    diagram = MakeSimBridgeDiagram(scenario, DrakeLcm("memq://"), Go1BridgeConfig())
    simulator = Simulator(diagram)
    simulator.AdvanceTo(0.5)
    drake_path = write_truth_log(diagram, simulator.get_context(), tmp_path / "drake.npz", names)
    bridge = MujocoBridge(MujocoGo1(scenario), DrakeLcm("memq://"), Go1BridgeConfig())
    for _ in range(251):
        bridge.tick()
    mujoco_path = bridge.truth.write(tmp_path / "mujoco.npz")
    index = scene_contact_index("back_object", "other", names)
    with np.load(drake_path) as drake_truth, np.load(mujoco_path) as mujoco_truth:
        # The Drake bridge's log also has its whole plant's state (apps.sil's truth_checks read it).
        assert set(drake_truth.files) - set(DRAKE_ONLY_TRUTH) == set(mujoco_truth.files)
        for truth in (drake_truth, mujoco_truth):
            assert list(truth["scene_names"]) == names
            assert truth["scene_contact_forces"].shape == (51, 5)
            assert 0.5 < truth["scene_contact_forces"][-1, index] < 2.0  # 0.1 kg resting on the trunk


@pytest.mark.wall_clock
def test_the_bridge_program_runs_at_wall_time_and_writes_its_truth(tmp_path):
    path = tmp_path / "truth.npz"
    completed = subprocess.run(
        [sys.executable, "-m", "pedi_drake.apps.mujoco_bridge", "--mission", "hit_target_front", "--duration", "1.0"]
        + ["--lcm_url", "udpm://239.255.76.67:7719?ttl=0", "--truth_log", str(path)],
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert completed.returncode == 0, completed.stderr
    assert "go1_mujoco_bridge: running on udpm://239.255.76.67:7719?ttl=0" in completed.stdout
    with np.load(path) as truth:
        wall = truth["wall_time"]
    assert len(wall) == 100
    assert 0.9 < wall[-1] - wall[0] < 1.3
