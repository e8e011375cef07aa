"""Scripted whole-body demonstrations of the controller alone (no Mission Manager), as diagram builders.

Each demo is a `DemoScript` (a stateless LeafSystem producing the controller's reference vectors
from the time, from quintic segments planned once from the scenario's initial pose) wired with
the simulated station, the scenario's estimator and the `WholeBodyController`:

* "stand": stand on four legs, holding the initial pose;
* "three_leg_hold": shift the trunk so the capture point lies inside the triangle of FL, RR, RL,
  unload FR (contact ramp), lift the FR foot to 15 cm below its shoulder and hold;
* "five_targets": as "three_leg_hold", then move the FR foot through 5 targets;
* "prongs": lower the trunk onto both prongs, load them, unload and lift both front feet;
* "push_no_prongs" / "push_prongs": on three legs at prong height (without / with the prongs
  loaded), a horizontal force on the trunk ramps to `push_force` and holds for `push_duration`;
* "push_foot": as "three_leg_hold", then a known force (`foot_push_force` along
  `foot_push_direction`) on the lifted FR foot: the measured foot stiffness and the controller's
  force estimate against the applied force.

The controller is the scenario's: `whole_body` (the HQP) or `projected_impedance` (paper 002).

`run_demo` simulates one and returns the logs needed by tests and the benchmark; the metrics
(foot error, trunk drift, stance slip, torques) are computed from ground truth for evaluation
only (the controller itself reads the estimate and go1.* signals).
"""

import dataclasses
import time

import numpy as np
from pydrake.common.value import Value
from pydrake.math import RigidTransform, RotationMatrix
from pydrake.multibody.math import SpatialForce
from pydrake.multibody.plant import ExternallyAppliedSpatialForce
from pydrake.systems.analysis import Simulator
from pydrake.systems.framework import Context, Diagram, DiagramBuilder, LeafSystem
from pydrake.systems.primitives import VectorLogSink

from pedi_drake import robot
from pedi_drake.control import references
from pedi_drake.control.projected_impedance_controller import ProjectedImpedanceController
from pedi_drake.control.references import LEG_MODE_FOOT
from pedi_drake.control.robot_model import ControllerModel
from pedi_drake.control.whole_body_controller import WholeBodyController, diagnostics_layout
from pedi_drake.estimation.ground_truth import GroundTruthEstimator
from pedi_drake.exceptions import ConfigError
from pedi_drake.fall import fell_during
from pedi_drake.leg_kinematics import foot_position_B, leg_geometry
from pedi_drake.prongs import ProngDesign
from pedi_drake.resources import scenarios_dir
from pedi_drake.scenario import Scenario, load_scenario
from pedi_drake.station.initial_state import initial_trunk_pose
from pedi_drake.station_interface import MakeStation
from pedi_drake.trajectory import PiecewiseQuintic, QuinticSegment

DEMOS = ("stand", "three_leg_hold", "five_targets", "prongs", "push_no_prongs", "push_prongs", "push_foot")
SCENARIO_FILE = scenarios_dir() / "wbc_demos.yaml"


@dataclasses.dataclass
class DemoTiming:
    """Phase times of the scripted demos [s]."""

    shift_start: float = 0.2
    shift_duration: float = 1.0
    lower_duration: float = 1.2  # trunk lowering (prongs, push demos)
    unload_at: float = 1.4  # contact set changes here (relative to the end of the shift)
    lift_delay: float = 0.4  # from unloading to the start of the lift
    lift_duration: float = 0.8
    target_move: float = 0.8  # five_targets: move time per target
    target_hold: float = 0.4  # five_targets: hold time per target
    push_start_after_lift: float = 1.0
    push_ramp: float = 0.5
    push_duration: float = 5.0  # time at full force
    push_force: float = 30.0  # [N]
    push_direction: tuple = (0.0, -1.0, 0.0)  # world, horizontal (towards the lifted FR side)
    foot_push_force: float = 10.0  # push_foot: force on the FR foot centre [N]
    foot_push_direction: tuple = (1.0, 0.0, 0.0)  # push_foot: its direction, world [-]
    foot_push_duration: float = 2.0  # push_foot: time at full force [s]


# Offsets of the five_targets demo from the first (15 cm below the shoulder) target, world [m].
FIVE_TARGET_OFFSETS = np.array(
    [[0.06, 0.0, 0.02], [0.08, -0.04, 0.05], [0.03, 0.03, 0.07], [-0.02, -0.02, 0.03], [0.05, 0.0, 0.0]]
)


@dataclasses.dataclass
class DemoPlan:
    """References of a demo as functions of time, and the phase times metrics are read at."""

    body: PiecewiseQuintic  # p_WB [m]
    R_WB: RotationMatrix
    legs: dict[str, PiecewiseQuintic]  # foot position references in world [m]
    leg_start: float  # leg references active from here [s]
    contact_switch: list[tuple[float, np.ndarray]]  # (time, contact set) in time order
    duration: float
    hold_windows: list[tuple[float, float, dict[str, np.ndarray]]]  # (t0, t1, {leg: target})
    three_leg_start: float  # first instant on three legs (after the ramp) [s]
    push: tuple[float, float] | None = None  # (start, end) of the full push force [s]
    push_body: str = robot.TRUNK_BODY_NAME  # the body the push acts on


def _shoulder_W(X_WB: RigidTransform, leg: str) -> np.ndarray:
    """The thigh joint (the 'shoulder') of `leg` in world [m]."""
    g = leg_geometry(leg)
    return X_WB.multiply(g.p_BH + g.p_HT)


def plan_demo(name: str, scenario: Scenario, timing: DemoTiming | None = None) -> DemoPlan:
    """Plans the references of demo `name` from the scenario's initial (standing) pose."""
    if name not in DEMOS:
        raise ConfigError(f"demo: must be one of {DEMOS}, got {name!r}")
    tm = timing or DemoTiming()
    X_WB0 = initial_trunk_pose(scenario.robot)
    p0 = X_WB0.translation()
    R0 = X_WB0.rotation()
    feet0 = {
        leg: X_WB0.multiply(foot_position_B(leg, robot.STANDING_Q[robot.leg_slice(leg)])) for leg in robot.LEG_NAMES
    }
    prongs = scenario.robot.prongs
    n_prongs = 0 if prongs is None else prongs.num_prongs
    four = references.contact_set_vector(num_prongs=n_prongs)
    if name == "stand":
        body = PiecewiseQuintic((QuinticSegment(p0, p0, 0.0, 1.0),))
        return DemoPlan(body, R0, {}, 0.0, [(0.0, four)], 2.0, [], np.inf)

    # Trunk target: prong height for the prong and push demos, else the standing height; shifted
    # so the centre of mass sits over the centroid of the remaining support.
    low = name in ("prongs", "push_no_prongs", "push_prongs")
    model = ControllerModel(prongs)
    base0 = np.concatenate([R0.ToQuaternion().wxyz(), p0, np.zeros(6)])
    snapshot = model.update(base0, robot.STANDING_Q, np.zeros(12))
    com_offset = snapshot.p_com[:2] - p0[:2]
    height = p0[2]
    if low:
        design = prongs if prongs is not None else robot_default_prongs()
        height = design.ground_contact_height() - 0.004  # slightly below touch: the prongs bear load
    if name == "prongs":
        support = [prongs.tip_positions_B()[0][:2] + p0[:2], feet0["RR"][:2], feet0["RL"][:2]]
    else:
        support = [feet0["FL"][:2], feet0["RR"][:2], feet0["RL"][:2]]
    centroid = np.mean(support, axis=0)
    shift_xy = centroid - (p0[:2] + com_offset)
    # The legs stay put while the trunk moves, so the CoM moves less than the trunk.
    shift_xy *= 1.25
    if name == "push_prongs" or name == "prongs":
        shift_xy = np.zeros(2) if name == "prongs" else shift_xy * 0.5  # prongs carry part of the load
    p1 = p0 + np.array([shift_xy[0], shift_xy[1], height - p0[2]])
    t_shift0 = tm.shift_start
    t_shift1 = t_shift0 + (tm.lower_duration if low else tm.shift_duration)
    body = PiecewiseQuintic((QuinticSegment(p0, p1, t_shift0, t_shift1 - t_shift0),))
    X_WB1 = RigidTransform(R0, p1)

    t_unload = t_shift1 + tm.unload_at - tm.shift_duration + 0.4
    switches = [(0.0, four)]
    if name in ("prongs", "push_prongs"):
        with_prongs = references.contact_set_vector(num_prongs=n_prongs, prongs=True)
        switches.append((t_shift1 - 0.1, with_prongs))
    lifted = ("FR", "FL") if name == "prongs" else ("FR",)
    stance = tuple(leg for leg in robot.LEG_NAMES if leg not in lifted)
    switches.append(
        (t_unload, references.contact_set_vector(stance, n_prongs, prongs=name in ("prongs", "push_prongs")))
    )
    t_ramped = t_unload + controller_config(scenario).contact_ramp_time
    t_lift0 = t_unload + tm.lift_delay
    t_lift1 = t_lift0 + tm.lift_duration
    legs, targets = {}, {}
    for leg in lifted:
        if name == "prongs":
            target = feet0[leg] + np.array([0.03, 0.0, 0.08])
        else:
            # 15 cm below the shoulder when standing; at prong height (0.17 m) that is the floor,
            # so the low demos hold the foot 8 cm below the shoulder, clear of the ground.
            depth = 0.08 if low else 0.15
            target = _shoulder_W(X_WB1, leg) - np.array([0.0, 0.0, depth])
        targets[leg] = target
        legs[leg] = PiecewiseQuintic.through(np.array([feet0[leg], target]), t_lift0, [tm.lift_duration])
    end = t_lift1 + 1.5
    windows = [(t_lift1 + 0.5, end, dict(targets))]
    push = None
    if name == "five_targets":
        waypoints = [targets["FR"]] + [targets["FR"] + o for o in FIVE_TARGET_OFFSETS]
        t, points, durations = t_lift1, [feet0["FR"], targets["FR"]], [tm.lift_duration]
        windows = []
        for k in range(1, len(waypoints)):
            # Move, then hold (a zero-length move is represented by a repeated waypoint).
            points += [waypoints[k], waypoints[k]]
            durations += [tm.target_move, tm.target_hold]
            t += tm.target_move + tm.target_hold
            windows.append((t - 0.05, t, {"FR": waypoints[k]}))
        legs["FR"] = PiecewiseQuintic.through(np.array(points), t_lift0, durations)
        end = t + 0.1
    push_body = robot.TRUNK_BODY_NAME
    if name in ("push_no_prongs", "push_prongs", "push_foot"):
        duration = tm.foot_push_duration if name == "push_foot" else tm.push_duration
        t_push0 = t_lift1 + tm.push_start_after_lift + tm.push_ramp
        push = (t_push0, t_push0 + duration)
        end = push[1] + tm.push_ramp + 0.5
        windows = [(t_lift1 + 0.5, push[0] - tm.push_ramp, dict(targets))]
        if name == "push_foot":
            push_body = "FR_foot"
    return DemoPlan(body, R0, legs, t_lift0 - 0.4, switches, end, windows, t_ramped, push, push_body)


def robot_default_prongs():
    return ProngDesign()


class DemoScript(LeafSystem):
    """Reference vectors of a `DemoPlan` as functions of time (stateless)."""

    def __init__(self, plan: DemoPlan, num_contacts: int) -> None:
        super().__init__()
        self._plan = plan
        self.body_port = self.DeclareVectorOutputPort("body_reference", references.BODY_REFERENCE_SIZE, self._body)
        self.leg_port = self.DeclareVectorOutputPort("leg_reference", references.LEG_REFERENCE_SIZE, self._legs)
        self.contact_port = self.DeclareVectorOutputPort("contact_set", num_contacts, self._contacts)

    def _body(self, context: Context, output) -> None:
        sample = self._plan.body.sample(context.get_time())
        output.SetFromVector(
            references.body_reference_vector(sample.position, self._plan.R_WB, sample.velocity, sample.acceleration)
        )

    def _legs(self, context: Context, output) -> None:
        t = context.get_time()
        entries = {}
        if t >= self._plan.leg_start:
            for leg, path in self._plan.legs.items():
                s = path.sample(t)
                entries[leg] = (LEG_MODE_FOOT, s.position, s.velocity, s.acceleration)
        output.SetFromVector(references.leg_reference_vector(entries))

    def _contacts(self, context: Context, output) -> None:
        t = context.get_time()
        current = self._plan.contact_switch[0][1]
        for t_switch, contact_set in self._plan.contact_switch:
            if t >= t_switch:
                current = contact_set
        output.SetFromVector(current)


class TrunkPush(LeafSystem):
    """A force on a body's origin (the trunk's, or a foot's centre): ramps up, holds, ramps down
    (an ExternallyAppliedSpatialForce list)."""

    def __init__(self, trunk_body_index, force_W: np.ndarray, t_full: float, t_end: float, ramp: float) -> None:
        super().__init__()
        self._body = trunk_body_index
        self._force = np.asarray(force_W, float)
        self._t_full, self._t_end, self._ramp = t_full, t_end, ramp
        self.DeclareAbstractOutputPort("forces", lambda: Value([ExternallyAppliedSpatialForce()]), self._calc)

    def magnitude_scale(self, t: float) -> float:
        if t < self._t_full - self._ramp or t > self._t_end + self._ramp:
            return 0.0
        if t < self._t_full:
            return (t - self._t_full + self._ramp) / self._ramp
        if t > self._t_end:
            return (self._t_end + self._ramp - t) / self._ramp
        return 1.0

    def _calc(self, context: Context, output) -> None:
        force = ExternallyAppliedSpatialForce()
        force.body_index = self._body
        force.p_BoBq_B = np.zeros(3)
        force.F_Bq_W = SpatialForce(np.zeros(3), self.magnitude_scale(context.get_time()) * self._force)
        output.set_value([force])


@dataclasses.dataclass
class DemoDiagram:
    diagram: Diagram
    plan: DemoPlan
    controller: WholeBodyController | ProjectedImpedanceController
    scenario: Scenario
    timing: DemoTiming


def controller_config(scenario: Scenario):
    """The settings of the scenario's whole-body controller (either kind)."""
    return scenario.projected_impedance if scenario.controller == "projected_impedance" else scenario.whole_body


def make_controller(scenario: Scenario) -> WholeBodyController | ProjectedImpedanceController:
    """The scenario's whole-body controller: the HQP, or paper 002's projected impedance."""
    if scenario.controller == "projected_impedance":
        return ProjectedImpedanceController(scenario.projected_impedance, scenario.robot.prongs)
    return WholeBodyController(scenario.whole_body, scenario.robot.prongs)


def demo_scenario(name: str, **whole_body_overrides) -> Scenario:
    """The shipped scenario of demo `name` (scenarios/wbc_demos.yaml), with config overrides."""
    scenario = load_scenario(filename=SCENARIO_FILE, scenario_name=name)
    for key, value in whole_body_overrides.items():
        setattr(scenario.whole_body, key, value)
    return scenario


def build_demo(
    name: str, scenario: Scenario | None = None, meshcat=None, timing: DemoTiming | None = None
) -> DemoDiagram:
    """The station + estimator + WholeBodyController + DemoScript (+ push) diagram of demo `name`."""
    scenario = scenario or demo_scenario(name)
    tm = timing or DemoTiming()
    plan = plan_demo(name, scenario, tm)
    builder = DiagramBuilder()
    station = builder.AddNamedSystem("station", MakeStation(scenario, meshcat))
    plant = station.GetSubsystemByName("plant")
    if scenario.estimator != "ground_truth":
        raise ConfigError("the demos measure the controller alone: they need estimator: ground_truth")
    estimator = builder.AddNamedSystem("estimator", GroundTruthEstimator(plant))
    builder.Connect(station.GetOutputPort("sim.plant_state"), estimator.GetInputPort("plant_state"))
    controller = builder.AddNamedSystem("controller", make_controller(scenario))
    script = builder.AddNamedSystem("script", DemoScript(plan, controller.num_contacts))
    builder.Connect(estimator.GetOutputPort("base_state"), controller.base_state_port)
    builder.Connect(station.GetOutputPort("go1.position_measured"), controller.position_port)
    builder.Connect(station.GetOutputPort("go1.velocity_measured"), controller.velocity_port)
    builder.Connect(script.body_port, controller.body_reference_port)
    builder.Connect(script.leg_port, controller.leg_reference_port)
    builder.Connect(script.contact_port, controller.contact_set_port)
    builder.Connect(controller.command_port, station.GetInputPort("go1.command"))
    if plan.push is not None:
        body = plant.GetBodyByName(plan.push_body)
        if plan.push_body == robot.TRUNK_BODY_NAME:
            force = tm.push_force * np.asarray(tm.push_direction, float)
        else:
            force = tm.foot_push_force * np.asarray(tm.foot_push_direction, float)
        push = builder.AddNamedSystem("push", TrunkPush(body.index(), force, plan.push[0], plan.push[1], tm.push_ramp))
        builder.Connect(push.get_output_port(), station.GetInputPort("sim.applied_spatial_force"))
    period = controller_config(scenario).period
    for log_name, port in (
        ("log.plant_state", station.GetOutputPort("sim.plant_state")),
        ("log.diagnostics", controller.diagnostics_port),
        ("log.motor_torque", station.GetOutputPort("sim.motor_torque")),
    ):
        logger = builder.AddNamedSystem(log_name, VectorLogSink(port.size(), period))
        builder.Connect(port, logger.get_input_port())
    return DemoDiagram(builder.Build(), plan, controller, scenario, tm)


@dataclasses.dataclass
class DemoResult:
    """Metrics of one demo run (ground truth, evaluation only)."""

    name: str
    sim_time: float  # [s]
    wall_time: float  # [s]
    real_time_factor: float
    fell: bool  # the fall rule of pedi_drake.fall held at some sample
    foot_errors: list[float]  # per hold window: max foot-to-target distance over the window [m]
    trunk_drift: float  # max |p_WB - p_ref| on three legs, before any push [m]
    stance_slip: float  # max horizontal foot-centre displacement of a stance foot on three legs [m]
    stance_slip_whole_run: float  # the same from t = 0 (includes the trunk shift on four feet) [m]
    max_torque_ratio: float  # max |tau| / effort limit over the run (applied motor torques)
    qp_failures: int
    tick_median_ms: float  # wall time of a controller tick, on three legs when the demo lifts a leg [ms]
    tick_p99_ms: float
    push_displacement: float = float("nan")  # max trunk displacement during the push [m]
    # push_foot: applied force / steady foot displacement along the push [N/m].
    foot_stiffness: float = float("nan")
    # push_foot: RMS of |estimate - applied force| at the foot over the steady push, per estimate [N].
    force_estimate_rms: dict = dataclasses.field(default_factory=dict)
    peak_knee_torque: float = float("nan")  # max |calf torque| of the stance legs during the push [N m]
    max_force_jump: float = float("nan")  # largest change of a contact force between ticks (t > 0.1 s) [N]
    prong_force: float = 0.0  # mean total prong normal force over the last 0.5 s [N]
    min_trunk_height: float = float("nan")  # [m]


def run_demo(name: str, scenario: Scenario | None = None, timing: DemoTiming | None = None) -> DemoResult:
    """Simulates demo `name` and evaluates it."""
    demo = build_demo(name, scenario, timing=timing)
    diagram, plan = demo.diagram, demo.plan
    simulator = Simulator(diagram)
    simulator.Initialize()
    start = time.perf_counter()
    simulator.AdvanceTo(plan.duration)
    wall = time.perf_counter() - start
    context = simulator.get_context()
    logs = {
        n: diagram.GetSubsystemByName(n).FindLog(context)
        for n in ("log.plant_state", "log.diagnostics", "log.motor_torque")
    }
    return evaluate(name, demo, logs, wall)


def max_force_jump(times: np.ndarray, forces: np.ndarray, after: float = 0.1) -> float:
    """Largest change of any contact-force component between consecutive ticks after `after` [N]."""
    keep = times[: len(forces)] >= after
    f = forces[keep]
    return float(np.max(np.abs(np.diff(f, axis=0)))) if len(f) > 1 else 0.0


def evaluate(name: str, demo: DemoDiagram, logs, wall: float) -> DemoResult:
    plan, controller = demo.plan, demo.controller
    plant = demo.diagram.GetSubsystemByName("station").GetSubsystemByName("plant")
    plant_context = plant.CreateDefaultContext()
    times = logs["log.plant_state"].sample_times()
    states = logs["log.plant_state"].data().T
    nq = plant.num_positions()
    feet = [plant.GetBodyByName(n) for n in robot.FOOT_BODY_NAMES]
    trunk = plant.GetBodyByName(robot.TRUNK_BODY_NAME)
    foot_p = np.zeros((len(times), 4, 3))
    trunk_p = np.zeros((len(times), 3))
    for k, x in enumerate(states):
        plant.SetPositions(plant_context, x[:nq])
        for i, foot in enumerate(feet):
            foot_p[k, i] = plant.EvalBodyPoseInWorld(plant_context, foot).translation()
        X = plant.EvalBodyPoseInWorld(plant_context, trunk)
        trunk_p[k] = X.translation()
    q0 = robot.Go1PlantMap.from_plant(plant).base_q_start
    fell = fell_during(states[:, q0 : q0 + 4].T, states[:, q0 + 6], has_prongs=demo.scenario.robot.prongs is not None)
    foot_errors = []
    for t0, t1, targets in plan.hold_windows:
        mask = (times >= t0) & (times <= t1)
        for leg, target in targets.items():
            i = robot.LEG_NAMES.index(leg)
            foot_errors.append(
                float(np.max(np.linalg.norm(foot_p[mask, i] - target, axis=1))) if np.any(mask) else np.inf
            )
    t_drift_end = plan.push[0] - 0.5 if plan.push else plan.duration
    mask = (times >= plan.three_leg_start) & (times <= t_drift_end)
    ref = np.array([plan.body.sample(t).position for t in times[mask]])
    drift = float(np.max(np.linalg.norm(trunk_p[mask] - ref, axis=1))) if np.any(mask) else 0.0
    # Foot-centre displacement of the feet that stay loaded: an upper bound of slip (it also
    # counts rolling of the foot sphere when the calf turns).
    lifted = set(plan.legs)
    slip, slip_all = 0.0, 0.0
    three = np.flatnonzero(times >= plan.three_leg_start)
    for i, leg in enumerate(robot.LEG_NAMES):
        if leg not in lifted:
            slip_all = max(slip_all, float(np.max(np.linalg.norm(foot_p[:, i, :2] - foot_p[0, i, :2], axis=1))))
            if len(three):
                moved = foot_p[three, i, :2] - foot_p[three[0], i, :2]
                slip = max(slip, float(np.max(np.linalg.norm(moved, axis=1))))
    torque = logs["log.motor_torque"].data().T
    ratio = float(np.max(np.abs(torque) / robot.EFFORT_LIMIT))
    diag = logs["log.diagnostics"].data().T
    layout = diagnostics_layout(controller.num_contacts)
    ticks = diag[:, layout["tick_time"]].ravel() * 1e3
    diag_times = logs["log.diagnostics"].sample_times()
    if np.isfinite(plan.three_leg_start):
        # Tick times on three legs (or the prongs' stance): the configuration the floors name.
        ticks = ticks[diag_times >= plan.three_leg_start]
    ticks = ticks[ticks > 0]
    forces = diag[:, layout["contact_forces"]]
    result = DemoResult(
        name=name,
        sim_time=plan.duration,
        wall_time=wall,
        real_time_factor=plan.duration / wall,
        fell=fell,
        foot_errors=foot_errors,
        trunk_drift=drift,
        stance_slip=slip,
        stance_slip_whole_run=slip_all,
        max_torque_ratio=ratio,
        qp_failures=int(diag[-1, layout["total_failures"]][0]),
        tick_median_ms=float(np.median(ticks)) if len(ticks) else float("nan"),
        tick_p99_ms=float(np.percentile(ticks, 99)) if len(ticks) else float("nan"),
        max_force_jump=max_force_jump(times, forces),
        min_trunk_height=float(np.min(trunk_p[:, 2])),
    )
    if controller.num_contacts > 4:
        last = times >= times[-1] - 0.5
        result.prong_force = float(np.mean(np.sum(forces[last][:, 14::3], axis=1)))
    if name == "push_foot":
        tm = demo.timing
        direction = np.asarray(tm.foot_push_direction, float)
        applied = tm.foot_push_force * direction
        before = (times >= plan.push[0] - tm.push_ramp - 0.4) & (times < plan.push[0] - tm.push_ramp)
        steady = (times >= plan.push[0] + 1.0) & (times <= plan.push[1])
        fr = robot.LEG_NAMES.index("FR")
        moved = float((foot_p[steady, fr].mean(axis=0) - foot_p[before, fr].mean(axis=0)) @ direction)
        result.foot_stiffness = tm.foot_push_force / moved if moved > 0 else float("inf")
        if "force_estimate" in controller.diag:
            estimate = diag[:, controller.diag["force_estimate"]][:, 3 * fr : 3 * fr + 3]
            window = (diag_times >= plan.push[0] + 1.0) & (diag_times <= plan.push[1])
            error = np.linalg.norm(estimate[window] - applied, axis=1)
            result.force_estimate_rms["impedance"] = float(np.sqrt(np.mean(error**2)))
    elif plan.push is not None:
        mask = (times >= plan.push[0] - 0.5) & (times <= plan.push[1] + 0.5)
        before = trunk_p[times < plan.push[0] - 0.5][-1]
        result.push_displacement = float(np.max(np.linalg.norm(trunk_p[mask] - before, axis=1)))
        calf = [3 * i + 2 for i, leg in enumerate(robot.LEG_NAMES) if leg not in lifted]
        result.peak_knee_torque = float(np.max(np.abs(torque[mask][:, calf])))
    return result
