"""MakeHardwareStation: the Go1 LCM driver behind the station ports (`pedi_drake.station_interface`).

    go1.command (60) -> Go1SafetyFilter -> Go1CommandSender -> pd_plustau_targets
    leg_control_data      -> go1.position_measured, go1.velocity_measured, go1.torque_estimated
    state_estimator_data  -> go1.imu, go1.foot_contact (raw sensor value)
    rc_command            -> the remote's E-stop button
all on the scenario's LCM bus "go1" (one receiver latches the three status channels). Driver-only ports:
    input  driver.estop (1, optional): > 0.5 latches damping
    output driver.status (1 + len(INTERVENTIONS)): latched reason and intervention counters
    output driver.message_counts (6): [received, dropped] for leg_control_data,
           state_estimator_data, rc_command
    output driver.command_published (60): the bounded command that goes on the wire
The messages travel through a Go1Link (go1_driver/link.py): the loop reads and stamps status
messages at the start of every tick, the link's own thread does while the loop is late, and that
thread's guard damps a loop that went silent; `hardware_link(diagram)`
finds it, for `hold_damping` at shutdown and for `report()` (rejected messages by reason, the
loop's lateness). Run the diagram in real time (Simulator target_realtime_rate = 1): the
watchdogs use the wall clock.

Within a tick: the receiver latches the newest status (an unrestricted update, before the
estimator and the controller update from it); then, one microsecond of diagram time later
(constants.COMMAND_OFFSET), the safety filter bounds the command the controller computed in this
tick (an unrestricted update) and the sender publishes it (a discrete update of the same instant,
which Drake computes after the unrestricted ones). A status's joint angles reach the wire in the
tick that latched them; a tick takes two simulator steps.
"""

from pydrake.lcm import DrakeLcmParams
from pydrake.systems.framework import Diagram, DiagramBuilder

from pedi_drake.exceptions import ScenarioError
from pedi_drake.go1_driver import constants as c
from pedi_drake.go1_driver.command_sender import Go1CommandSender
from pedi_drake.go1_driver.config import Go1DriverConfig
from pedi_drake.go1_driver.link import Go1Link
from pedi_drake.go1_driver.safety import Go1SafetyFilter
from pedi_drake.go1_driver.status_receiver import MakeStatusReceiver


def go1_lcm_url(lcm_buses: dict[str, DrakeLcmParams]) -> str:
    """The URL of the bus "go1" of `lcm_buses` (a Scenario's; default udpm://239.255.76.67:7667?ttl=0)."""
    if c.GO1_BUS_NAME not in lcm_buses:
        raise ScenarioError(f"lcm_buses: no bus named {c.GO1_BUS_NAME!r}, which the Go1 driver uses")
    return lcm_buses[c.GO1_BUS_NAME].lcm_url


def go1_link(config: Go1DriverConfig, lcm_buses: dict[str, DrakeLcmParams]) -> Go1Link:
    """The driver's Go1Link on the bus "go1" of `lcm_buses`."""
    return Go1Link.from_url(go1_lcm_url(lcm_buses), config)


def hardware_link(diagram: Diagram) -> Go1Link | None:
    """The Go1Link of the hardware station inside `diagram` (or `diagram` itself), None without one."""
    for system in diagram.GetSystems():
        if isinstance(system, Go1CommandSender):
            return system.link
        if isinstance(system, Diagram):
            link = hardware_link(system)
            if link is not None:
                return link
    return None


def MakeHardwareStation(config: Go1DriverConfig, link: Go1Link) -> Diagram:
    """The Go1 LCM driver with settings `config` on `link` (ports as MakeStation's; see the module docstring).

    `link`: the bus to the robot (`go1_link(config, scenario.lcm_buses)`, or a Go1Link on an
    in-process transport for tests). Initialising the diagram starts the link's receive thread and
    waits up to config.first_status_timeout [s] for leg_control_data and state_estimator_data,
    raising LcmTimeout naming channel and URL when they do not come.
    """
    period = config.safety.period
    builder = DiagramBuilder()
    # One receiver latches the three status channels (one Python call a tick); its outputs are
    # parts of its state, split off by compiled code.
    status = builder.AddNamedSystem(
        "status_receiver", MakeStatusReceiver(link, period=period, wait_timeout=config.first_status_timeout)
    )
    safety = builder.AddNamedSystem("safety", Go1SafetyFilter(config.safety, num_status_channels=2))
    sender = builder.AddNamedSystem("command_sender", Go1CommandSender(link, period=period))

    builder.Connect(status.GetOutputPort("robot_status"), safety.GetInputPort("robot_status"))
    builder.Connect(safety.GetOutputPort("command"), sender.GetInputPort("command"))

    builder.ExportInput(safety.GetInputPort("command"), "go1.command")
    for name in ("position_measured", "velocity_measured", "torque_estimated", "imu", "foot_contact"):
        builder.ExportOutput(status.GetOutputPort(name), f"go1.{name}")

    builder.ExportInput(safety.GetInputPort("estop"), "driver.estop")
    builder.ExportOutput(safety.GetOutputPort("status"), "driver.status")
    builder.ExportOutput(safety.GetOutputPort("command"), "driver.command_published")
    # In the order of c.STATUS_CHANNELS.
    builder.ExportOutput(status.GetOutputPort("message_counts"), "driver.message_counts")
    diagram = builder.Build()
    diagram.set_name("go1_hardware_station")
    return diagram
