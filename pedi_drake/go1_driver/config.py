"""Settings of the Go1 LCM driver: safety bounds, watchdogs, soft start, and the simulator bridge.

The Scenario field `go1_driver: Go1DriverConfig`: one YAML file tunes both the driver (controller
side) and the simulator bridge (robot side, `python -m pedi_drake.apps.sim_bridge`).
"""

import dataclasses

from pedi_drake.go1_driver.constants import BRIDGE_PERIOD, RC_ESTOP_FIELDS


@dataclasses.dataclass
class Go1SafetyConfig:
    """Bounds the driver enforces on every command before it is published."""

    # Control (and publish) period of the driver [s]: the bridge's 500 Hz.
    period: float = BRIDGE_PERIOD
    # Largest position gain sent to a motor [N m/rad].
    kp_max: float = 150.0
    # Largest damping gain sent to a motor [N m s/rad].
    kd_max: float = 10.0
    # Damping gain of the safe (damping) command [N m s/rad]; must be > 0.
    damping_kd: float = 2.0
    # Largest rate of change of a published position target [rad/s].
    max_target_rate: float = 8.0
    # Switch to damping when no status message arrived for this long [s]. 40 ms of silence plus
    # one 2 ms tick puts damping on the wire within 50 ms of the last status message.
    status_timeout: float = 0.04
    # Switch to damping when the driver's own loop has not published for this long [s]: the
    # controller stopped producing (a hang); the robot-side bridge would hold the last command.
    command_timeout: float = 0.05
    # The first ticks of a run do one-time work (the mission's first update, the first solves, the
    # first evaluations of every cache) while the soft start publishes the measured pose: during
    # the first `warmup_duration` [s] of the loop the loop-silence limit is `warmup_command_timeout` [s].
    warmup_duration: float = 0.1
    warmup_command_timeout: float = 0.5
    # Duration of the soft start that blends targets from the measured pose [s].
    soft_start_duration: float = 1.0
    # rc_command fields whose non-zero value latches the E-stop (the remote's button).
    rc_estop_fields: list[str] = dataclasses.field(default_factory=lambda: list(RC_ESTOP_FIELDS))


@dataclasses.dataclass
class Go1BridgeConfig:
    """Imperfections of the robot-side simulator bridge (`pedi_drake.apps.sim_bridge`)."""

    # Extra delay of every published status message [s] (0: none).
    latency: float = 0.0
    # Probability that a status tick is not published [-].
    drop_probability: float = 0.0
    # SCHED_FIFO priority [1-99] of the bridge's threads; 0 (the default): the OS's normal
    # scheduling. The simulated robot can need most of a core on a slow machine, and Linux lets
    # real-time threads have at most 0.95 s of every second by default
    # (/proc/sys/kernel/sched_rt_runtime_us): a bridge under SCHED_FIFO that needs more is stopped
    # for the rest of each second, and the driver's status watchdog latches. At
    # normal scheduling the bridge is never stopped so, and the driver's loop, if it runs under
    # SCHED_FIFO, still comes first (docs/real_time.md).
    realtime_priority: int = 0


@dataclasses.dataclass
class Go1DriverConfig:
    """The Go1 LCM driver (controller side) and its simulator bridge (robot side)."""

    # Wait this long for the first status message when the driver starts [s].
    first_status_timeout: float = 5.0
    # Every exit of a hardware run (mission end, Ctrl-C, SIGTERM, an exception) puts damping on the
    # wire for this long before the process leaves [s]: the bridge holds the last command it
    # received, so the last one must be damping, repeated in case a datagram is lost.
    shutdown_damping_duration: float = 0.3
    # SCHED_FIFO priority [1-99] of every thread of the driver's wall-clock loop (controller
    # side; the simulator bridge has its own, `bridge.realtime_priority`); 0: the OS's normal scheduling. Where the OS
    # refuses (no root, CAP_SYS_NICE or `ulimit -r`), the loop runs at normal priority with a
    # warning, and result.json says which it got (see pedi_drake.runtime.realtime_priority). Off by
    # default: with it the semi-autonomous mode's posture plans, computed at normal priority,
    # come late (docs/real_time.md).
    realtime_priority: int = 0
    # How the loop waits for its next period: "sleep" (the OS's timer), "spin" (a busy wait that
    # keeps a core busy for as long as the loop runs, and keeps the loop on time where waking a
    # sleeping thread is slow, as on virtual machines) or "auto": spin unless the
    # loop runs at a real-time priority or the run has an operator or a posture planner, whose
    # work needs that core (pedi_drake/go1_driver/pacing.py, docs/real_time.md).
    wait: str = "auto"
    # Safety layer bounds and watchdogs.
    safety: Go1SafetyConfig = dataclasses.field(default_factory=Go1SafetyConfig)
    # The simulator bridge's latency, message drops and scheduling.
    bridge: Go1BridgeConfig = dataclasses.field(default_factory=Go1BridgeConfig)
