"""Mission results for result.json, judged against simulation ground truth after the run.

The mission manager decides success from the state estimate, as the robot would. These figures
(foot errors, trunk drift, door angle, ...) are the evaluator's view: they come from the logged
plant state, which no controller ever reads.
"""

import math

import numpy as np

from pedi_drake import robot
from pedi_drake.control.references import LEG_BLOCK
from pedi_drake.evaluation.obstacle_response import classify_press
from pedi_drake.mission.progress import MissionProgress

FOOT_ON_GROUND = 0.005  # [m] a foot centre this close above its radius touches the ground


def _sample_index(times: np.ndarray, t: float) -> int:
    return int(np.clip(np.searchsorted(times, t), 0, len(times) - 1))


def _foot_W(plant, context, x: np.ndarray, leg: str) -> np.ndarray:
    plant.SetPositionsAndVelocities(context, x)
    return plant.GetBodyByName(f"{leg}_foot").EvalPoseInWorld(context).translation()


def phase_table(progress: MissionProgress) -> list[dict]:
    """The `phases` list of result.json."""
    return [
        {
            "name": r.name,
            "kind": r.kind,
            "status": r.status,
            "t_start": r.t_start,
            "t_end": r.t_end,
            "reason": r.reason,
        }
        for r in progress.records
    ]


def mode_switch_table(progress: MissionProgress) -> list[dict]:
    """The `mode_switches` list of result.json: {time [s], from, to, reason, phase} per switch."""
    return [
        {"time": s.time, "from": s.from_mode, "to": s.to_mode, "reason": s.reason, "phase": s.phase}
        for s in progress.switches
    ]


def friction_table(progress: MissionProgress) -> list[dict]:
    """The `friction_changes` list of result.json: {time [s], friction [-], by} per change of the
    controllers' friction coefficient (a set_friction phase: "mission"; the operator: "operator")."""
    return [{"time": t, "friction": mu, "by": source} for t, mu, source in progress.friction_changes]


def posture_table(progress: MissionProgress) -> list[dict]:
    """The `postures` list of result.json: every lift with posture: optimal, its fixed and optimal
    postures and their SUFs at its targets (pedi_drake.suf.posture; the estimate's stance)."""
    return [
        {"phase": r.name, "leg": r.metrics.get("leg", ""), **r.metrics["posture"]}
        for r in progress.records
        if r.kind == "leg_to_pedipulation" and "posture" in r.metrics
    ]


def _finite_or_none(value: float | None) -> float | None:
    return value if value is not None and math.isfinite(value) else None


def teleop_table(progress: MissionProgress) -> list[dict]:
    """The `teleop` list of result.json: per teleop_foot phase, how often each of its bounds acted
    (pedi_drake.mission.teleop_foot.BOUNDS), its largest estimated foot force [N], the estimate's
    noise [N] and the lowest force limit the bound kept for it [N], and what ended it."""
    return [
        {
            "phase": r.name,
            "leg": r.metrics.get("leg", ""),
            "bound_activations": dict(r.metrics.get("bound_activations", {})),
            "max_force_n": r.metrics.get("max_force_n"),
            "force_noise_n": r.metrics.get("force_noise_n"),
            # None when the phase ended before its first update.
            "min_force_limit_n": _finite_or_none(r.metrics.get("min_force_limit_n")),
            "ended_by": r.metrics.get("ended_by", ""),
        }
        for r in progress.records
        if r.kind == "teleop_foot"
    ]


def target_table(progress: MissionProgress) -> dict:
    """The `operator_targets` of result.json: every target the operator sent in the
    semi-autonomous mode ({time [s], target_W [m], accepted, reason}) and how many were refused."""
    rows = [
        {"time": r.time, "target_W": list(r.target_W), "accepted": r.accepted, "reason": r.reason}
        for r in progress.target_requests
    ]
    return {"requests": rows, "refused": sum(not row["accepted"] for row in rows)}


def _reach_rows(progress: MissionProgress):
    """(record, leg, target_W, estimated error) for every leg of every finished reach phase."""
    for record in progress.records:
        if record.kind != "reach" or record.t_end is None or "target_W" not in record.metrics:
            continue
        metrics = record.metrics
        legs = metrics.get("legs") or [
            {"leg": metrics["leg"], "target_W": metrics["target_W"], "error_m": metrics.get("error_m")}
        ]
        for row in legs:
            yield record, row["leg"], list(row["target_W"]), row.get("error_m")


def foot_errors(progress: MissionProgress, plant, times: np.ndarray, states: np.ndarray) -> list[dict]:
    """Final foot-to-target distance of every leg of every reach phase, from the true foot [m]."""
    context = plant.CreateDefaultContext()
    rows = []
    for record, leg, target_W, estimated in _reach_rows(progress):
        k = _sample_index(times, record.t_end)
        true_foot = _foot_W(plant, context, states[:, k], leg)
        rows.append(
            {
                "phase": record.name,
                "leg": leg,
                "error": float(np.linalg.norm(true_foot - np.asarray(target_W))),
                "estimated_error": estimated,
                "target_W": target_W,
                "status": record.status,
            }
        )
    return rows


def max_base_drift(p_WB: np.ndarray, body_ref: np.ndarray, status: np.ndarray) -> float:
    """Largest |p_WB - p_WB_ref| while a leg is in pedipulation mode [m] (0 if never).

    `p_WB` (3, N): trunk positions (ground truth in simulation, the estimate on hardware), sampled
    with the logged body references and mission status.
    """
    n = min(p_WB.shape[1], body_ref.shape[1], status.shape[1])
    active = status[2, :n] > 0.5
    if not np.any(active):
        return 0.0
    p = p_WB[:, :n]
    return float(np.max(np.linalg.norm(p[:, active] - body_ref[0:3, :n][:, active], axis=0)))


def estimated_foot_errors(progress: MissionProgress) -> list[dict]:
    """Every leg's final foot error in every reach phase as the controller estimated it [m]."""
    return [
        {
            "phase": record.name,
            "leg": leg,
            "error": estimated,
            "estimated_error": estimated,
            "target_W": target_W,
            "status": record.status,
            "t_end": record.t_end,
        }
        for record, leg, target_W, estimated in _reach_rows(progress)
    ]


def sensed_touches(progress: MissionProgress) -> list[dict]:
    """Each touching reach (spec.GuardedTouch) as the robot sensed it: whether contact was felt,
    the force it felt against the approach [N] (less its bias) by which estimate, the bias [N]
    and whether it was taken with the foot moving freely (else at rest, at the approach point),
    and where along the approach contact came, from the target [m] (< 0: before it)."""
    rows = []
    for record in progress.records:
        touch = record.metrics.get("touch") if record.kind == "reach" else None
        if touch is None:
            continue
        rows.append(
            {
                "phase": record.name,
                "leg": record.metrics.get("leg", ""),
                "confirmed": bool(touch["confirmed"]),
                "force_n": touch.get("force_n", touch["largest_force_n"]),
                "force_estimate": touch["force_estimate"],
                "felt_from_target_m": touch.get("felt_from_target_m"),
                "travel_m": touch["travel_m"],
                "bias_n": touch.get("bias_n"),
                "bias_in_motion": touch.get("bias_n") is not None,
            }
        )
    return rows


def prong_leans(progress: MissionProgress) -> list[dict]:
    """Each lean_on_prongs as the robot sensed it: the most the feet carried before the prongs
    took load [N] (their summed vertical load, joint-torque estimate), the load the prongs took
    off them when the lean was judged loaded (or at its end) [N], and when the load was felt [s]
    (null: never)."""
    return [
        {
            "phase": record.name,
            "feet_load_before_n": record.metrics["feet_load_before_n"],
            "prong_load_n": record.metrics.get("prong_load_n"),
            "load_felt_at_s": record.metrics.get("load_felt_at_s"),
        }
        for record in progress.records
        if record.kind == "lean_on_prongs" and "feet_load_before_n" in record.metrics
    ]


def _press_figures(metrics: dict, source: str) -> dict:
    """A finished press's figures by the force estimate `source`, its obstacle classified."""
    curve = metrics["curve"]
    response = classify_press(curve["displacement_m"], curve["force_n"][source], metrics["stopped_by"])
    return {
        "force_n": metrics["forces_n"][source],
        "peak_force_n": response.peak_force_n,
        "rise_stiffness_n_per_m": response.rise_stiffness_n_per_m,
        "travel_beyond_rise_m": response.travel_beyond_rise_m,
        "force_growth_n": response.force_growth_n,
        "classified_as": response.stiffness_class,
        "mobility": response.mobility,
    }


def press_results(progress: MissionProgress) -> list[dict]:
    """Each press phase: force, displacement and what its force-displacement curve says of the
    obstacle (pedi_drake.evaluation.obstacle_response), by the mission's force estimate and by
    each available one."""
    rows = []
    for record in progress.records:
        metrics = record.metrics
        if record.kind != "press" or "curve" not in metrics:
            continue
        by_estimate = {source: _press_figures(metrics, source) for source in metrics["curve"]["force_n"]}
        rows.append(
            {
                "phase": record.name,
                "displacement_m": metrics["displacement_m"],
                "stopped_by": metrics["stopped_by"],
                "force_estimate": metrics["force_estimate"],
                **by_estimate[metrics["force_estimate"]],
                "by_estimate": by_estimate,
            }
        )
    return rows


def door_opening(plant, states: np.ndarray) -> dict | None:
    """Door hinge angle at the start and the end [rad], if the scene has a door."""
    if not plant.HasModelInstanceNamed("door"):
        return None
    hinge = plant.GetJointByName("hinge", plant.GetModelInstanceByName("door"))
    start, end = states[hinge.position_start(), 0], states[hinge.position_start(), -1]
    return {"start_rad": float(start), "end_rad": float(end), "opened_deg": float(np.degrees(end - start))}


def box_displacement(plant, states: np.ndarray) -> dict | None:
    """Where the box started and ended, and how far it moved on the floor [m], if the scene has one."""
    if not plant.HasModelInstanceNamed("box"):
        return None
    box = plant.GetBodyByName("box", plant.GetModelInstanceByName("box"))
    i = box.floating_positions_start() + 4  # [quaternion; position]
    start, end = states[i : i + 3, 0], states[i : i + 3, -1]
    return {"start_m": start.tolist(), "end_m": end.tolist(), "moved_m": float(np.linalg.norm((end - start)[:2]))}


def pedipulation_leg(leg_reference_log: np.ndarray) -> str | None:
    """The first leg that ever had a task in `leg_reference`."""
    for k, leg in enumerate(robot.LEG_NAMES):
        if np.any(leg_reference_log[k * LEG_BLOCK] > 0.5):
            return leg
    return None


def foot_positions_W(plant, states: np.ndarray, indices: np.ndarray) -> np.ndarray:
    """True foot centres (len(indices), 4, 3) at the logged plant states `states[:, indices]` [m]."""
    context = plant.CreateDefaultContext()
    feet = [plant.GetBodyByName(name) for name in robot.FOOT_BODY_NAMES]
    nq = plant.num_positions()
    positions = np.zeros((len(indices), len(feet), 3))
    for row, k in enumerate(indices):
        plant.SetPositions(context, states[:nq, k])
        for i, foot in enumerate(feet):
            positions[row, i] = foot.EvalPoseInWorld(context).translation()
    return positions


def foot_slides(feet_W: np.ndarray) -> dict[str, float]:
    """Per foot of `feet_W` (N, 4, 3) [m]: the largest horizontal distance from its first sample at
    the samples where it touches the ground [m] (0 if it never does).

    A foot lifted on purpose is not taken for one that slid; the figure is an upper bound of the
    slip, as it also counts the foot sphere rolling when the calf turns.
    """
    on_ground = feet_W[:, :, 2] < robot.FOOT_RADIUS + FOOT_ON_GROUND
    moved = np.linalg.norm(feet_W[:, :, :2] - feet_W[:1, :, :2], axis=-1)
    return {leg: float(np.max(moved[on_ground[:, i], i], initial=0.0)) for i, leg in enumerate(robot.LEG_NAMES)}


def max_foot_slip(plant, states: np.ndarray, t_state: np.ndarray, t_end: float) -> float:
    """Largest horizontal distance any foot moved on the ground from the first sample to `t_end` [m]
    (see `foot_slides`)."""
    last = _sample_index(t_state, t_end)
    step = max(1, last // 200)  # a few hundred samples are enough to see a slide of centimetres
    feet_W = foot_positions_W(plant, states, np.arange(0, last + 1, step))
    return max(foot_slides(feet_W).values())


def trunk_height_at(p_WB: np.ndarray, times: np.ndarray, t: float) -> float:
    """The trunk origin's height at time `t` (the logged sample at or after it) [m]."""
    return float(p_WB[2, _sample_index(times, t)])
