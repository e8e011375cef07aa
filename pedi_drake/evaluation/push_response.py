"""How the simulated robot withstood the pushes of a run (paper 003's push recovery, Figs. 5-6).

From simulation ground truth only (the logged plant state, the torques the motors applied, the
true foot contact forces, the applied push), for judging: no controller reads any of it.

Per push, over its window (from its start until it has ramped back to zero):

* the slide of each stance foot (on the ground at the push's start): the largest horizontal
  distance of its centre from where it stood then (`mission_results.foot_slides`);
* the trunk's displacement: the largest distance of the trunk origin from its position at the
  push's start;
* the knee (calf motor) torques: the peak |tau| per leg, and the mean while the push is at full
  force beside the mean just before it (what the push added);
* what the prongs carried at full force: the weight and the share of the push the feet did not.
"""

import dataclasses

import numpy as np

from pedi_drake import robot
from pedi_drake.evaluation.mission_results import FOOT_ON_GROUND, foot_positions_W, foot_slides
from pedi_drake.run_logs import SignalLog
from pedi_drake.scenario import Push
from pedi_drake.station.disturbance import push_force_W

# A stance foot that slides further than this under a push did not withstand it [m].
STANCE_FOOT_SLIDE_LIMIT = 0.01
# The knee torques "before the push" are the mean over this long before its start [s].
BEFORE_PUSH_WINDOW = 0.5
KNEES = [3 * i + 2 for i in range(4)]  # the calf motors in Unitree order


@dataclasses.dataclass
class PushResponse:
    """The robot's response to one push (ground truth; see the module docstring)."""

    force: float  # full force of the push [N]
    start: float  # [s]
    end: float  # [s] when it had ramped back to zero
    stance_legs: list[str]  # feet on the ground at the push's start
    foot_slide: dict[str, float]  # per stance foot [m]
    trunk_displacement: float  # [m]
    knee_torque_peak: dict[str, float]  # per leg, max |tau| over the window [N m]
    knee_torque_before: dict[str, float]  # per leg, mean tau before the push [N m]
    knee_torque_full_force: dict[str, float]  # per leg, mean tau at full force [N m]
    # Mean vertical load not carried by the feet at full force (the prongs', 0 without) [N] ...
    prong_load: float
    # ... and the share of the push's horizontal force the feet did not take [-].
    prong_share_of_push: float

    def max_foot_slide(self) -> tuple[str, float]:
        """(leg, slide [m]) of the stance foot that slid furthest."""
        leg = max(self.foot_slide, key=self.foot_slide.get)
        return leg, self.foot_slide[leg]

    def row(self) -> dict:
        """The entry of result.json's `pushes` (SI units in the key names)."""
        return {
            "force_N": self.force,
            "start_s": self.start,
            "end_s": self.end,
            "stance_legs": self.stance_legs,
            "foot_slide_m": self.foot_slide,
            "max_foot_slide_m": self.max_foot_slide()[1],
            "trunk_displacement_m": self.trunk_displacement,
            "knee_torque_peak_Nm": self.knee_torque_peak,
            "knee_torque_before_Nm": self.knee_torque_before,
            "knee_torque_full_force_Nm": self.knee_torque_full_force,
            "prong_load_N": self.prong_load,
            "prong_share_of_push": self.prong_share_of_push,
        }


@dataclasses.dataclass
class PushSeries:
    """One push's time series for plots: times from the push's start [s], trunk displacement along
    the push's direction [m], the applied force's magnitude [N], the knee torques (4, N) [N m]."""

    times: np.ndarray
    displacement: np.ndarray
    force: np.ndarray
    knee_torques: np.ndarray


def _window(times: np.ndarray, start: float, end: float) -> np.ndarray:
    return np.flatnonzero((times >= start) & (times <= end))


def _trunk_positions(plant, states: np.ndarray) -> np.ndarray:
    """Trunk origins (3, N) of logged plant states [m] (the floating base's position in q)."""
    q0 = robot.Go1PlantMap.from_plant(plant).base_q_start
    return states[q0 + 4 : q0 + 7]


def _per_leg(values: np.ndarray) -> dict[str, float]:
    return {leg: float(v) for leg, v in zip(robot.LEG_NAMES, values, strict=True)}


def push_response(plant, logs: dict[str, SignalLog], push: Push) -> PushResponse | None:
    """The response to `push` from a simulated run's logs, or None if the run ended before it began."""
    state_log, torque_log = logs["sim.plant_state"], logs["sim.motor_torque"]
    window = _window(state_log.times, push.start, push.end())
    if not len(window):
        return None
    feet_W = foot_positions_W(plant, state_log.data, window)
    stance = [i for i in range(4) if feet_W[0, i, 2] < robot.FOOT_RADIUS + FOOT_ON_GROUND]
    slides = foot_slides(feet_W)
    p_WB = _trunk_positions(plant, state_log.data[:, window])
    displacement = float(np.max(np.linalg.norm(p_WB - p_WB[:, :1], axis=0)))

    full_start, full_end = push.start + push.ramp, push.start + push.ramp + push.duration
    torques = torque_log.data[KNEES]
    in_window = _window(torque_log.times, push.start, push.end())
    before = _window(torque_log.times, push.start - BEFORE_PUSH_WINDOW, push.start)
    full = _window(torque_log.times, full_start, full_end)
    mean_before = torques[:, before].mean(axis=1) if len(before) else np.full(4, np.nan)
    mean_full = torques[:, full].mean(axis=1) if len(full) else np.full(4, np.nan)

    contact = logs["sim.foot_contact_forces"]
    at_full = _window(contact.times, full_start, full_end)
    model = plant.GetBodyByName(robot.TRUNK_BODY_NAME).model_instance()
    weight = plant.CalcTotalMass(plant.CreateDefaultContext(), [model]) * robot.GRAVITY
    if len(at_full):
        feet_force = contact.data[:, at_full].reshape(4, 3, -1).sum(axis=0).mean(axis=1)  # on the feet [N]
        direction = np.asarray(push.direction, float) / np.linalg.norm(push.direction)
        horizontal = np.array([direction[0], direction[1], 0.0])
        # Quasi-static: push + feet + prongs + weight = 0, so the prongs take what the feet do not.
        prong_load = float(weight - feet_force[2])
        share = float(1.0 + feet_force @ horizontal / push.force) if push.force > 0 else 0.0
    else:
        prong_load = share = float("nan")
    return PushResponse(
        force=push.force,
        start=push.start,
        end=push.end(),
        stance_legs=[robot.LEG_NAMES[i] for i in stance],
        foot_slide={robot.LEG_NAMES[i]: slides[robot.LEG_NAMES[i]] for i in stance},
        trunk_displacement=displacement,
        knee_torque_peak=_per_leg(np.max(np.abs(torques[:, in_window]), axis=1)),
        knee_torque_before=_per_leg(mean_before),
        knee_torque_full_force=_per_leg(mean_full),
        prong_load=prong_load,
        prong_share_of_push=share,
    )


def push_series(plant, logs: dict[str, SignalLog], push: Push, margin: float = 1.0) -> PushSeries:
    """`push`'s time series from `margin` [s] before its start to `margin` after its end."""
    state_log, torque_log = logs["sim.plant_state"], logs["sim.motor_torque"]
    window = _window(state_log.times, push.start - margin, push.end() + margin)
    times = state_log.times[window]
    p_WB = _trunk_positions(plant, state_log.data[:, window])
    start = int(np.searchsorted(times, push.start))
    direction = np.asarray(push.direction, float) / np.linalg.norm(push.direction)
    displacement = direction @ (p_WB - p_WB[:, min(start, len(times) - 1), None])
    force = np.array([np.linalg.norm(push_force_W(push, t)) for t in times])
    torque_index = np.clip(np.searchsorted(torque_log.times, times), 0, len(torque_log.times) - 1)
    return PushSeries(times - push.start, displacement, force, torque_log.data[KNEES][:, torque_index])
