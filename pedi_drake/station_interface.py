"""MakeStation: the simulated Go1 or the Go1 LCM driver, behind identical `go1.*` ports."""

from pydrake.geometry import Meshcat
from pydrake.systems.framework import Diagram

from pedi_drake.go1_driver.hardware_station import MakeHardwareStation, go1_link
from pedi_drake.scenario import Scenario
from pedi_drake.station.sim_station import MakeSimulationStation

STATION_PORTS = {
    # name: (direction, size)
    "go1.command": ("input", 60),
    "go1.position_measured": ("output", 12),
    "go1.velocity_measured": ("output", 12),
    "go1.torque_estimated": ("output", 12),
    "go1.imu": ("output", 10),
    "go1.foot_contact": ("output", 4),
}


def MakeStation(scenario: Scenario, meshcat: Meshcat | None = None, *, hardware: bool = False) -> Diagram:
    """The station for `scenario`: a MultibodyPlant simulation, or with `hardware=True` the LCM driver.

    Both export the ports of STATION_PORTS (Unitree motor order); the simulation also exports
    `sim.*` ports for logging and tests.
    """
    if hardware:
        # The driver draws nothing: `meshcat` is for the simulation's visualiser.
        return MakeHardwareStation(scenario.go1_driver, go1_link(scenario.go1_driver, scenario.lcm_buses))
    return MakeSimulationStation(scenario, meshcat)
