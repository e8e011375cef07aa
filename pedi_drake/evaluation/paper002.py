"""Paper 002's evaluations judged from a finished run: IV-A (the lifted foot's pose against the
pose it held when the torso started to move, and the torso's circle tracking, Figs. 3 to 5) and
the foot force estimates against the simulated contact force during press phases.

Everything here reads simulation ground truth (the logged plant state and foot contact forces)
and is for evaluation only; the controllers read the state estimate and go1.* signals.
"""

import dataclasses

import numpy as np

from pedi_drake import robot
from pedi_drake.control.projected_impedance_controller import projected_diagnostics_layout
from pedi_drake.estimation.base_state import BaseState
from pedi_drake.mission.robot_view import RobotView
from pedi_drake.mission.spec import MissionSpec
from pedi_drake.run_logs import SignalLog
from pedi_drake.vector3 import orientation_error_W

# Acceptance floors of the IV-A evaluation (foot held within them while the torso circles).
FOOT_POSITION_FLOOR_M = 0.005
FOOT_ORIENTATION_FLOOR_RAD = np.radians(2.0)
TORSO_TRACKING_RMS_FLOOR_M = 0.01


@dataclasses.dataclass
class FootHoldEvaluation:
    """IV-A figures over the torso-motion phase (ground truth)."""

    times: np.ndarray  # (N,) [s]
    trunk: np.ndarray  # (N, 3) trunk origin [m]
    trunk_reference: np.ndarray  # (N, 3) its reference [m]
    foot: np.ndarray  # (N, 3) held foot centre [m]
    foot_error: np.ndarray  # (N, 3) foot minus its pose at the phase start [m]
    orientation_error: np.ndarray  # (N, 3) calf rotation from its start, world x (roll), y (pitch), z (yaw) [rad]

    @property
    def foot_position_error_max_m(self) -> float:
        return float(np.max(np.linalg.norm(self.foot_error, axis=1)))

    @property
    def foot_orientation_error_max_rad(self) -> float:
        """Largest roll or pitch error (the yaw is not held)."""
        return float(np.max(np.abs(self.orientation_error[:, :2])))

    @property
    def foot_yaw_error_max_rad(self) -> float:
        return float(np.max(np.abs(self.orientation_error[:, 2])))

    @property
    def torso_tracking_rms_m(self) -> float:
        return float(np.sqrt(np.mean(np.sum((self.trunk - self.trunk_reference) ** 2, axis=1))))

    @property
    def torso_reference_span_m(self) -> float:
        """The smaller of the torso reference's x and y extents (a circle's diameter) [m]."""
        xy = self.trunk_reference[:, :2]
        return float(np.min(xy.max(axis=0) - xy.min(axis=0)))

    def summary(self) -> dict:
        return {
            "foot_position_error_max_m": self.foot_position_error_max_m,
            "foot_orientation_error_max_deg": float(np.degrees(self.foot_orientation_error_max_rad)),
            "foot_yaw_error_max_deg": float(np.degrees(self.foot_yaw_error_max_rad)),
            "torso_tracking_rms_m": self.torso_tracking_rms_m,
            "torso_reference_span_m": self.torso_reference_span_m,
        }


def evaluate_foot_hold(
    plant, logs: dict[str, SignalLog], t_start: float, t_end: float, leg: str = "FL"
) -> FootHoldEvaluation:
    """IV-A figures of `leg` between t_start and t_end [s] from a run's logs (`plant`: the
    simulation's plant, for its state layout)."""
    states = logs["sim.plant_state"]
    body = logs["mission.body_reference"]
    context = plant.CreateDefaultContext()
    foot_body = plant.GetBodyByName(f"{leg}_foot")
    calf_body = plant.GetBodyByName(f"{leg}_calf")
    trunk_body = plant.GetBodyByName(robot.TRUNK_BODY_NAME)
    keep = (states.times >= t_start) & (states.times <= t_end)
    times = states.times[keep]
    nq = plant.num_positions()
    trunk, foot, rotations = [], [], []
    for x in states.data[:, keep].T:
        plant.SetPositions(context, x[:nq])
        trunk.append(plant.EvalBodyPoseInWorld(context, trunk_body).translation())
        foot.append(plant.EvalBodyPoseInWorld(context, foot_body).translation())
        rotations.append(plant.EvalBodyPoseInWorld(context, calf_body).rotation().matrix())
    trunk, foot = np.array(trunk), np.array(foot)
    index = np.clip(np.searchsorted(body.times, times), 0, len(body.times) - 1)
    reference = body.data[0:3, index].T
    R0 = rotations[0]
    # The calf's rotation since the start, as a world rotation vector: x roll, y pitch, z yaw.
    orientation = np.array([orientation_error_W(R, R0) for R in rotations])
    return FootHoldEvaluation(times, trunk, reference, foot, foot - foot[0], orientation)


def press_force_errors(logs: dict[str, SignalLog], phases: list[dict], leg: str = "FR") -> dict:
    """The foot force estimates against the simulated contact force on the foot during every
    press phase: RMS of |estimate - true| [N] per estimate ("joint_torque" always, "impedance"
    when the controller's diagnostics carry it), over all press samples pooled.

    The joint-torque estimate is recomputed from the logged go1.* signals and the state estimate
    exactly as the mission computes it (RobotView.foot_external_force_W); the impedance estimate
    is the controller's `force_estimate` diagnostic. Neither has its press-start bias removed.
    """
    true = logs["sim.foot_contact_forces"]
    k = robot.LEG_NAMES.index(leg)
    windows = [(p["t_start"], p["t_end"]) for p in phases if p["kind"] == "press" and p["t_end"] is not None]
    keep = np.zeros(len(true.times), dtype=bool)
    for t0, t1 in windows:
        keep |= (true.times >= t0) & (true.times <= t1)
    times = true.times[keep]
    F_true = true.data[3 * k : 3 * k + 3, keep].T

    def at(log: SignalLog) -> np.ndarray:
        return np.clip(np.searchsorted(log.times, times), 0, len(log.times) - 1)

    base, q, tau = logs["base_state"], logs["go1.position_measured"], logs["go1.torque_estimated"]
    ib, iq, it = at(base), at(q), at(tau)
    joint = []
    for a, b, c in zip(ib, iq, it, strict=True):
        view = RobotView(
            time=0.0,
            base=BaseState.from_vector(base.data[:, a]),
            q=q.data[:, b],
            qd=np.zeros(12),
            tau=tau.data[:, c],
            foot_force=np.zeros(4),
        )
        joint.append(view.foot_external_force_W(leg))
    estimates = {"joint_torque": np.array(joint).reshape(-1, 3)}
    diagnostics = logs.get("controller.diagnostics")
    if diagnostics is not None:
        num_contacts = _num_contacts_of(diagnostics.data.shape[0])
        if num_contacts is not None:
            where = projected_diagnostics_layout(num_contacts)["force_estimate"]
            estimates["impedance"] = diagnostics.data[where, :][3 * k : 3 * k + 3, at(diagnostics)].T
    rms = {
        source: float(np.sqrt(np.mean(np.sum((F - F_true) ** 2, axis=1)))) if len(times) else float("nan")
        for source, F in estimates.items()
    }
    return {"samples": int(len(times)), "rms_n": rms, "true_force_max_n": float(np.max(np.linalg.norm(F_true, axis=1)))}


def _num_contacts_of(diagnostics_size: int) -> int | None:
    """The contact count whose projected-impedance diagnostics have this size (None: another controller)."""
    for num_contacts in range(4, 12):
        if projected_diagnostics_layout(num_contacts)["constraint_rank"].stop == diagnostics_size:
            return num_contacts
    return None


def phase_window(spec: MissionSpec, phases: list[dict], kind: str, pivoted: bool = False) -> tuple[float, float] | None:
    """(start, end) [s] from the first to the last finished phase of `kind` in a run's `phases`
    (result.json rows); with `pivoted`, only body_rotate phases that turn about a prong (the
    mission `spec` says which). None when there is none."""
    names = {p.name for p in spec.phases if not pivoted or getattr(p, "pivot", "")}
    rows = [p for p in phases if p["kind"] == kind and p["name"] in names and p["t_end"] is not None]
    if not rows:
        return None
    return rows[0]["t_start"], rows[-1]["t_end"]


def pivot_prong(spec: MissionSpec) -> str:
    """The prong the mission's body_rotate phases turn about ("" when none does)."""
    return next((p.pivot for p in spec.phases if getattr(p, "pivot", "")), "")


@dataclasses.dataclass
class PivotEvaluation:
    """IV-B figures over the rotations about a prong (ground truth)."""

    rotation_reached_rad: dict  # {"roll" | "pitch" | "yaw": (most negative, most positive)} from the start attitude
    front_feet_drift_max_m: float  # largest displacement of FR or FL from where they were held
    pivot_slip_max_m: float  # largest horizontal displacement of the pivot prong's tip
    times: np.ndarray  # (N,) [s]
    rotation: np.ndarray  # (N, 3) trunk rotation from its start attitude, world x, y, z [rad]
    front_feet_displacement: np.ndarray  # (N, 2, 3) FR and FL from where they were held [m]

    def summary(self) -> dict:
        return {
            "rotation_reached_deg": {
                axis: [float(np.degrees(lo)), float(np.degrees(hi))]
                for axis, (lo, hi) in self.rotation_reached_rad.items()
            },
            "rotation_reached_min_deg": float(
                np.degrees(min(min(-lo, hi) for lo, hi in self.rotation_reached_rad.values()))
            ),
            "front_feet_drift_max_m": self.front_feet_drift_max_m,
            "pivot_slip_max_m": self.pivot_slip_max_m,
        }


def evaluate_pivot_rotations(
    plant, logs: dict[str, SignalLog], t_start: float, t_end: float, pivot: str, tip_offset: np.ndarray
) -> PivotEvaluation:
    """IV-B figures between t_start and t_end [s] (the rotation phases about prong `pivot`).

    The rotation is the trunk's attitude relative to the start (see the comment below);
    `tip_offset` is the tip's centre in the prong body's frame [m] (0, 0, -length)."""
    states = logs["sim.plant_state"]
    keep = (states.times >= t_start) & (states.times <= t_end)
    context = plant.CreateDefaultContext()
    trunk_body = plant.GetBodyByName(robot.TRUNK_BODY_NAME)
    feet = [plant.GetBodyByName(f"{leg}_foot") for leg in ("FR", "FL")]
    prong = plant.GetBodyByName(pivot)
    nq = plant.num_positions()
    rotations, foot_positions, tips = [], [], []
    for x in states.data[:, keep].T:
        plant.SetPositions(context, x[:nq])
        rotations.append(plant.EvalBodyPoseInWorld(context, trunk_body).rotation().matrix())
        foot_positions.append([plant.EvalBodyPoseInWorld(context, foot).translation() for foot in feet])
        tips.append(plant.EvalBodyPoseInWorld(context, prong) @ np.asarray(tip_offset, float))
    R0 = rotations[0]
    # Each sample's rotation from the start attitude (world rotation vector), its angle credited
    # to the axis it is mostly about, with its sign: rotations about axes tilted by the trunk's
    # start pitch still count in full.
    relative = np.array([orientation_error_W(R, R0) for R in rotations])
    angle = np.linalg.norm(relative, axis=1)
    dominant = np.argmax(np.abs(relative), axis=1)
    signed = angle * np.sign(relative[np.arange(len(relative)), dominant])
    reached = {}
    for k, axis in enumerate(("roll", "pitch", "yaw")):
        mine = signed[dominant == k]
        reached[axis] = (float(min(mine.min(), 0.0)), float(max(mine.max(), 0.0))) if len(mine) else (0.0, 0.0)
    foot_positions = np.array(foot_positions)
    displacement = foot_positions - foot_positions[0]
    drift = float(np.max(np.linalg.norm(displacement, axis=2)))
    tips = np.array(tips)
    slip = float(np.max(np.linalg.norm(tips[:, :2] - tips[0, :2], axis=1)))
    return PivotEvaluation(reached, drift, slip, states.times[keep], relative, displacement)


@dataclasses.dataclass
class FootPushResponse:
    """A known push on a lifted, held foot: its steady displacement and the force estimate's error."""

    stiffness_n_per_m: float  # push force / steady displacement along the push
    force_estimate_rms_n: float  # RMS |Eq. 11 estimate - applied force| over the steady push (nan without one)


def foot_push_response(
    plant, logs: dict[str, SignalLog], push, leg: str = "FR", settle: float = 1.0, before: float = 0.4
) -> FootPushResponse:
    """The response of the foot of `leg` to `push` (a `pedi_drake.scenario.Push` on it): the foot's
    mean position over the last `before` [s] before the push against its mean over the full-force
    window (from `settle` [s] after the ramp), both from ground truth; and the controller's Eq. 11
    estimate (the `force_estimate` diagnostic, when there is one) against the logged push force."""
    states = logs["sim.plant_state"]
    foot = plant.GetBodyByName(f"{leg}_foot")
    context = plant.CreateDefaultContext()
    nq = plant.num_positions()
    full_start, full_end = push.start + push.ramp, push.start + push.ramp + push.duration
    quiet = (states.times >= push.start - before) & (states.times < push.start)
    steady = (states.times >= full_start + settle) & (states.times <= full_end)

    def mean_foot(mask: np.ndarray) -> np.ndarray:
        points = []
        for x in states.data[:, mask].T:
            plant.SetPositions(context, x[:nq])
            points.append(plant.EvalBodyPoseInWorld(context, foot).translation())
        return np.mean(points, axis=0)

    direction = np.asarray(push.direction, float) / np.linalg.norm(push.direction)
    moved = float((mean_foot(steady) - mean_foot(quiet)) @ direction)
    stiffness = push.force / moved if moved > 0 else float("inf")
    rms = float("nan")
    diagnostics = logs.get("controller.diagnostics")
    num_contacts = _num_contacts_of(diagnostics.data.shape[0]) if diagnostics is not None else None
    if num_contacts is not None:
        k = robot.LEG_NAMES.index(leg)
        where = projected_diagnostics_layout(num_contacts)["force_estimate"]
        window = (diagnostics.times >= full_start + settle) & (diagnostics.times <= full_end)
        estimate = diagnostics.data[where, :][3 * k : 3 * k + 3, window].T
        applied = logs["sim.push_force"]
        index = np.clip(np.searchsorted(applied.times, diagnostics.times[window]), 0, len(applied.times) - 1)
        rms = float(np.sqrt(np.mean(np.sum((estimate - applied.data[:, index].T) ** 2, axis=1))))
    return FootPushResponse(stiffness, rms)
