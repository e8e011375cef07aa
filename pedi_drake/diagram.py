"""MakePedipulationDiagram: the one place where a whole run is wired.

Scenario -> station (plant or driver) -> state estimate -> mission manager <-> leg IK ->
controller -> station command, with the operator's input (when the scenario has one) beside the
estimate into the mission manager and its E-stop on the command, the live SUF beside the mission
manager, and the operator's haptic feedback out of it. run_sim.py, the tests, the
benchmarks and the notebooks all build their diagrams here.

Every logged signal goes through one Multiplexer into one VectorLogSink (`LOG_SINK`):
a sink costs about as much a tick whether it publishes or not (the Simulator schedules every
system's periodic events at every step), about 4,500 instructions, and a run logs 14 to 20
signals; the multiplexer's copy costs less than a tenth of that. `PedipulationDiagram.logs`
splits the one log into the signals again.
"""

import dataclasses

import numpy as np
from pydrake.common.value import AbstractValue
from pydrake.geometry import Meshcat
from pydrake.lcm import DrakeLcm, DrakeLcmInterface
from pydrake.systems.framework import Context, Diagram, DiagramBuilder
from pydrake.systems.primitives import ConstantValueSource, Demultiplexer, MatrixGain, Multiplexer, VectorLogSink

from pedi_drake.control.controller_switch import ControllerSwitch
from pedi_drake.control.projected_impedance_controller import ProjectedImpedanceController
from pedi_drake.control.references import BODY_REFERENCE_SIZE, LEG_REFERENCE_SIZE
from pedi_drake.control.stand_controller import StandController
from pedi_drake.control.trunk_load_compensation import TrunkLoadCompensator
from pedi_drake.control.whole_body_controller import WholeBodyController
from pedi_drake.estimation.ground_truth import GroundTruthEstimator
from pedi_drake.estimation.kalman_estimator import KalmanEstimator
from pedi_drake.exceptions import ScenarioError
from pedi_drake.go1_driver.pacing import loop_wait
from pedi_drake.ik.leg_ik_system import LegIkSystem
from pedi_drake.mission.mission_manager import MissionManager, needs_posture_planner
from pedi_drake.mission.spec import SWITCHABLE_CONTROLLERS, MissionSpec, load_mission
from pedi_drake.operator.command import OPERATOR_COMMAND_SIZE
from pedi_drake.operator.estop_gate import OperatorEstopGate
from pedi_drake.operator.feedback import OperatorFeedback
from pedi_drake.operator.meshcat_panel import MeshcatOperatorPanel
from pedi_drake.operator.message_stream import MessagePlayer, TimedMessage
from pedi_drake.operator.operator_input import OperatorInput
from pedi_drake.run_checks import control_period
from pedi_drake.run_logs import SignalLog
from pedi_drake.runtime.log_hold import LogHold
from pedi_drake.runtime.wall_clock import WallClock
from pedi_drake.scenario import MISSION_CONTROLLERS, Scenario
from pedi_drake.station_interface import MakeStation
from pedi_drake.suf.live_suf_system import LiveSufSystem
from pedi_drake.terrain import terrain_table
from pedi_drake.viz.force_display import ForceDisplay

# Signals logged by every run (name -> exported port of the diagram).
LOGGED_SIGNALS = (
    "go1.command",
    "go1.position_measured",
    "go1.velocity_measured",
    "go1.torque_estimated",
    "go1.foot_contact",
    "go1.imu",
    "base_state",
)
# Simulation ground truth for judging: the plant state, the torques the motors applied, the pushes,
# the contact forces on the feet and between the robot and each scene object.
SIM_LOGGED_SIGNALS = (
    "sim.plant_state",
    "sim.motor_torque",
    "sim.push_force",
    "sim.foot_contact_forces",
    "sim.scene_contact_forces",
)
# The tolerance of the mission's IK solves [m]: well inside every reach phase's tolerance.
MISSION_IK_TOLERANCE = 5e-4
# The one log of a run's signals, and the multiplexer that feeds it (subsystem names).
LOG_SINK = "log"
LOG_MULTIPLEXER = "log.signals"
# The sample-and-hold of the SAMPLED_SENSOR_SIGNALS (subsystem name).
LOG_HOLD = "log_hold"
# Simulated sensor signals that are costly to compute: logged through a sample-and-hold.
SAMPLED_SENSOR_SIGNALS = (
    "go1.imu",
    "go1.foot_contact",
    "go1.torque_estimated",
    "sim.foot_contact_forces",
    "sim.scene_contact_forces",
)


@dataclasses.dataclass
class PedipulationDiagram:
    """The built diagram and the names of its parts that a run reads back."""

    diagram: Diagram
    # The rows of each logged signal (by name) in the one log (`LOG_SINK`); read with `logs`.
    log_rows: dict[str, slice]
    hardware: bool
    # The mission being run, if any (its manager is the subsystem "mission").
    mission: MissionSpec | None = None
    log_period: float = 0.002  # [s]

    def reserve_logs(self, context: Context, duration: float) -> None:
        """Makes room in the log of `context` (the root context) for `duration` [s] of samples: a
        log that fills up doubles, copying all it holds (tens of megabytes late in a run) within
        one tick."""
        log = self.diagram.GetSubsystemByName(LOG_SINK).FindMutableLog(context)
        log.Reserve(int(duration / self.log_period) + 2)

    def logs(self, context: Context) -> dict[str, SignalLog]:
        """Every logged signal's samples so far in `context` (the root context), as copies."""
        log = self.diagram.GetSubsystemByName(LOG_SINK).FindLog(context)
        times, data = log.sample_times(), log.data()
        return {name: SignalLog(times.copy(), data[rows].copy()) for name, rows in self.log_rows.items()}


def apply_mission(scenario: Scenario, mission: MissionSpec) -> Scenario:
    """The scenario with the mission's scene objects and pushes added, its robot variant, its
    whole-body task stack and its contact ramp time applied."""
    merged = dataclasses.replace(
        scenario, scene=list(scenario.scene) + list(mission.scene), pushes=list(scenario.pushes) + list(mission.pushes)
    )
    if mission.robot is not None:
        merged.robot = dataclasses.replace(scenario.robot, prongs=mission.robot.prongs)
    if mission.stack:
        merged.whole_body = dataclasses.replace(merged.whole_body, stack=mission.stack)
    if mission.contact_ramp_time:
        ramp = mission.contact_ramp_time
        merged.whole_body = dataclasses.replace(merged.whole_body, contact_ramp_time=ramp)
        merged.projected_impedance = dataclasses.replace(merged.projected_impedance, contact_ramp_time=ramp)
    return merged


def whole_body_controller(scenario: Scenario, name: str):
    """The whole-body controller `name` ("whole_body" or "projected_impedance") of `scenario`."""
    terrain = terrain_table(scenario.scene)
    if name == "projected_impedance":
        return ProjectedImpedanceController(scenario.projected_impedance, scenario.robot.prongs, terrain)
    return WholeBodyController(scenario.whole_body, scenario.robot.prongs, terrain)


def _add_controller_switch(
    builder: DiagramBuilder, scenario: Scenario, controllers, manager, operator
) -> ControllerSwitch:
    """The ControllerSwitch between the two controllers (the scenario's first), fed by the mission's
    and the operator's requests."""
    switch = builder.AddNamedSystem(
        "controller.switch",
        ControllerSwitch(scenario.controller, scenario.whole_body.period, scenario.controller_switch.blend_time),
    )
    names = [scenario.controller, *(name for name in SWITCHABLE_CONTROLLERS if name != scenario.controller)]
    for name, system in zip(names, controllers, strict=True):
        builder.Connect(system.GetOutputPort("command"), switch.command_ports[name])
    if manager is not None:
        builder.Connect(manager.GetOutputPort("controller_request"), switch.mission_request_port)
    if operator is not None:
        builder.Connect(operator.GetOutputPort("operator_command"), switch.operator_port)
    return switch


def _add_leg_ik(builder: DiagramBuilder, manager: MissionManager) -> None:
    """One LegIkSystem per leg the mission moves ("ik.<leg>"), asked and answered by the manager.

    The IK updates twice per manager period: its update at the manager's tick sees the request
    from before that tick, the one half a period later sees the new request, so every answer is
    in by the manager's next tick.
    """
    for leg in manager.ik_legs:
        ik = builder.AddNamedSystem(f"ik.{leg}", LegIkSystem(period=manager.period / 2, tol=MISSION_IK_TOLERANCE))
        name = builder.AddNamedSystem(f"ik.{leg}.leg", ConstantValueSource(AbstractValue.Make(leg)))
        builder.Connect(name.get_output_port(), ik.GetInputPort("leg"))
        builder.Connect(manager.GetOutputPort(f"ik_foot_target_W.{leg}"), ik.GetInputPort("foot_target_W"))
        builder.Connect(manager.GetOutputPort("ik_X_WB"), ik.GetInputPort("X_WB"))
        builder.Connect(manager.GetOutputPort("ik_q_seed"), ik.GetInputPort("q_measured"))
        for answer, port in (
            ("leg_q_goal", "ik_q_goal"),
            ("solved", "ik_solved"),
            ("ik_error", "ik_error"),
            ("solved_target_B", "ik_target_B"),
        ):
            builder.Connect(ik.GetOutputPort(answer), manager.GetInputPort(f"{port}.{leg}"))


def _add_live_suf(builder: DiagramBuilder, scenario: Scenario, manager: MissionManager, base_state, station):
    """The live SUF ("suf"), asked and read by the manager (pedi_drake.suf.live_suf_system)."""
    config = scenario.live_suf
    suf = builder.AddNamedSystem(
        "suf",
        LiveSufSystem(
            scenario.robot.prongs,
            mu=scenario.ground_friction,
            period=manager.period,
            offset=config.offset,
            tick=control_period(scenario),
            tick_work=config.tick_work,
            max_lps=config.max_lps,
        ),
    )
    builder.Connect(base_state, suf.GetInputPort("base_state"))
    builder.Connect(station.GetOutputPort("go1.position_measured"), suf.GetInputPort("position_measured"))
    builder.Connect(manager.GetOutputPort("contact_set"), suf.GetInputPort("contact_set"))
    builder.Connect(manager.GetOutputPort("suf_request"), suf.GetInputPort("suf_request"))
    builder.Connect(suf.GetOutputPort("suf"), manager.GetInputPort("suf"))
    return suf


# Where the E-stop flag sits in the operator_command vector (pedi_drake.operator.command).
_OPERATOR_ESTOP_INDEX = 6


def _add_operator(
    builder: DiagramBuilder, scenario: Scenario, lcm: DrakeLcmInterface | None, meshcat: Meshcat | None
) -> OperatorInput | MeshcatOperatorPanel:
    """The operator's input system ("operator"): the panel on `meshcat`, or the input on its bus
    (`lcm`, or one opened on the scenario's URL)."""
    config = scenario.operator
    if config.source == "meshcat":
        if meshcat is None:
            raise ScenarioError("operator.source: 'meshcat' needs a Meshcat (run_sim.py --meshcat --teleop)")
        panel = MeshcatOperatorPanel(
            config.meshcat, meshcat, config.period, controller_buttons=scenario.controller_switch.enabled
        )
        return builder.AddNamedSystem("operator", panel)
    if lcm is None:
        lcm = DrakeLcm(scenario.lcm_buses[config.lcm_bus].lcm_url)
    return builder.AddNamedSystem("operator", OperatorInput(config, lcm))


def _connect_operator_estop(builder, operator, station, command, scenario: Scenario, hardware: bool):
    """The command port that reaches the motors: on hardware the driver latches damping on the
    operator's E-stop (its `driver.estop`); in simulation an OperatorEstopGate does the same."""
    if hardware:
        select = np.zeros((1, OPERATOR_COMMAND_SIZE))
        select[0, _OPERATOR_ESTOP_INDEX] = 1.0
        estop = builder.AddNamedSystem("operator.estop", MatrixGain(select))
        builder.Connect(operator.GetOutputPort("operator_command"), estop.get_input_port())
        builder.Connect(estop.get_output_port(), station.GetInputPort("driver.estop"))
        return command
    gate = builder.AddNamedSystem(
        "operator.estop_gate", OperatorEstopGate(scenario.go1_driver.safety, scenario.go1_driver.safety.period)
    )
    builder.Connect(command, gate.GetInputPort("command"))
    builder.Connect(operator.GetOutputPort("operator_command"), gate.GetInputPort("operator_command"))
    for name in ("position_measured", "velocity_measured"):
        builder.Connect(station.GetOutputPort(f"go1.{name}"), gate.GetInputPort(name))
    return gate.GetOutputPort("command")


def _with_loop_wait_resolved(scenario: Scenario, mission: MissionSpec | None) -> Scenario:
    """`scenario` with `go1_driver.wait: auto` replaced by the wait the loop does (pacing.loop_wait)."""
    driver = scenario.go1_driver
    work_beside_loop = scenario.operator.source != "none" or (mission is not None and needs_posture_planner(mission))
    wait = loop_wait(driver.wait, realtime_priority=driver.realtime_priority, work_beside_loop=work_beside_loop)
    return dataclasses.replace(scenario, go1_driver=dataclasses.replace(driver, wait=wait))


def MakePedipulationDiagram(
    scenario: Scenario,
    meshcat: Meshcat | None = None,
    *,
    hardware: bool = False,
    log_period: float = 0.002,
    operator_lcm: DrakeLcmInterface | None = None,
    operator_messages: list[TimedMessage] | None = None,
) -> PedipulationDiagram:
    """Wires station, estimator, mission manager, leg IK and controller for `scenario`, with a log
    of LOGGED_SIGNALS (and of the controller's diagnostics and the mission's outputs).

    `operator_lcm`: the bus of the operator's input (scenario `operator:`); None opens the URL of
    its `lcm_bus`. In-process tests pass one DrakeLcm("memq://") shared with their publisher. The
    Meshcat panel (`operator: {source: meshcat}`) goes on `meshcat`.
    `operator_messages`: an operator's stream (pedi_drake.operator.message_stream) played on the
    operator's bus in lock step by a MessagePlayer ("operator.player"); without `operator_lcm`
    the bus is then an in-process one (memq://), so nothing leaves the process."""
    mission = load_mission(scenario.mission) if scenario.mission else None
    if mission is not None:
        if scenario.controller not in MISSION_CONTROLLERS:
            raise ScenarioError(f"mission: {scenario.mission!r} needs controller: one of {MISSION_CONTROLLERS}")
        scenario = apply_mission(scenario, mission)
    if hardware:
        scenario = _with_loop_wait_resolved(scenario, mission)
    builder = DiagramBuilder()
    station = builder.AddNamedSystem("station", MakeStation(scenario, meshcat, hardware=hardware))

    if scenario.estimator == "ground_truth":
        if hardware:
            raise ScenarioError("estimator: ground_truth is for simulation only; use estimator: kalman on hardware")
        plant = station.GetSubsystemByName("plant")
        estimator = builder.AddNamedSystem("estimator", GroundTruthEstimator(plant))
        builder.Connect(station.GetOutputPort("sim.plant_state"), estimator.GetInputPort("plant_state"))
    else:
        estimator = builder.AddNamedSystem(
            "estimator",
            KalmanEstimator(
                scenario.kalman, scenario.robot.initial_xy, scenario.robot.prongs, terrain_table(scenario.scene)
            ),
        )
        for name in ("imu", "position_measured", "velocity_measured", "torque_estimated", "foot_contact"):
            builder.Connect(station.GetOutputPort(f"go1.{name}"), estimator.GetInputPort(name))
    base_state = estimator.GetOutputPort("base_state")

    extra_logs = {}
    operator = operator_bus = manager = None
    if operator_messages is not None and scenario.operator.source != "lcm":
        raise ScenarioError(f"operator.source: an operator's stream is played on LCM, got {scenario.operator.source!r}")
    if scenario.operator.source != "none":
        if scenario.operator.source != "meshcat":
            url = "memq://" if operator_messages is not None else scenario.lcm_buses[scenario.operator.lcm_bus].lcm_url
            operator_bus = operator_lcm or DrakeLcm(url)
        operator = _add_operator(builder, scenario, operator_bus, meshcat)
    if operator_messages is not None:
        builder.AddNamedSystem("operator.player", MessagePlayer(operator_bus, operator_messages))
    if operator is not None:
        extra_logs["operator.command"] = operator.GetOutputPort("operator_command")
    if scenario.controller == "stand_pd":
        controller = builder.AddNamedSystem("controller", StandController(scenario.stand))
        builder.Connect(station.GetOutputPort("go1.position_measured"), controller.GetInputPort("position_measured"))
    else:
        system = whole_body_controller(scenario, scenario.controller)
        controller = builder.AddNamedSystem("controller", system)
        # With controller_switch, the other controller ticks beside it on the same inputs.
        controllers = [controller]
        if scenario.controller_switch.enabled:
            other = next(name for name in SWITCHABLE_CONTROLLERS if name != scenario.controller)
            controllers.append(builder.AddNamedSystem(f"controller.{other}", whole_body_controller(scenario, other)))
            extra_logs[f"controller.{other}.diagnostics"] = controllers[1].diagnostics_port
        for each in controllers:
            builder.Connect(base_state, each.base_state_port)
            builder.Connect(station.GetOutputPort("go1.position_measured"), each.position_port)
            builder.Connect(station.GetOutputPort("go1.velocity_measured"), each.velocity_port)
        extra_logs["controller.diagnostics"] = controller.diagnostics_port
        if mission is not None:
            force_estimate = mission.force_estimate or scenario.force_estimate
            if force_estimate == "impedance" and scenario.controller != "projected_impedance":
                raise ScenarioError(
                    f"mission: {scenario.mission!r} uses force_estimate: impedance, which needs "
                    "controller: projected_impedance"
                )
            manager = builder.AddNamedSystem(
                "mission",
                MissionManager(
                    mission,
                    prongs=scenario.robot.prongs,
                    friction=scenario.ground_friction,
                    terrain=terrain_table(scenario.scene),
                    force_estimate=force_estimate,
                    safety_margin=scenario.whole_body.safety_margin,
                    contact_ramp_time=max(
                        scenario.whole_body.contact_ramp_time, scenario.projected_impedance.contact_ramp_time
                    ),
                    wait_for_plans=not hardware,
                ),
            )
            _add_leg_ik(builder, manager)
            if isinstance(system, ProjectedImpedanceController):
                # The Eq. 11 estimate, out of the controller's diagnostics.
                where = system.diag["force_estimate"]
                select = np.zeros((12, controller.diagnostics_port.size()))
                select[np.arange(12), np.arange(where.start, where.stop)] = 1.0
                estimate = builder.AddNamedSystem("foot_force_estimate", MatrixGain(select))
                builder.Connect(controller.diagnostics_port, estimate.get_input_port())
                builder.Connect(estimate.get_output_port(), manager.GetInputPort("foot_force_estimate"))
            builder.Connect(base_state, manager.GetInputPort("base_state"))
            if operator is not None:
                builder.Connect(operator.GetOutputPort("operator_command"), manager.GetInputPort("operator_command"))
            for name in ("position_measured", "velocity_measured", "torque_estimated", "foot_contact"):
                builder.Connect(station.GetOutputPort(f"go1.{name}"), manager.GetInputPort(name))
            # Both references from one evaluation of the manager a tick (see MissionManager).
            split = builder.AddNamedSystem(
                "mission.references", Demultiplexer([BODY_REFERENCE_SIZE, LEG_REFERENCE_SIZE])
            )
            builder.Connect(manager.GetOutputPort("references"), split.get_input_port())
            body_reference, leg_reference = split.get_output_port(0), split.get_output_port(1)
            for each in controllers:
                builder.Connect(body_reference, each.GetInputPort("body_reference"))
            if scenario.trunk_load_compensation.enabled:
                compensator = builder.AddNamedSystem(
                    "trunk_load",
                    TrunkLoadCompensator(
                        scenario.trunk_load_compensation,
                        system.config.period,
                        system.num_contacts,
                        system.model.total_mass,
                        system.model.standing_rotational_inertia(),
                    ),
                )
                builder.Connect(body_reference, compensator.body_reference_port)
                builder.Connect(leg_reference, compensator.leg_reference_port)
                builder.Connect(base_state, compensator.base_state_port)
                builder.Connect(manager.GetOutputPort("contact_set"), compensator.contact_set_port)
                for each in controllers:
                    builder.Connect(compensator.wrench_port, each.GetInputPort("trunk_external_wrench"))
                extra_logs["trunk_load.learnt"] = compensator.GetOutputPort("learnt")
            for each in controllers:
                builder.Connect(leg_reference, each.GetInputPort("leg_reference"))
                for name in ("contact_set", "safety_polygon", "friction"):
                    builder.Connect(manager.GetOutputPort(name), each.GetInputPort(name))
            if isinstance(estimator, KalmanEstimator):
                builder.Connect(manager.GetOutputPort("contact_set"), estimator.contact_set_port)
            if scenario.live_suf.enabled:
                suf = _add_live_suf(builder, scenario, manager, base_state, station)
                extra_logs["mission.suf"] = suf.GetOutputPort("suf")
            if operator_bus is not None and scenario.operator.feedback_channel:
                feedback = builder.AddNamedSystem(
                    "operator.feedback",
                    OperatorFeedback(operator_bus, scenario.operator.feedback_channel, scenario.operator.period),
                )
                builder.Connect(manager.GetOutputPort("operator_feedback"), feedback.GetInputPort("operator_feedback"))
            if meshcat is not None and operator is not None:
                # The haptic feedback drawn in the live view: the force arrow, the limit's bar.
                display = ForceDisplay(meshcat, scenario.operator.period)
                builder.AddNamedSystem("operator.force_display", display)
                builder.Connect(manager.GetOutputPort("operator_feedback"), display.GetInputPort("operator_feedback"))
                builder.Connect(base_state, display.GetInputPort("base_state"))
                measured = station.GetOutputPort("go1.position_measured")
                builder.Connect(measured, display.GetInputPort("position_measured"))
            extra_logs["mission.status"] = manager.GetOutputPort("mission_status")
            # The driven foot's estimated force, which the teleoperated foot's force bound acts on.
            extra_logs["mission.operator_feedback"] = manager.GetOutputPort("operator_feedback")
            extra_logs["mission.body_reference"] = body_reference
            extra_logs["mission.leg_reference"] = leg_reference
            extra_logs["mission.contact_set"] = manager.GetOutputPort("contact_set")
            extra_logs["mission.safety_polygon"] = manager.GetOutputPort("safety_polygon")
            extra_logs["mission.friction"] = manager.GetOutputPort("friction")
    command = controller.GetOutputPort("command")
    if scenario.controller != "stand_pd" and scenario.controller_switch.enabled:
        switch = _add_controller_switch(builder, scenario, controllers, manager, operator)
        command = switch.GetOutputPort("command")
        extra_logs["controller.switch"] = switch.GetOutputPort("switch_state")
    if operator is not None:
        command = _connect_operator_estop(builder, operator, station, command, scenario, hardware)
    builder.Connect(command, station.GetInputPort("go1.command"))

    sources = {"go1.command": command, "base_state": base_state, **extra_logs}
    for name in LOGGED_SIGNALS:
        if name not in sources:
            sources[name] = station.GetOutputPort(name)
    if not hardware:
        for name in SIM_LOGGED_SIGNALS:
            sources[name] = station.GetOutputPort(name)
    else:
        # The host's clock beside the signals: aligns this run's logs with the robot side's.
        sources["wall_clock"] = builder.AddNamedSystem("wall_clock", WallClock()).clock
    logged, log_rows = [], {}

    def log(port) -> slice:
        start = sum(previous.size() for previous in logged)
        logged.append(port)
        return slice(start, start + port.size())

    held = [name for name in sources if not hardware and name in SAMPLED_SENSOR_SIGNALS]
    for name, port in sources.items():
        builder.ExportOutput(port, name)
        if name not in held:
            log_rows[name] = log(port)
    if held:
        # Logged directly, these sensors would be computed twice a tick (see LogHold); one hold
        # for all of them is one Python callback a tick instead of one each.
        sizes = [sources[name].size() for name in held]
        gather = builder.AddNamedSystem(f"{LOG_HOLD}.signals", Multiplexer(sizes))
        for k, name in enumerate(held):
            builder.Connect(sources[name], gather.get_input_port(k))
        hold = builder.AddNamedSystem(LOG_HOLD, LogHold(sum(sizes), log_period))
        builder.Connect(gather.get_output_port(), hold.get_input_port())
        block = log(hold.get_output_port())
        for name, start in zip(held, np.cumsum([0, *sizes[:-1]]), strict=True):
            log_rows[name] = slice(block.start + int(start), block.start + int(start) + sources[name].size())
    signals = builder.AddNamedSystem(LOG_MULTIPLEXER, Multiplexer([port.size() for port in logged]))
    for k, port in enumerate(logged):
        builder.Connect(port, signals.get_input_port(k))
    sink = builder.AddNamedSystem(LOG_SINK, VectorLogSink(signals.get_output_port().size(), log_period))
    builder.Connect(signals.get_output_port(), sink.get_input_port())
    diagram = builder.Build()
    diagram.set_name("pedipulation")
    return PedipulationDiagram(
        diagram=diagram, log_rows=log_rows, hardware=hardware, mission=mission, log_period=log_period
    )
