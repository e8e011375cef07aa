"""Judging the walking phases by ground truth: result.json's `walks` rows.

Per `walk`, `walk_velocity` or `walk_teleop` phase: the trunk's true start and end pose, the
distance it walked and its mean speed (while walking, and over a walk_velocity's commanded
window), how far any stance foot slipped, the estimate's drift against the true trunk path, the
steps and touchdowns the phase counted, and for `walk` the true distance and heading error from
its goal (a `walk` whose trunk stopped outside its tolerances fails, whatever the estimate says).
"""

import math

import numpy as np
from pydrake.common.eigen_geometry import Quaternion
from pydrake.math import RollPitchYaw, RotationMatrix

from pedi_drake import robot
from pedi_drake.mission import spec

# A foot is in stance where the ground pushes it with at least this [N] (true contact force) ...
STANCE_FORCE = 20.0
# ... and its slip is its horizontal travel within one stance, after this settling time [s]
# from the touchdown (the sphere rolls onto its contact as the load comes on).
STANCE_SETTLE = 0.05
SLIP_SAMPLE_PERIOD = 0.01  # [s] feet are sampled this often for the slip
WALK_KINDS = (spec.Walk, spec.WalkVelocity, spec.WalkTeleop)  # a walk_to is a walk
# Their mission-file kinds, as a result's phase rows name them.
WALK_KIND_NAMES = ("walk", "walk_to", "walk_velocity", "walk_teleop")
DRIFT_DISTANCE = 0.2  # [m] the least displacement the estimate's drift is given as a share of


def _yaw(quaternion_wxyz: np.ndarray) -> float:
    q = np.asarray(quaternion_wxyz, float)
    return float(RollPitchYaw(RotationMatrix(Quaternion(q / np.linalg.norm(q)))).yaw_angle())


def _wrap(angle: float) -> float:
    return (angle + math.pi) % (2.0 * math.pi) - math.pi


def feet_contact_travel(plant, states: np.ndarray, indices: np.ndarray) -> np.ndarray:
    """(len(indices), 4, 2) each foot's ground contact point's horizontal travel [m] from the first
    sample, accumulated from sample to sample: the sphere's centre displacement less what rolling
    on the ground moves it by (its rotation phi about the contact point moves the centre by
    phi x (r z)). Zero travel while the foot rolls without slipping."""
    context = plant.CreateDefaultContext()
    feet = [plant.GetBodyByName(name) for name in robot.FOOT_BODY_NAMES]
    nq = plant.num_positions()
    lever = np.array([0.0, 0.0, robot.FOOT_RADIUS])
    travel = np.zeros((len(indices), len(feet), 2))
    last = None
    for row, k in enumerate(indices):
        plant.SetPositions(context, states[:nq, k])
        poses = [foot.EvalPoseInWorld(context) for foot in feet]
        if last is not None:
            for i, (pose, before) in enumerate(zip(poses, last, strict=True)):
                turn = (pose.rotation() @ before.rotation().inverse()).ToAngleAxis()
                phi = turn.axis() * turn.angle()
                step = pose.translation() - before.translation() - np.cross(phi, lever)
                travel[row, i] = travel[row - 1, i] + step[:2]
        last = poses
    return travel


def stance_slips(travel: np.ndarray, stance: np.ndarray, times: np.ndarray) -> np.ndarray:
    """Per foot, the largest horizontal slip [m] within one stance: `travel` (N, 4, 2) of the feet's
    contact points (feet_contact_travel) and `stance` (N, 4) bool sampled at `times` (N,) [s]; the
    first STANCE_SETTLE of a stance skipped."""
    slips = np.zeros(travel.shape[1])
    for i in range(travel.shape[1]):
        start = None
        for n in range(len(times) + 1):
            on = n < len(times) and stance[n, i]
            if on and start is None:
                start = n
            if not on and start is not None:
                window = np.flatnonzero(times[start:n] >= times[start] + STANCE_SETTLE) + start
                if window.size > 1:
                    slips[i] = max(
                        slips[i], float(np.max(np.linalg.norm(travel[window, i] - travel[window[0], i], axis=1)))
                    )
                start = None
    return slips


def judge_walks(
    mission, phases: list[dict], metrics: dict, plant, t_state, states, base_log, foot_forces
) -> tuple[list[dict], str]:
    """result.json's `walks` rows and why a walk missed its goal (empty if none did).

    `metrics` the phases' own counts by phase name (pedi_drake.mission.walk: steps, touchdowns);
    `states` (nx, N) the logged plant states at `t_state` [s]; `base_log` the estimate's SignalLog;
    `foot_forces` the SignalLog of the true foot contact forces (12: per foot, world [N])."""
    q0 = robot.Go1PlantMap.from_plant(plant).base_q_start
    rows, problems = [], []
    for phase, row in zip(mission.phases, phases, strict=False):
        if not isinstance(phase, WALK_KINDS) or row["t_end"] is None:
            continue
        t0, t1 = row["t_start"], row["t_end"]
        window = np.flatnonzero((t_state >= t0) & (t_state <= t1))
        if window.size < 2:
            continue
        quaternions, positions = states[q0 : q0 + 4], states[q0 + 4 : q0 + 7]
        first, last = window[0], window[-1]
        path = np.linalg.norm(np.diff(positions[:2, window], axis=1), axis=0).sum()
        end_pose = [*positions[:2, last].tolist(), _yaw(quaternions[:, last])]
        start_pose = [*positions[:2, first].tolist(), _yaw(quaternions[:, first])]
        walk = {
            "phase": row["name"],
            "kind": row["kind"],
            "gait": phase.gait,
            "start_pose": start_pose,
            "end_pose": end_pose,
            "displacement_m": float(np.linalg.norm(positions[:2, last] - positions[:2, first])),
            "turned_rad": _wrap(end_pose[2] - start_pose[2]),
            "path_length_m": float(path),
        }
        counted = metrics.get(row["name"], {})
        for key in ("steps", "early_touchdowns", "late_touchdowns", "slowed_cycles", "slowed_slots"):
            walk[key] = counted.get(key)
        errors = counted.get("foothold_errors_m") or [0.0]
        walk["foothold_error_max_m"] = float(max(errors))
        if "stop" in counted:
            walk["stop"] = counted["stop"]
        # The mean speed while walking: from the phase's start to its stop (a cycle at rest and the
        # trunk's centring, which are not walking).
        t_stop = counted.get("walked_until_s")
        if t_stop is not None and t_stop > t0:
            k_stop = window[max(np.searchsorted(t_state[window], t_stop) - 1, 0)]
            walked = float(np.linalg.norm(positions[:2, k_stop] - positions[:2, first]))
            walk["walking_speed_m_s"] = walked / (t_state[k_stop] - t_state[first])
            walk["walking_time_s"] = float(t_state[k_stop] - t_state[first])
        if isinstance(phase, spec.WalkVelocity):
            # Over the commanded window: the walk's own stop (a cycle at rest) comes after it.
            t_cmd = min(t0 + phase.duration, t1)
            k_cmd = window[np.searchsorted(t_state[window], t_cmd) - 1]
            direction = np.asarray(phase.twist[:2], float)
            if np.linalg.norm(direction) > 0.0:
                yaw0 = start_pose[2]
                forward = np.array([math.cos(yaw0), math.sin(yaw0)])
                left = np.array([-math.sin(yaw0), math.cos(yaw0)])
                moved = positions[:2, k_cmd] - positions[:2, first]
                speed = np.array([forward @ moved, left @ moved]) / (t_state[k_cmd] - t_state[first])
                walk["mean_velocity_m_s"] = speed.tolist()
        if isinstance(phase, spec.Walk):
            # A walk_to's goal is the stop it chose (its record's `stop`), a walk's its position.
            goal = counted.get("stop", {}).get("taken_W", [*phase.position, phase.yaw])
            error = float(np.linalg.norm(positions[:2, last] - np.asarray(goal[:2], float)))
            yaw_error = abs(_wrap(goal[2] - end_pose[2]))
            walk.update(goal_error_m=error, goal_yaw_error_rad=yaw_error)
            if error > phase.tolerance or yaw_error > phase.yaw_tolerance:
                problems.append(
                    f"{row['name']}: the trunk stopped {100 * error:.1f} cm and {math.degrees(yaw_error):.1f} deg "
                    f"from the goal (tolerances {100 * phase.tolerance:.1f} cm, "
                    f"{math.degrees(phase.yaw_tolerance):.1f} deg)"
                )
        # Stance slip: the feet sampled every SLIP_SAMPLE_PERIOD, in stance where the ground pushes them.
        step = max(1, int(round(SLIP_SAMPLE_PERIOD / max(t_state[1] - t_state[0], 1e-9))))
        samples = window[::step]
        travel = feet_contact_travel(plant, states, samples)
        k_force = np.clip(np.searchsorted(foot_forces.times, t_state[samples]), 0, foot_forces.times.size - 1)
        normal = foot_forces.data[2::3, k_force].T  # (N, 4) the forces' vertical components
        slips = stance_slips(travel, normal > STANCE_FORCE, t_state[samples])
        walk["max_stance_slip_m"] = {leg: float(slips[i]) for i, leg in enumerate(robot.LEG_NAMES)}
        # The estimate's drift: how much its error grew over the walk, against the path walked.
        k_est = np.clip(np.searchsorted(base_log.times, t_state[[first, last]]), 0, base_log.times.size - 1)
        errors = base_log.data[4:7, k_est] - positions[:, [first, last]]
        drift = float(np.linalg.norm(errors[:2, 1] - errors[:2, 0]))
        estimate_window = np.clip(np.searchsorted(base_log.times, t_state[samples]), 0, base_log.times.size - 1)
        height_errors = base_log.data[6, estimate_window] - positions[2, samples]
        walk.update(
            estimate_drift_m=drift,
            # Against the distance walked: the trunk's displacement (its sway's path left out); none
            # for a walk that turns on the spot.
            estimate_drift_share=drift / walk["displacement_m"] if walk["displacement_m"] >= DRIFT_DISTANCE else None,
            estimate_height_error_max_m=float(np.max(np.abs(height_errors))),
        )
        rows.append(walk)
    return rows, "; ".join(problems)
