"""The Go1 driver's safety layer: every command is bounded here before it is published.

Plain functions (`bound_command`, `damping_command`) hold the maths; `Go1SafetyFilter` is the
LeafSystem that applies them at the control rate with its watchdogs, soft start and latched
E-stop, keeping everything that changes (last published command, soft-start pose, latch,
intervention counters) in the Context's discrete state.

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
from pydrake.systems.framework import BasicVector, DiscreteValues, LeafSystem

from pedi_drake import robot
from pedi_drake.go1_command import COMMAND_SIZE, pack_command, split_command
from pedi_drake.go1_driver.config import Go1SafetyConfig
from pedi_drake.go1_driver.constants import STATUS_CHANNELS
from pedi_drake.jit import kernel
from pedi_drake.trajectory import min_jerk

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
        middle = 0.5 * (self.q_lower + self.q_upper)
        return np.clip(np.where(np.isfinite(q), q, middle), self.q_lower, self.q_upper)


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
    qd = np.where(np.isfinite(qd), qd, 0.0)
    kd_vec = np.full(12, min(max(kd, 1e-3), limits.kd_max))
    torque = kd_vec * np.abs(qd)
    bound = limits.effort * _EFFORT_MARGIN
    kd_vec = np.where(torque > bound, bound / np.maximum(np.abs(qd), 1e-300), kd_vec)
    return pack_command(limits.clip_position(q_hold), 0.0, 0.0, kd_vec, 0.0)


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


def command_timeout(config: Go1SafetyConfig, elapsed: float) -> float:
    """The loop-silence limit [s] after `elapsed` [s] of the loop (longer while it warms up)."""
    return config.warmup_command_timeout if elapsed < config.warmup_duration else config.command_timeout


def soft_start_blend(command: np.ndarray, q_start: np.ndarray, fraction: float) -> np.ndarray:
    """The command with targets blended from q_start [rad]: fraction 0 holds q_start, 1 passes through.

    Velocity target and feed-forward torque are scaled by the fraction; gains are unchanged,
    so at fraction 0 the motors hold the measured pose with the controller's stiffness.
    """
    q_des, qd_des, kp, kd, tau_ff = split_command(command)
    return pack_command(q_start + fraction * (q_des - q_start), fraction * qd_des, kp, kd, fraction * tau_ff)


def smooth_fraction(elapsed: float, duration: float) -> float:
    """Quintic 0 -> 1 over `duration` [s] with zero slope at both ends (1 when duration <= 0)."""
    if duration <= 0.0:
        return 1.0
    return min_jerk(elapsed / duration)[0]


# Discrete state layout of Go1SafetyFilter.
_CMD = slice(0, COMMAND_SIZE)  # last published command
_Q_START = slice(60, 72)  # measured pose at the first tick [rad]
_T_START = 72  # context time of the first tick [s]
_STARTED = 73  # 1 after the first tick
_LATCH = 74  # 1 + index of the latching intervention, 0 when not latched
_LAST_WALL = 75  # wall clock of the previous tick [s]
_COUNTERS = slice(76, 76 + len(INTERVENTIONS))
_STATE_SIZE = 76 + len(INTERVENTIONS)


def _should_log(count: float) -> bool:
    # First occurrence, then every power of ten: counted always, logged without flooding at 500 Hz.
    return count >= 1 and math.log10(count).is_integer()


class Go1SafetyFilter(LeafSystem):
    """command (60) + measured state + status receipt times + E-stops -> safe command (60).

    Inputs:
      command (60): the controller's `go1.command`.
      position_measured (12) [rad], velocity_measured (12) [rad/s]: from leg_control_data.
      status_silence (n): how long each status channel has been silent [s], judged by the receive
        thread's clock (Go1Link.silence); the watchdog trips on the longest.
      estop (1, optional): > 0.5 latches damping.
      rc_estop (1, optional): > 0.5 latches damping (the remote's button).
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
        self._q = self.DeclareVectorInputPort("position_measured", 12)
        self._qd = self.DeclareVectorInputPort("velocity_measured", 12)
        self._status_silence = self.DeclareVectorInputPort("status_silence", num_status_channels)
        self._estop = self.DeclareVectorInputPort("estop", 1)
        self._rc_estop = self.DeclareVectorInputPort("rc_estop", 1)
        initial = np.zeros(_STATE_SIZE)
        initial[_CMD] = damping_command(robot.STANDING_Q, np.zeros(12), self._limits, config.damping_kd)
        self._state = self.DeclareDiscreteState(initial)
        # Compiled here (or loaded from numba's cache), not in the first control tick.
        bound_command(initial[_CMD], robot.STANDING_Q, np.zeros(12), self._limits, robot.STANDING_Q)
        self.DeclarePeriodicDiscreteUpdateEvent(config.period, 0.0, self._update)
        self.DeclareVectorOutputPort("command", COMMAND_SIZE, self._calc_command, {self.xd_ticket()})
        self.DeclareVectorOutputPort("status", 1 + len(INTERVENTIONS), self._calc_status, {self.xd_ticket()})

    @property
    def limits(self) -> SafetyLimits:
        return self._limits

    def _flag(self, port, context) -> bool:
        return port.HasValue(context) and bool(port.Eval(context)[0] > 0.5)

    def _update(self, context, discrete_state: DiscreteValues) -> None:
        config, limits = self._config, self._limits
        x = context.get_discrete_state(self._state).get_value().copy()
        now = self._clock()
        fired: set[str] = set()
        q, qd = self._q.Eval(context), self._qd.Eval(context)
        status_ok = bool(np.isfinite(q).all() and np.isfinite(qd).all())
        if x[_STARTED] == 0.0:
            x[_Q_START] = limits.clip_position(q)
            x[_T_START] = context.get_time()
            x[_CMD] = pack_command(x[_Q_START], 0.0, 0.0, 0.0, 0.0)
            x[_STARTED] = 1.0
        elif now - x[_LAST_WALL] > command_timeout(config, context.get_time() - x[_T_START]):
            fired.add("controller_silence")
        x[_LAST_WALL] = now

        # The receive thread's judgement, not `now - receipt`: a late tick does not make the robot
        # look silent, and the robot's real silence trips within status_timeout + one look.
        silence = self._status_silence.Eval(context)
        if not float(silence.max()) <= config.status_timeout:  # NaN counts as silent
            fired.add("status_timeout")
        if self._flag(self._estop, context):
            fired.add("estop_port")
        if self._flag(self._rc_estop, context):
            fired.add("estop_remote")
        if x[_LATCH] == 0.0:
            for name in LATCHING:
                if name in fired:
                    x[_LATCH] = 1 + INTERVENTION_INDEX[name]
                    _log.error("Go1 driver: %s, damping latched", name)
                    break

        command = self._command.Eval(context)
        q_des_previous = x[_CMD][0:12].copy()
        if not status_ok:
            fired.add("nonfinite_status")
        if not np.isfinite(command).all():
            fired.add("nonfinite_command")
        if x[_LATCH] != 0.0 or not status_ok or "nonfinite_command" in fired:
            fired.add("damping")
            safe = damping_command(q_des_previous, qd, limits, config.damping_kd)
        else:
            elapsed = context.get_time() - x[_T_START]
            if elapsed < config.soft_start_duration:
                fired.add("soft_start")
                command = soft_start_blend(command, x[_Q_START], smooth_fraction(elapsed, config.soft_start_duration))
            safe, flags = bound_command(command, q, qd, limits, q_des_previous)
            fired |= flags
        x[_CMD] = safe
        counters = x[_COUNTERS]
        for name in fired:
            i = INTERVENTION_INDEX[name]
            counters[i] += 1
            if name not in ("soft_start", "damping") and _should_log(counters[i]):
                _log.warning("Go1 driver safety: %s (count %d) at t = %.3f s", name, counters[i], context.get_time())
        x[_COUNTERS] = counters
        discrete_state.set_value(self._state, x)

    def _calc_command(self, context, output: BasicVector) -> None:
        output.SetFromVector(context.get_discrete_state(self._state).get_value()[_CMD])

    def _calc_status(self, context, output: BasicVector) -> None:
        x = context.get_discrete_state(self._state).get_value()
        output.SetFromVector(np.concatenate([[x[_LATCH]], x[_COUNTERS]]))
