"""The Go1 driver's safety layer: every command is bounded here before it is published.

Plain functions (`bound_command`, `damping_command`) hold the maths; `Go1SafetyFilter` is the
LeafSystem that applies them at the control rate with its watchdogs, soft start and latched
E-stop, keeping everything that changes (last published command, soft-start pose, latch,
intervention counters) in the Context's discrete state. Its tick is one compiled call
(`_filter_step_kernel`, built from the same kernels) that writes that state in place.

What is guaranteed for every published command (Unitree order, `go1.command` layout):
  * all 60 values are finite;
  * q_des within the intersection of the URDF and Unitree SDK limits (robot.HARDWARE_Q_*);
  * |qd_des| <= robot.VELOCITY_LIMIT, |tau_ff| <= robot.EFFORT_LIMIT;
  * 0 <= kp <= kp_max, 0 <= kd <= kd_max;
  * the torque the motors would apply at the measured state,
    |tau_ff + kp (q_des - q) + kd (qd_des - qd)|, is within robot.EFFORT_LIMIT.
"""

import dataclasses
import logging
import math
import time
from collections.abc import Callable

import numpy as np
from pydrake.systems.framework import BasicVector, State

from pedi_drake import robot
from pedi_drake.go1_command import COMMAND_SIZE
from pedi_drake.go1_driver.config import Go1SafetyConfig
from pedi_drake.go1_driver.constants import COMMAND_OFFSET, STATUS_CHANNELS
from pedi_drake.leaf_system import LeafSystemWithoutWitnesses
from pedi_drake.runtime.jit import kernel

_log = logging.getLogger(__name__)

# Kinds of intervention, counted separately (index = position in this tuple).
INTERVENTIONS = (
    "nonfinite_command",  # NaN/Inf in the controller's command: damping this tick
    "nonfinite_status",  # NaN/Inf in the measured joint state: damping this tick
    "position_clamped",  # q_des outside the hardware joint limits
    "velocity_clamped",  # qd_des outside the velocity limits
    "gain_clamped",  # kp or kd outside [0, max]
    "feedforward_clamped",  # tau_ff outside the effort limits
    "torque_bounded",  # the resulting PD torque at the measured state exceeded the effort limits
    "rate_limited",  # q_des moved faster than max_target_rate
    "soft_start",  # targets blended from the measured pose (counted per tick)
    "status_timeout",  # status messages stopped (latches damping)
    "controller_silence",  # the driver loop did not run for command_timeout (latches damping)
    "estop_port",  # E-stop from the driver.estop input (latches damping)
    "estop_remote",  # E-stop from the remote's button on rc_command (latches damping)
    "damping",  # damping command published (counted per tick)
)
INTERVENTION_INDEX = {name: i for i, name in enumerate(INTERVENTIONS)}
LATCHING = ("status_timeout", "controller_silence", "estop_port", "estop_remote")

# Internal torque bound, a hair inside the effort limit so that rounding never crosses it.
_EFFORT_MARGIN = 1.0 - 1e-9


@dataclasses.dataclass(frozen=True)
class SafetyLimits:
    """The bounds a published command must respect (arrays in Unitree order)."""

    q_lower: np.ndarray  # (12,) [rad]
    q_upper: np.ndarray  # (12,) [rad]
    qd_max: np.ndarray  # (12,) [rad/s]
    effort: np.ndarray  # (12,) [N m]
    kp_max: float  # [N m/rad]
    kd_max: float  # [N m s/rad]
    max_target_step: float  # largest change of q_des in one control period [rad]

    @staticmethod
    def from_config(config: Go1SafetyConfig) -> "SafetyLimits":
        return SafetyLimits(
            q_lower=robot.HARDWARE_Q_LOWER.copy(),
            q_upper=robot.HARDWARE_Q_UPPER.copy(),
            qd_max=robot.VELOCITY_LIMIT.copy(),
            effort=robot.EFFORT_LIMIT.copy(),
            kp_max=float(config.kp_max),
            kd_max=float(config.kd_max),
            max_target_step=float(config.max_target_rate * config.period),
        )

    def clip_position(self, q: np.ndarray) -> np.ndarray:
        """q clipped into the joint limits, non-finite entries replaced by the range's middle [rad]."""
        return _clip_position_kernel(np.asarray(q, dtype=float), self.q_lower, self.q_upper)


@kernel
def _clip_position_kernel(q, q_lower, q_upper):
    """`SafetyLimits.clip_position` on plain arrays (12,)."""
    out = np.empty(12)
    for j in range(12):
        value = q[j] if math.isfinite(q[j]) else 0.5 * (q_lower[j] + q_upper[j])
        out[j] = min(max(value, q_lower[j]), q_upper[j])
    return out


def driver_report(status: np.ndarray, message_counts: np.ndarray | None = None) -> dict:
    """The driver's `status` output (and `message_counts`) as a plain dictionary for result files.

    {"latched": name of the intervention that latched damping, or None, "interventions": {name:
    count} of every kind that fired, "messages": {channel: {"received", "dropped"}}}.
    """
    status = np.asarray(status, dtype=float)
    latch = int(status[0])
    report = {
        "latched": INTERVENTIONS[latch - 1] if latch > 0 else None,
        "interventions": {name: int(count) for name, count in zip(INTERVENTIONS, status[1:], strict=True) if count},
    }
    if message_counts is not None:
        channels = STATUS_CHANNELS
        counts = np.asarray(message_counts, dtype=float).reshape(len(channels), 2)
        report["messages"] = {
            channel: {"received": int(received), "dropped": int(dropped)}
            for channel, (received, dropped) in zip(channels, counts, strict=True)
        }
    return report


def damping_command(q_hold: np.ndarray, qd: np.ndarray, limits: SafetyLimits, kd: float) -> np.ndarray:
    """The safe command: kp = 0, kd > 0, tau_ff = 0, qd_des = 0.

    q_des = q_hold clipped into the limits (irrelevant with kp = 0, but always a valid target).
    kd is reduced per joint where kd |qd| would exceed the effort limit, so the damping torque
    at the measured rates stays within the limits; non-finite rates count as zero.
    """
    return _damping_kernel(
        np.asarray(q_hold, dtype=float),
        np.asarray(qd, dtype=float),
        limits.q_lower,
        limits.q_upper,
        limits.effort,
        limits.kd_max,
        float(kd),
    )


@kernel
def _damping_kernel(q_hold, qd, q_lower, q_upper, effort, kd_max, kd):
    """`damping_command` on plain arrays: the command (60,)."""
    out = np.zeros(60)
    out[0:12] = _clip_position_kernel(q_hold, q_lower, q_upper)
    gain = min(max(kd, 1e-3), kd_max)
    for j in range(12):
        rate = qd[j] if math.isfinite(qd[j]) else 0.0
        bound = effort[j] * _EFFORT_MARGIN
        out[36 + j] = bound / max(abs(rate), 1e-300) if gain * abs(rate) > bound else gain
    return out


# Bits of `_bound_command_kernel`'s flags, named as in INTERVENTIONS.
_BOUND_FLAGS = (
    "gain_clamped",
    "position_clamped",
    "rate_limited",
    "velocity_clamped",
    "feedforward_clamped",
    "torque_bounded",
)


@kernel
def _bound_command_kernel(command, q, qd, q_lower, q_upper, qd_max, effort, kp_max, kd_max, step, q_prev, rate_limit):
    """The maths of `bound_command` on plain arrays: (bounded command (60,), flag bits of _BOUND_FLAGS).

    Element by element in the order numpy would apply them, so the compiled and the plain-Python
    runs agree to the last bit: clip = min(max(x, lower), upper).
    """
    out = command.copy()
    flags = 0
    bound = np.empty(12)
    aim = np.empty(12)
    pd = np.empty(12)
    over = np.zeros(12, dtype=np.bool_)
    any_over = False
    for j in range(12):
        iq, iqd, ikp, ikd, itau = j, 12 + j, 24 + j, 36 + j, 48 + j
        kp = min(max(command[ikp], 0.0), kp_max)
        kd = min(max(command[ikd], 0.0), kd_max)
        if kp != command[ikp] or kd != command[ikd]:
            flags |= 1
        q_des = min(max(command[iq], q_lower[j]), q_upper[j])
        if q_des != command[iq]:
            flags |= 2
        if rate_limit:
            limited = min(max(q_des, q_prev[j] - step), q_prev[j] + step)
            if limited != q_des:
                flags |= 4
            # The previous target is inside the limits, so this keeps both bounds.
            q_des = min(max(limited, q_lower[j]), q_upper[j])
        qd_des = min(max(command[iqd], -qd_max[j]), qd_max[j])
        if qd_des != command[iqd]:
            flags |= 8
        tau = min(max(command[itau], -effort[j]), effort[j])
        if tau != command[itau]:
            flags |= 16
        # Resulting torque at the measured state, aimed a hair inside the bound so that rounding
        # in the move below does not cross it.
        bound[j] = effort[j] * _EFFORT_MARGIN
        aim[j] = bound[j] * _EFFORT_MARGIN
        tau = min(max(tau, -aim[j]), aim[j])
        pd[j] = kp * (q_des - q[j]) + kd * (qd_des - qd[j])
        over[j] = abs(tau + pd[j]) > aim[j]
        any_over = any_over or over[j]
        out[iq], out[iqd], out[ikp], out[ikd], out[itau] = q_des, qd_des, kp, kd, tau
    if any_over:
        # Where the torque exceeds the effort limit, pull the targets toward the measured state
        # (same stiffness, smaller error) until it sits on the limit.
        flags |= 32
        any_still = False
        still = np.zeros(12, dtype=np.bool_)
        for j in range(12):
            iq, iqd, ikp, ikd, itau = j, 12 + j, 24 + j, 36 + j, 48 + j
            tau = out[itau]
            scale = 1.0
            if over[j]:
                target = min(max(tau + pd[j], -aim[j]), aim[j])
                scale = (target - tau) / pd[j]
            out[iq] = min(max(q[j] + scale * (out[iq] - q[j]), q_lower[j]), q_upper[j])
            out[iqd] = min(max(qd[j] + scale * (out[iqd] - qd[j]), -qd_max[j]), qd_max[j])
            pd[j] = out[ikp] * (out[iq] - q[j]) + out[ikd] * (out[iqd] - qd[j])
            still[j] = abs(tau + pd[j]) > bound[j]
            any_still = any_still or still[j]
        if any_still:
            # The re-clip can only matter when the measured state is itself outside the limits:
            # then soften both gains on that joint, which always reaches the bound (|tau_ff| <= it).
            for j in range(12):
                ikp, ikd, itau = 24 + j, 36 + j, 48 + j
                gain_scale = 1.0
                if still[j]:
                    tau = out[itau]
                    target = min(max(tau + pd[j], -bound[j]), bound[j])
                    gain_scale = min(max((target - tau) / pd[j], 0.0), 1.0)
                out[ikp] = out[ikp] * gain_scale
                out[ikd] = out[ikd] * gain_scale
    return out, flags


def bound_command(
    command: np.ndarray,
    q: np.ndarray,
    qd: np.ndarray,
    limits: SafetyLimits,
    q_des_previous: np.ndarray | None = None,
) -> tuple[np.ndarray, set[str]]:
    """The command clipped into `limits`, and the names of the interventions applied.

    `command` must be finite and q [rad], qd [rad/s] (the measured state) finite: the caller
    replaces anything else by `damping_command`. `q_des_previous` is the last published target
    [rad] for the rate limit (None: no rate limit).

    In order: gains into [0, max], q_des into the joint limits, then within `max_target_step` of
    the previous target, qd_des and tau_ff into their limits; then, where the torque the motors
    would apply at the measured state exceeds the effort limit, the targets are pulled toward the
    measured state (and, if that is not enough, both gains softened) until it sits on the limit.
    """
    rate_limit = q_des_previous is not None
    safe, bits = _bound_command_kernel(
        np.asarray(command, dtype=float),
        np.asarray(q, dtype=float),
        np.asarray(qd, dtype=float),
        limits.q_lower,
        limits.q_upper,
        limits.qd_max,
        limits.effort,
        limits.kp_max,
        limits.kd_max,
        limits.max_target_step,
        np.asarray(q_des_previous, dtype=float) if rate_limit else _NO_PREVIOUS,
        rate_limit,
    )
    return safe, {name for k, name in enumerate(_BOUND_FLAGS) if bits >> k & 1}


_NO_PREVIOUS = np.zeros(12)


def robot_status_size(num_status_channels: int) -> int:
    """The size of Go1SafetyFilter's robot_status input for `num_status_channels` watched channels."""
    return 24 + num_status_channels + 1


def robot_status_vector(q: np.ndarray, qd: np.ndarray, silence: np.ndarray, remote_estop: float) -> np.ndarray:
    """Go1SafetyFilter's robot_status input: [q (12) [rad], qd (12) [rad/s], silence (n) [s], remote E-stop]."""
    return np.concatenate([np.asarray(q, float), np.asarray(qd, float), np.asarray(silence, float), [remote_estop]])


def command_timeout(config: Go1SafetyConfig, elapsed: float) -> float:
    """The loop-silence limit [s] after `elapsed` [s] of the loop (longer while it warms up)."""
    return config.warmup_command_timeout if elapsed < config.warmup_duration else config.command_timeout


@kernel
def _soft_start_kernel(command, q_start, fraction):
    """The command with targets blended from q_start [rad]: fraction 0 holds q_start, 1 passes through.

    Velocity target and feed-forward torque are scaled by the fraction; gains are unchanged,
    so at fraction 0 the motors hold the measured pose with the controller's stiffness.
    """
    out = command.copy()
    for j in range(12):
        out[j] = q_start[j] + fraction * (command[j] - q_start[j])
        out[12 + j] = fraction * command[12 + j]
        out[48 + j] = fraction * command[48 + j]
    return out


@kernel
def _smooth_fraction_kernel(elapsed, duration):
    """Quintic 0 -> 1 over `duration` [s] with zero slope at both ends (1 when duration <= 0): the
    minimum-jerk blend s = 10 tau^3 - 15 tau^4 + 6 tau^5 of trajectory.min_jerk."""
    if duration <= 0.0:
        return 1.0
    tau = elapsed / duration
    if tau <= 0.0:
        return 0.0
    if tau >= 1.0:
        return 1.0
    # Products, not **: compiled and interpreted then agree to the bit (numba's pow does not
    # always round as the C library's).
    return tau * tau * tau * (10.0 - 15.0 * tau + 6.0 * (tau * tau))


@kernel
def _should_log(count):
    """First occurrence, then every power of ten: counted always, logged without flooding at 500 Hz."""
    if count < 1.0:
        return False
    exponent = math.log10(count)
    return exponent == math.floor(exponent)


# The filter's discrete state: the published command (60, its own group: the `command` output
# reads it directly), and its memory:
_LATCH = 0  # 1 + index of the latching intervention, 0 when not latched
_COUNTERS = 1  # len(INTERVENTIONS) counters, one per kind
_Q_START = 1 + len(INTERVENTIONS)  # measured pose at the first tick (12) [rad]
_T_START = _Q_START + 12  # context time of the first tick [s]
_STARTED = _T_START + 1  # 1 after the first tick
_LAST_WALL = _T_START + 2  # wall clock of the previous tick [s]
_MEMORY_SIZE = _T_START + 3
_STATUS_SIZE = 1 + len(INTERVENTIONS)  # the `status` output: [latch, counters], the memory's start

# Intervention indices the compiled tick sets (numba reads module constants at compile time).
_I = INTERVENTION_INDEX
_LATCHING_INDICES = tuple(_I[name] for name in LATCHING)
_BOUND_FLAG_INDICES = tuple(_I[name] for name in _BOUND_FLAGS)
_NONFINITE_COMMAND, _NONFINITE_STATUS = _I["nonfinite_command"], _I["nonfinite_status"]
_SOFT_START, _DAMPING = _I["soft_start"], _I["damping"]
_STATUS_TIMEOUT, _CONTROLLER_SILENCE = _I["status_timeout"], _I["controller_silence"]
_ESTOP_PORT, _ESTOP_REMOTE = _I["estop_port"], _I["estop_remote"]


# The filter's settings as its compiled tick takes them (one array: each argument of a compiled
# call costs a type check), by index.
_KP_MAX, _KD_MAX, _MAX_TARGET_STEP, _DAMPING_KD = 0, 1, 2, 3
_STATUS_TIMEOUT_S, _COMMAND_TIMEOUT_S, _WARMUP_COMMAND_TIMEOUT_S, _WARMUP_DURATION_S = 4, 5, 6, 7
_SOFT_START_DURATION_S = 8


def _settings_vector(config: Go1SafetyConfig, limits: SafetyLimits) -> np.ndarray:
    settings = np.empty(9)
    settings[_KP_MAX], settings[_KD_MAX] = limits.kp_max, limits.kd_max
    settings[_MAX_TARGET_STEP], settings[_DAMPING_KD] = limits.max_target_step, config.damping_kd
    settings[_STATUS_TIMEOUT_S], settings[_COMMAND_TIMEOUT_S] = config.status_timeout, config.command_timeout
    settings[_WARMUP_COMMAND_TIMEOUT_S] = config.warmup_command_timeout
    settings[_WARMUP_DURATION_S] = config.warmup_duration
    settings[_SOFT_START_DURATION_S] = config.soft_start_duration
    return settings


@kernel
def _filter_step_kernel(published, memory, command, robot_status, estop, now, t, bounds, settings):
    """One tick of `Go1SafetyFilter` on its state, in place: (bits of the interventions to log,
    index of the intervention that latched damping in this tick or -1).

    published (60): the last published command, overwritten by this tick's; memory: the filter's
    memory (layout above). Inputs: the controller's command (60), the filter's robot_status
    ([q (12) [rad], qd (12) [rad/s], silence of each status channel [s], remote E-stop]), estop
    (1; > 0.5 latches), the wall clock `now` [s] and the context time `t` [s]; `bounds` (4, 12):
    SafetyLimits' q_lower, q_upper, qd_max and effort; `settings`: by the indices above.
    """
    q_lower, q_upper, qd_max, effort = bounds[0], bounds[1], bounds[2], bounds[3]
    kd_max = settings[_KD_MAX]
    q, qd = robot_status[0:12], robot_status[12:24]
    num_channels = robot_status.shape[0] - 25
    fired = 0
    status_ok = True
    for j in range(12):
        if not (math.isfinite(q[j]) and math.isfinite(qd[j])):
            status_ok = False
    if memory[_STARTED] == 0.0:
        q_start = _clip_position_kernel(q, q_lower, q_upper)
        memory[_Q_START : _Q_START + 12] = q_start
        memory[_T_START] = t
        published[:] = 0.0
        published[0:12] = q_start
        memory[_STARTED] = 1.0
    else:
        # The loop-silence limit (longer while the loop warms up), as `command_timeout`.
        warming_up = t - memory[_T_START] < settings[_WARMUP_DURATION_S]
        limit = settings[_WARMUP_COMMAND_TIMEOUT_S] if warming_up else settings[_COMMAND_TIMEOUT_S]
        if now - memory[_LAST_WALL] > limit:
            fired |= 1 << _CONTROLLER_SILENCE
    memory[_LAST_WALL] = now

    # The link's judgement (its last look at the socket), not `now - receipt`: a late tick does
    # not make the robot look silent, and the robot's real silence trips within status_timeout +
    # one look.
    for i in range(num_channels):
        if not robot_status[24 + i] <= settings[_STATUS_TIMEOUT_S]:  # NaN counts as silent
            fired |= 1 << _STATUS_TIMEOUT
    if estop[0] > 0.5:
        fired |= 1 << _ESTOP_PORT
    if robot_status[24 + num_channels] > 0.5:
        fired |= 1 << _ESTOP_REMOTE
    latched = -1
    if memory[_LATCH] == 0.0:
        for k in range(len(_LATCHING_INDICES)):
            if fired >> _LATCHING_INDICES[k] & 1:
                latched = _LATCHING_INDICES[k]
                memory[_LATCH] = 1 + latched
                break

    q_des_previous = published[0:12].copy()
    if not status_ok:
        fired |= 1 << _NONFINITE_STATUS
    command_ok = True
    for i in range(60):
        if not math.isfinite(command[i]):
            command_ok = False
    if not command_ok:
        fired |= 1 << _NONFINITE_COMMAND
    if memory[_LATCH] != 0.0 or not status_ok or not command_ok:
        fired |= 1 << _DAMPING
        safe = _damping_kernel(q_des_previous, qd, q_lower, q_upper, effort, kd_max, settings[_DAMPING_KD])
    else:
        elapsed = t - memory[_T_START]
        if elapsed < settings[_SOFT_START_DURATION_S]:
            fired |= 1 << _SOFT_START
            fraction = _smooth_fraction_kernel(elapsed, settings[_SOFT_START_DURATION_S])
            command = _soft_start_kernel(command, memory[_Q_START : _Q_START + 12], fraction)
        safe, bits = _bound_command_kernel(
            command,
            q,
            qd,
            q_lower,
            q_upper,
            qd_max,
            effort,
            settings[_KP_MAX],
            kd_max,
            settings[_MAX_TARGET_STEP],
            q_des_previous,
            True,
        )
        for k in range(len(_BOUND_FLAG_INDICES)):
            if bits >> k & 1:
                fired |= 1 << _BOUND_FLAG_INDICES[k]
    published[:] = safe
    log = 0
    for i in range(len(INTERVENTIONS)):
        if fired >> i & 1:
            memory[_COUNTERS + i] += 1.0
            if i != _SOFT_START and i != _DAMPING and _should_log(memory[_COUNTERS + i]):
                log |= 1 << i
    return log, latched


class Go1SafetyFilter(LeafSystemWithoutWitnesses):
    """command (60) + the robot's status + E-stop -> safe command (60).

    Inputs:
      command (60): the controller's `go1.command`.
      robot_status (24 + n + 1): what the filter reads from the robot, in one vector (one port
        evaluation a tick): [q (12) [rad], qd (12) [rad/s] (leg_control_data), silence (n): how
        long each status channel has been silent [s], judged by the link's looks
        (Go1Link.silence; the watchdog trips on the longest), remote E-stop (1): > 0.5 latches
        damping (the remote's button)].
      estop (1, optional): > 0.5 latches damping.
    Outputs:
      command (60): the bounded command, from the state (what the sender publishes).
      status (1 + len(INTERVENTIONS)): [latched reason (0 none, else 1 + index in INTERVENTIONS),
        counters of every intervention kind].
    """

    def __init__(
        self,
        config: Go1SafetyConfig,
        *,
        num_status_channels: int = 2,
        clock: Callable[[], float] = time.monotonic,
    ):
        super().__init__()
        self._config = config
        self._limits = SafetyLimits.from_config(config)
        # The wall clock is a dependency (injectable for tests), not state.
        self._clock = clock
        self._command = self.DeclareVectorInputPort("command", COMMAND_SIZE)
        self._robot_status = self.DeclareVectorInputPort("robot_status", robot_status_size(num_status_channels))
        self._estop = self.DeclareVectorInputPort("estop", 1)
        self._no_estop = np.zeros(1)
        limits = self._limits
        self._bounds = np.array([limits.q_lower, limits.q_upper, limits.qd_max, limits.effort])
        self._settings = _settings_vector(config, limits)
        initial = damping_command(robot.STANDING_Q, np.zeros(12), limits, config.damping_kd)
        self._published = self.DeclareDiscreteState(initial)
        self._memory = self.DeclareDiscreteState(_MEMORY_SIZE)
        # Compiled here (or loaded from numba's cache), not in the first control tick.
        bound_command(initial, robot.STANDING_Q, np.zeros(12), limits, robot.STANDING_Q)
        robot_status = robot_status_vector(robot.STANDING_Q, np.zeros(12), np.zeros(num_status_channels), 0.0)
        memory = np.zeros(_MEMORY_SIZE)
        for command in (initial, np.full(COMMAND_SIZE, np.nan)):
            _filter_step_kernel(
                initial.copy(), memory, command, robot_status, self._no_estop, 0.0, 0.0, self._bounds, self._settings
            )
        # After the controller's update of the same tick, and unrestricted so that the sender's
        # discrete update at the same instant reads the command bounded here (see COMMAND_OFFSET).
        self.DeclarePeriodicUnrestrictedUpdateEvent(config.period, COMMAND_OFFSET, self._update)
        self.DeclareStateOutputPort("command", self._published)
        self.DeclareVectorOutputPort("status", _STATUS_SIZE, self._calc_status, {self.xd_ticket()})

    @property
    def limits(self) -> SafetyLimits:
        return self._limits

    def _update(self, context, state: State) -> None:
        discrete_state = state.get_mutable_discrete_state()
        estop = self._estop
        log, latched = _filter_step_kernel(
            discrete_state.get_mutable_value(self._published),
            discrete_state.get_mutable_value(self._memory),
            self._command.Eval(context),
            self._robot_status.Eval(context),
            estop.Eval(context) if estop.HasValue(context) else self._no_estop,
            self._clock(),
            context.get_time(),
            self._bounds,
            self._settings,
        )
        if log or latched >= 0:
            self._log_interventions(discrete_state.get_value(self._memory), log, latched, context.get_time())

    @staticmethod
    def _log_interventions(memory: np.ndarray, log: int, latched: int, t: float) -> None:
        if latched >= 0:
            _log.error("Go1 driver: %s, damping latched", INTERVENTIONS[latched])
        for i, name in enumerate(INTERVENTIONS):
            if log >> i & 1:
                count = memory[_COUNTERS + i]
                _log.warning("Go1 driver safety: %s (count %d) at t = %.3f s", name, count, t)

    def _calc_status(self, context, output: BasicVector) -> None:
        output.SetFromVector(context.get_discrete_state(self._memory).get_value()[:_STATUS_SIZE])
