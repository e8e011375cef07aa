"""Settings of the operator input (the Scenario field `operator:`)."""

import dataclasses
import math

from pedi_drake.go1_driver.constants import GO1_BUS_NAME, RC_ESTOP_FIELDS
from pedi_drake.go1_driver.lcmtypes import rc_command_lcmt

OPERATOR_SOURCES = ("none", "lcm", "remote", "meshcat")
# Sources read from an LCM bus (the Meshcat panel is read from the Meshcat server).
LCM_SOURCES = ("lcm", "remote")
REMOTE_FRAMES = ("trunk", "world")
REMOTE_STICKS = ("foot", "walk")
# The remote's switches (rc_command_lcmt fields, int16 on the wire: non-zero while pressed).
REMOTE_BUTTONS = tuple(name for name in rc_command_lcmt.__slots__ if name.endswith("_switch"))
# The project's foot command channel (type foot_command_lcmt) and its feedback channel
# (foot_feedback_lcmt, pedi_drake.operator.feedback).
DEFAULT_FOOT_COMMAND_CHANNEL = "operator_foot_command"
DEFAULT_FOOT_FEEDBACK_CHANNEL = "operator_foot_feedback"


@dataclasses.dataclass
class RemoteMapping:
    """How the Go1 remote's sticks and buttons (rc_command, walk-these-ways layout) become a command.

    Sticks are in [-1, 1]: left stick up (left_stick[1]) moves the foot forward (+x), left stick
    right (left_stick[0]) moves it right (-y), right stick up (right_stick[1]) moves it up (+z).
    With `sticks: walk` they drive a walk_teleop phase instead: left stick up walks forward, left
    stick right walks to the right, right stick right (right_stick[0]) turns right, each at
    `walk_speeds` at full deflection.
    """

    # What the sticks command: "foot" (a lifted foot's velocity) or "walk" (the trunk's twist).
    sticks: str = "foot"
    # The twist at full deflection: forward [m/s], sideways [m/s], yaw rate [rad/s]; the static
    # walk's limits (pedi_drake.locomotion.gait.GAITS), which a walk_teleop phase holds it to.
    walk_speeds: list[float] = dataclasses.field(default_factory=lambda: [0.2, 0.11, 0.3])

    # Foot speed at full stick deflection [m/s].
    max_speed: float = 0.1
    # Stick deflections below this count as zero (the sticks do not rest at exactly 0) [-].
    deadband: float = 0.05
    # Frame of the foot velocity: "trunk" or "world".
    frame: str = "trunk"
    # Button (an rc_command switch field) that asks for the teleoperated foot.
    teleop_button: str = "right_upper_switch"
    # Button that asks for the autonomous mission.
    autonomous_button: str = "left_upper_switch"
    # Buttons that latch the E-stop (the driver's remote E-stop buttons by default).
    estop_buttons: list[str] = dataclasses.field(default_factory=lambda: list(RC_ESTOP_FIELDS))


@dataclasses.dataclass
class MeshcatPanelConfig:
    """The Meshcat panel (source: meshcat): sliders for the foot velocity, buttons for the modes.

    The panel's keys (with the page focused) follow `pedi_drake.apps.teleop_lcm`: w/s, a/d, r/f
    step the x, y, z sliders, space stops the foot, t asks for teleop, g for the autonomous
    mission, e is the E-stop.
    """

    # The sliders' range: the foot velocity in [-max_speed, max_speed] along each axis [m/s].
    max_speed: float = 0.1
    # The sliders' step (and a key press's) [m/s].
    step: float = 0.005
    # Frame of the foot velocity: "trunk" or "world".
    frame: str = "trunk"
    # What the sliders command: "foot" (a lifted foot's velocity) or "walk" (the trunk's twist
    # for a walk_teleop phase, each slider within +-walk_speeds).
    sliders: str = "foot"
    # The twist's bounds: forward [m/s], sideways [m/s], yaw rate [rad/s] (the static walk's limits).
    walk_speeds: list[float] = dataclasses.field(default_factory=lambda: [0.2, 0.11, 0.3])


@dataclasses.dataclass
class OperatorConfig:
    """Where the operator's commands come from and how they are read."""

    # "none" (no operator), "lcm" (foot_command_lcmt on `channel`), "remote" (the Go1 remote's
    # rc_command, mapped by `remote`) or "meshcat" (a panel in the Meshcat page, `meshcat`).
    source: str = "none"
    # The LCM bus (a name in the scenario's lcm_buses) the commands arrive on.
    lcm_bus: str = GO1_BUS_NAME
    # Channel of the foot commands (source: lcm).
    channel: str = DEFAULT_FOOT_COMMAND_CHANNEL
    # How often the input is read and the feedback published [s].
    period: float = 0.01
    # Channel of the haptic feedback (foot_feedback_lcmt: the estimated foot force, the balance
    # bound and the live SUF) on the same bus; empty: none published.
    feedback_channel: str = DEFAULT_FOOT_FEEDBACK_CHANNEL
    # The remote's mapping (source: remote).
    remote: RemoteMapping = dataclasses.field(default_factory=RemoteMapping)
    # The Meshcat panel (source: meshcat).
    meshcat: MeshcatPanelConfig = dataclasses.field(default_factory=MeshcatPanelConfig)

    def problems(self, lcm_buses) -> list[tuple[str, str]]:
        """(field, problem) for every invalid value (field relative to `operator`); empty when valid."""
        found = []
        if self.source not in OPERATOR_SOURCES:
            found.append(("source", f"must be one of {OPERATOR_SOURCES}, got {self.source!r}"))
        if self.source in LCM_SOURCES and self.lcm_bus not in lcm_buses:
            found.append(("lcm_bus", f"no bus named {self.lcm_bus!r} in lcm_buses ({sorted(lcm_buses)})"))
        if not self.channel:
            found.append(("channel", "must name an LCM channel"))
        if not (math.isfinite(self.period) and self.period > 0):
            found.append(("period", f"must be a finite number > 0 s, got {self.period}"))
        panel = self.meshcat
        if not (math.isfinite(panel.max_speed) and panel.max_speed > 0):
            found.append(("meshcat.max_speed", f"must be a finite number > 0 m/s, got {panel.max_speed}"))
        if not (math.isfinite(panel.step) and 0 < panel.step <= panel.max_speed):
            found.append(("meshcat.step", f"must be in (0, max_speed] m/s, got {panel.step}"))
        if panel.frame not in REMOTE_FRAMES:
            found.append(("meshcat.frame", f"must be one of {REMOTE_FRAMES}, got {panel.frame!r}"))
        if panel.sliders not in REMOTE_STICKS:
            found.append(("meshcat.sliders", f"must be one of {REMOTE_STICKS}, got {panel.sliders!r}"))
        for field, speeds in (
            ("meshcat.walk_speeds", panel.walk_speeds),
            ("remote.walk_speeds", self.remote.walk_speeds),
        ):
            if len(speeds) != 3 or not all(math.isfinite(v) and v > 0 for v in speeds):
                found.append((field, f"expected 3 finite numbers > 0 [m/s, m/s, rad/s], got {speeds}"))
        remote = self.remote
        if not (math.isfinite(remote.max_speed) and remote.max_speed > 0):
            found.append(("remote.max_speed", f"must be a finite number > 0 m/s, got {remote.max_speed}"))
        if not (math.isfinite(remote.deadband) and 0 <= remote.deadband < 1):
            found.append(("remote.deadband", f"must be in [0, 1), got {remote.deadband}"))
        if remote.frame not in REMOTE_FRAMES:
            found.append(("remote.frame", f"must be one of {REMOTE_FRAMES}, got {remote.frame!r}"))
        if remote.sticks not in REMOTE_STICKS:
            found.append(("remote.sticks", f"must be one of {REMOTE_STICKS}, got {remote.sticks!r}"))
        buttons = {"remote.teleop_button": remote.teleop_button, "remote.autonomous_button": remote.autonomous_button}
        buttons.update({f"remote.estop_buttons[{i}]": b for i, b in enumerate(remote.estop_buttons)})
        for field, button in buttons.items():
            if button not in REMOTE_BUTTONS:
                found.append((field, f"must be one of {REMOTE_BUTTONS}, got {button!r}"))
        if remote.teleop_button == remote.autonomous_button:
            found.append(("remote.autonomous_button", "must differ from remote.teleop_button"))
        if {remote.teleop_button, remote.autonomous_button} & set(remote.estop_buttons):
            found.append(("remote.estop_buttons", "a mode button cannot also be an E-stop button"))
        return found
