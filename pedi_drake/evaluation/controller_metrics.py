"""How well the whole-body controller did in a simulated run, from the run's logs.

The controller benchmark and its tests read these figures (foot error over a hold, trunk drift,
stance-foot slip, torques, tick times, the response to a push). Positions, slip and torques come
from simulation ground truth (the logged plant state and motor torques), which no controller
reads; the prong load from the simulated foot sensors (the true contact normal forces, when
noise is off); tick times, QP failures and planned contact forces are the controller's own
diagnostics.

Which legs stand and when a leg manipulates come from the mission's logged status and leg
references, so the same figures hold for any mission, not one script.
"""

import dataclasses

import numpy as np

from pedi_drake import robot
from pedi_drake.control.references import LEG_BLOCK, LEG_MODE_NONE
from pedi_drake.control.whole_body_controller import diagnostics_layout
from pedi_drake.diagram import apply_mission
from pedi_drake.evaluation.push_response import push_response
from pedi_drake.exceptions import PediError
from pedi_drake.mission import spec
from pedi_drake.mission.progress import SUCCEEDED
from pedi_drake.run_logs import SignalLog

FORCE_JUMP_AFTER = 0.1  # [s] the contact forces settle from their zero initial guess before this
PRONG_LOAD_WINDOW = 0.5  # [s] the prong load is averaged over the run's last this long


@dataclasses.dataclass
class ControllerMetrics:
    """Figures of one run (positions from ground truth; see the module docstring)."""

    fell: bool  # the fall rule of pedi_drake.fall held at some sample
    mission_succeeded: bool
    sim_time: float  # [s]
    wall_time: float  # [s]
    real_time_factor: float
    # Per leg of every succeeded reach phase: max |foot - target| over the phase's hold [m].
    foot_errors: list[float]
    # Max |p_WB - p_WB_ref| while a leg manipulates and before any push [m].
    trunk_drift: float
    # Max horizontal displacement of a stance foot's centre while a leg manipulates [m]: an upper
    # bound of slip (it also counts the foot sphere rolling when the calf turns).
    stance_slip: float
    # The same from the first sample (includes trunk motions on four feet) [m].
    stance_slip_whole_run: float
    max_torque_ratio: float  # max |applied motor torque| / effort limit over the run
    qp_failures: int
    # Wall time of a controller tick, while a leg manipulates if one does, else over the run [ms].
    tick_median_ms: float
    tick_p99_ms: float
    # Largest change of a planned contact-force component between logged ticks (after 0.1 s) [N].
    max_force_jump: float
    min_trunk_height: float  # [m]
    # Weight not carried by the feet, mean over the last 0.5 s [N]: the prongs' load (0 without).
    prong_load: float = 0.0
    # With pushes: max trunk displacement under a push (pedi_drake.evaluation.push_response) [m] ...
    push_displacement: float = float("nan")
    # ... the largest |calf torque| of a stance leg meanwhile [N m] ...
    peak_knee_torque: float = float("nan")
    # ... and whether a leg manipulated throughout the push (the demos push the robot on three legs).
    push_while_manipulating: bool = False


def _nearest(log: SignalLog, times: np.ndarray) -> np.ndarray:
    """Indices of `log`'s samples at (or just after) `times`."""
    return np.clip(np.searchsorted(log.times, times), 0, len(log.times) - 1)


def _positions(plant, states: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """True trunk origins (N, 3) and foot centres (N, 4, 3) of logged plant states (nx, N) [m]."""
    context = plant.CreateDefaultContext()
    nq = plant.num_positions()
    trunk = plant.GetBodyByName(robot.TRUNK_BODY_NAME)
    feet = [plant.GetBodyByName(name) for name in robot.FOOT_BODY_NAMES]
    trunk_p = np.zeros((states.shape[1], 3))
    feet_p = np.zeros((states.shape[1], 4, 3))
    for k in range(states.shape[1]):
        plant.SetPositions(context, states[:nq, k])
        trunk_p[k] = trunk.EvalPoseInWorld(context).translation()
        for i, foot in enumerate(feet):
            feet_p[k, i] = foot.EvalPoseInWorld(context).translation()
    return trunk_p, feet_p


def _manipulating_legs(leg_reference: np.ndarray) -> list[str]:
    """Legs that had a task in the logged `mission.leg_reference` at some sample."""
    return [leg for k, leg in enumerate(robot.LEG_NAMES) if np.any(leg_reference[k * LEG_BLOCK] != LEG_MODE_NONE)]


def _max_norm(values: np.ndarray) -> float:
    return float(np.max(np.linalg.norm(values, axis=-1))) if values.size else 0.0


def hold_foot_errors(mission: spec.MissionSpec, progress, plant, times: np.ndarray, states: np.ndarray) -> list[float]:
    """Per leg of every succeeded reach phase: max true |foot - target| over its final `hold` [m]."""
    phases = {phase.name: phase for phase in mission.phases}
    context = plant.CreateDefaultContext()
    nq = plant.num_positions()
    errors = []
    for record in progress.records:
        phase = phases.get(record.name)
        if not isinstance(phase, spec.Reach) or record.status != SUCCEEDED:
            continue
        legs = record.metrics.get("legs") or [{"leg": phase.leg, "target_W": record.metrics["target_W"]}]
        window = np.flatnonzero((times >= record.t_end - phase.hold) & (times <= record.t_end))
        for row in legs:
            foot = plant.GetBodyByName(f"{row['leg']}_foot")
            worst = 0.0
            for k in window:
                plant.SetPositions(context, states[:nq, k])
                error = np.linalg.norm(foot.EvalPoseInWorld(context).translation() - np.asarray(row["target_W"]))
                worst = max(worst, float(error))
            errors.append(worst)
    return errors


def controller_metrics(record, judged: dict) -> ControllerMetrics:
    """The figures of `record` (a simulated `pedi_drake.run.RunRecord` of a mission) and its
    `judged` result (`pedi_drake.evaluation.judge.judge_run`)."""
    if record.hardware or record.built.mission is None:
        raise PediError("controller metrics need a simulated mission run (ground truth and the mission's logs)")
    # The scenario as simulated: with the mission's robot variant and pushes.
    logs, scenario = record.logs, apply_mission(record.scenario, record.built.mission)
    plant = record.built.diagram.GetSubsystemByName("station").GetSubsystemByName("plant")
    state_log = logs["sim.plant_state"]
    times, states = state_log.times, state_log.data
    trunk_p, feet_p = _positions(plant, states)

    status = logs["mission.status"]
    manipulating = status.data[2, _nearest(status, times)] > 0.5
    legs_log = logs["mission.leg_reference"]
    lifted = _manipulating_legs(legs_log.data)
    stance = [i for i, leg in enumerate(robot.LEG_NAMES) if leg not in lifted]

    pushes = scenario.pushes
    first_push = min((push.start for push in pushes), default=np.inf)
    before_push = manipulating & (times < first_push)
    body_ref = logs["mission.body_reference"]
    p_ref = body_ref.data[0:3, _nearest(body_ref, times)].T
    drift = _max_norm(trunk_p[before_push] - p_ref[before_push])

    slip = slip_all = 0.0
    active = np.flatnonzero(manipulating)
    for i in stance:
        slip_all = max(slip_all, _max_norm(feet_p[:, i, :2] - feet_p[0, i, :2]))
        if len(active):
            slip = max(slip, _max_norm(feet_p[active, i, :2] - feet_p[active[0], i, :2]))

    torque_log = logs["sim.motor_torque"]
    torque = torque_log.data.T
    diagnostics = logs["controller.diagnostics"]
    num_contacts = 4 + (0 if scenario.robot.prongs is None else scenario.robot.prongs.num_prongs)
    layout = diagnostics_layout(num_contacts)
    ticks = 1e3 * diagnostics.data[layout["tick_time"]].ravel()
    tick_manipulating = status.data[2, _nearest(status, diagnostics.times)] > 0.5
    if np.any(tick_manipulating):
        ticks = ticks[tick_manipulating]
    ticks = ticks[ticks > 0]
    forces = diagnostics.data[layout["contact_forces"]].T[diagnostics.times >= FORCE_JUMP_AFTER]

    result = ControllerMetrics(
        fell=bool(judged["fell"]),
        mission_succeeded=bool(judged["success"]),
        sim_time=record.sim_time,
        wall_time=record.wall_time,
        real_time_factor=record.sim_time / record.wall_time,
        foot_errors=hold_foot_errors(record.built.mission, record.mission_progress(), plant, times, states),
        trunk_drift=drift,
        stance_slip=slip,
        stance_slip_whole_run=slip_all,
        max_torque_ratio=float(np.max(np.abs(torque) / robot.EFFORT_LIMIT)),
        qp_failures=int(diagnostics.data[layout["total_failures"], -1][0]),
        tick_median_ms=float(np.median(ticks)) if len(ticks) else float("nan"),
        tick_p99_ms=float(np.percentile(ticks, 99)) if len(ticks) else float("nan"),
        max_force_jump=float(np.max(np.abs(np.diff(forces, axis=0)))) if len(forces) > 1 else 0.0,
        min_trunk_height=float(np.min(trunk_p[:, 2])),
    )
    if scenario.robot.prongs is not None:
        feet = logs["go1.foot_contact"]
        last = feet.times >= feet.times[-1] - PRONG_LOAD_WINDOW
        # The prongs belong to the Go1's model instance (robot.add_go1).
        model = plant.GetBodyByName(robot.TRUNK_BODY_NAME).model_instance()
        weight = plant.CalcTotalMass(plant.CreateDefaultContext(), [model]) * robot.GRAVITY
        result.prong_load = float(weight - np.mean(np.sum(feet.data[:, last], axis=0)))
    responses = [r for r in (push_response(plant, logs, push) for push in pushes) if r is not None]
    if responses:
        result.push_displacement = max(r.trunk_displacement for r in responses)
        result.peak_knee_torque = max(r.knee_torque_peak[leg] for r in responses for leg in r.stance_legs)
        window = (times >= first_push) & (times <= max(push.end() for push in pushes))
        result.push_while_manipulating = bool(np.any(window) and np.all(manipulating[window]))
    return result
