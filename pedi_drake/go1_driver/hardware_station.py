"""MakeHardwareStation: the Go1 LCM driver behind the station ports (`pedi_drake.station_interface`).

    go1.command (60) -> Go1SafetyFilter -> Go1CommandSender -> pd_plustau_targets
    leg_control_data      -> go1.position_measured, go1.velocity_measured, go1.torque_estimated
    state_estimator_data  -> go1.imu, go1.foot_contact (raw sensor value)
    rc_command            -> the remote's E-stop button
all on the scenario's LCM bus "go1" through one LcmInterfaceSystem. Driver-only ports:
    input  driver.estop (1, optional): > 0.5 latches damping
    output driver.status (1 + len(INTERVENTIONS)): latched reason and intervention counters
    output driver.message_counts (6): [received, dropped] for leg_control_data,
           state_estimator_data, rc_command
    output driver.command_published (60): the bounded command that goes on the wire
Run the diagram in real time (Simulator target_realtime_rate = 1): the watchdogs use the wall clock.
"""

from pydrake.lcm import DrakeLcm, DrakeLcmInterface, DrakeLcmParams
from pydrake.systems.framework import Diagram, DiagramBuilder
from pydrake.systems.lcm import LcmInterfaceSystem
from pydrake.systems.primitives import Multiplexer

from pedi_drake.exceptions import ScenarioError
from pedi_drake.go1_driver import constants as c
from pedi_drake.go1_driver.command_sender import Go1CommandSender
from pedi_drake.go1_driver.config import Go1DriverConfig
from pedi_drake.go1_driver.safety import Go1SafetyFilter
from pedi_drake.go1_driver.status_receiver import (
    MakeLegControlReceiver,
    MakeRcCommandReceiver,
    MakeStateEstimatorReceiver,
)


def go1_lcm(lcm_buses: dict[str, DrakeLcmParams]) -> DrakeLcm:
    """A DrakeLcm on the bus "go1" of `lcm_buses` (a Scenario's; default udpm://239.255.76.67:7667?ttl=0)."""
    if c.GO1_BUS_NAME not in lcm_buses:
        raise ScenarioError(f"lcm_buses: no bus named {c.GO1_BUS_NAME!r}, which the Go1 driver uses")
    return DrakeLcm(lcm_buses[c.GO1_BUS_NAME])


def MakeHardwareStation(config: Go1DriverConfig, lcm: DrakeLcmInterface) -> Diagram:
    """The Go1 LCM driver with settings `config` on `lcm` (ports as MakeStation's; see the module docstring).

    `lcm`: the bus to the robot (`go1_lcm(scenario.lcm_buses)`, or "memq://" for in-process tests).
    Initialising the diagram waits up to config.first_status_timeout [s] for leg_control_data and
    state_estimator_data and raises LcmTimeout naming channel and URL when they do not come.
    """
    period = config.safety.period
    builder = DiagramBuilder()
    builder.AddNamedSystem("lcm", LcmInterfaceSystem(lcm))
    wait = config.first_status_timeout
    leg = builder.AddNamedSystem("leg_control_receiver", MakeLegControlReceiver(lcm, period=period, wait_timeout=wait))
    estimator = builder.AddNamedSystem(
        "state_estimator_receiver", MakeStateEstimatorReceiver(lcm, period=period, wait_timeout=wait)
    )
    remote = builder.AddNamedSystem(
        "rc_command_receiver", MakeRcCommandReceiver(lcm, config.safety.rc_estop_fields, period=period)
    )
    safety = builder.AddNamedSystem("safety", Go1SafetyFilter(config.safety, num_status_channels=2))
    sender = builder.AddNamedSystem("command_sender", Go1CommandSender(lcm, period=period))

    times = builder.AddNamedSystem("status_receipt_times", Multiplexer([1, 1]))
    builder.Connect(leg.GetOutputPort("receipt_time"), times.get_input_port(0))
    builder.Connect(estimator.GetOutputPort("receipt_time"), times.get_input_port(1))
    builder.Connect(times.get_output_port(), safety.GetInputPort("status_receipt_times"))
    builder.Connect(leg.GetOutputPort("position_measured"), safety.GetInputPort("position_measured"))
    builder.Connect(leg.GetOutputPort("velocity_measured"), safety.GetInputPort("velocity_measured"))
    builder.Connect(remote.GetOutputPort("estop"), safety.GetInputPort("rc_estop"))
    builder.Connect(safety.GetOutputPort("command"), sender.GetInputPort("command"))

    builder.ExportInput(safety.GetInputPort("command"), "go1.command")
    for name in ("position_measured", "velocity_measured", "torque_estimated"):
        builder.ExportOutput(leg.GetOutputPort(name), f"go1.{name}")
    builder.ExportOutput(estimator.GetOutputPort("imu"), "go1.imu")
    builder.ExportOutput(estimator.GetOutputPort("foot_contact"), "go1.foot_contact")

    builder.ExportInput(safety.GetInputPort("estop"), "driver.estop")
    builder.ExportOutput(safety.GetOutputPort("status"), "driver.status")
    builder.ExportOutput(safety.GetOutputPort("command"), "driver.command_published")
    counts = builder.AddNamedSystem("message_counts", Multiplexer([2, 2, 2]))
    # In the order of c.STATUS_CHANNELS.
    for i, receiver in enumerate((leg, estimator, remote)):
        builder.Connect(receiver.GetOutputPort("message_counts"), counts.get_input_port(i))
    builder.ExportOutput(counts.get_output_port(), "driver.message_counts")
    diagram = builder.Build()
    diagram.set_name("go1_hardware_station")
    return diagram
