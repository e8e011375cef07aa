"""Software in the loop over real UDP: a mission through the Go1 LCM driver against the simulator
bridge in a second process, judged against the bridge's ground truth.

    python -m pedi_drake.apps.sil [--mission hit_target_front] [--scenario_name NAME]
                                  [--scenario_text YAML] [--lcm_url URL] [--out out/sil_<mission>]
                                  [--separate] [--robot drake|mujoco]
                                  [--operator_log FILE | --operator_script FILE [--operator_leg LEG]
                                   | --operator_search_button HEADING_DEG]
                                  [--callbacks] [--pin]
                                  [--flood_at S [--flood_duration S] [--flood_rate HZ]]

Starts `python -m pedi_drake.apps.sim_bridge --mission M --truth_log ...` (the robot side,
real time, 500 Hz), then runs the mission here exactly as `run_sim.py --hardware` does (driver,
state estimator, controller, mission manager; no ground truth on this side), stops the bridge
and compares: each reach phase's target with where the bridge's simulated foot really was at the
end of the phase (the two processes' logs are aligned by the host's wall clock). Prints a table
and writes `sil.json` beside the run's result.json.

With `--separate` the controller side is not run here but started as its own program, the
README's second terminal: `python run_sim.py --hardware --mission M ...` (the run_sim.py beside
the package, so a source checkout), while the bridge keeps running as the first terminal's does.
This process then only starts, waits and judges.

`--robot mujoco` runs the robot side in MuJoCo instead (`python -m pedi_drake.apps.mujoco_bridge`,
the same wire and truth log, another engine and a Go1 model with a real one's joint friction and
soft feet); everything else is unchanged. For either robot, `sil.json` has the mission's touches
judged by the truth log's contact forces (`touches`, pedi_drake.evaluation.touches), a
`success_by_truth` (the mission's success and every touch happened by physics) and the estimate's
vertical trunk error against the truth while standing still (`estimator_trunk_height_error`).
Against the Drake robot, whose truth log carries the whole plant's state, the mission's other
physical checks are judged on it too (`truth_checks`: an object push, an E-stop button press,
every walk's true end pose and stance slip), and count in `success_by_truth`.

`--operator_log FILE` adds an operator in a third process, as a person would run one:
`python -m pedi_drake.apps.teleop_lcm --lcm_log FILE --start_on_feedback` on the same bus, which
plays the log's messages on the controller's clock (the scenario needs `operator: {source: lcm}`).
`--operator_script FILE` plays a teleop_lcm script instead (its velocities in the trunk frame),
from the robot's offer of the foot `--operator_leg` (FR): `python -m pedi_drake.apps.teleop_lcm
--script FILE --start_on_leg FR`. `--operator_search_button HEADING_DEG` runs the operator that
finds an E-stop button by touch (`teleop_lcm --search_button HEADING_DEG`), as for
terrain/field_course.

`--callbacks` times the controller side's Python callbacks (pedi_drake.measuring.callback_profile) and keeps
those over 1 ms of the loop's CPU time, and the garbage collections over 1 ms, each with its
diagram time: beside the driver's stalls (their tick times and the loop's CPU time in each), what
a late tick computed, and the page faults the loop thread took in each call. The timers add a
microsecond or two to each call.

`--flood_at S` adds a publisher of malformed status messages in a third process,
`python -m pedi_drake.apps.status_flood`: S seconds after the controller's first command it
floods every status channel for `--flood_duration` seconds (1) at `--flood_rate` messages a
second (500) of each kind (a wrong fingerprint, truncated, NaN fields). `sil.json`'s `flood`
then says whether the driver counted every one by channel and reason, and how late the loop's
ticks were while it lasted (from the run's wall-clock log): a floor of the hardware swap is that
the flood latches nothing and delays no tick past its period.

`--pin` runs the bridge on the last CPU this process may use and the controller side on the
others (Linux CPU affinity; `sil.json`'s `cpus` says which): on a 2-core machine each process
keeps a core of its own instead of the kernel moving them between the two.
"""

import argparse
import contextlib
import json
import math
import os
import signal
import subprocess
import sys
import time
from pathlib import Path
from types import SimpleNamespace

import numpy as np
from pydrake.common.yaml import yaml_load

from pedi_drake import robot
from pedi_drake.apps.bridge_options import bridge_scenario
from pedi_drake.apps.sim_bridge import TRUTH_LOG_PERIOD
from pedi_drake.apps.status_flood import expected_rejections, number_problem
from pedi_drake.evaluation.button_press import judge_button_press, plunger_travel
from pedi_drake.evaluation.estimator_accuracy import STANDING_TRUNK_HEIGHT
from pedi_drake.evaluation.object_push import judge_object_push
from pedi_drake.evaluation.touches import judge_touches
from pedi_drake.evaluation.walks import WALK_KINDS, judge_walks
from pedi_drake.exceptions import ConfigError
from pedi_drake.go1_driver.link import lateness_against_earliest
from pedi_drake.measuring.callback_profile import slow_calls
from pedi_drake.measuring.cpu_steal import steal_seconds
from pedi_drake.mission.spec import load_mission
from pedi_drake.run import run
from pedi_drake.run_checks import check_out_dir
from pedi_drake.run_logs import read_run_logs
from pedi_drake.scenario import apply_scenario_text, lcm_url_is_valid, load_scenario
from pedi_drake.station_interface import MakeStation

GROUP = "239.255.76.67"
# The README's controller program, beside the package in a source checkout.
RUN_SIM = Path(__file__).resolve().parents[2] / "run_sim.py"
BRIDGE_START_TIMEOUT = 60.0  # [s] for the bridge to build its diagram and start publishing
START_WINDOW = 0.1  # [s] of the loop's start judged by `start_transient`
# [m/s] a trunk moving up or down slower than this, above STANDING_TRUNK_HEIGHT, stands still.
STILL_SPEED = 0.02
# [s] between two ground-truth samples of the bridge (TRUTH_LOG_PERIOD apart in simulated time)
# that `bridge_pace` counts as the robot side falling behind: two samples' worth.
BRIDGE_GAP = 0.02
# [s] for the operator to finish its log after the controller side ended (then it is stopped).
OPERATOR_END_TIMEOUT = 30.0
# [s] an operator script waits this long for the robot's offer of the foot (a whole field course).
OPERATOR_OFFER_TIMEOUT = 600.0
# [s] of the loop's CPU time over which `--callbacks` keeps a call (a control period is 2 ms).
SLOW_CALL = 0.001
# [s] for the flood's publisher to leave once stopped.
FLOOD_END_TIMEOUT = 30.0
# The robot side's program for each --robot: the project's Drake simulation, or MuJoCo.
BRIDGES = {"drake": "pedi_drake.apps.sim_bridge", "mujoco": "pedi_drake.apps.mujoco_bridge"}


def true_foot_errors(result: dict, controller_logs: dict, truth: dict) -> list[dict]:
    """Per reach phase: |true foot position at the phase end - target| [m], via the wall clock.

    `controller_logs` are the run's logs (with `wall_clock`), `truth` the bridge's truth log.
    """
    clock = controller_logs["wall_clock"]
    rows = []
    for row in result["foot_errors_m"]:
        wall = float(np.interp(row["t_end"], clock.times, clock.data[0]))
        leg = robot.LEG_NAMES.index(row["leg"])
        p_true = np.array([np.interp(wall, truth["wall_time"], truth["p_WF"][:, leg, k]) for k in range(3)])
        rows.append(
            {
                "phase": row["phase"],
                "leg": row["leg"],
                "true_error_m": float(np.linalg.norm(p_true - np.asarray(row["target_W"]))),
                "estimated_error_m": row["estimated_error"],
            }
        )
    return rows


def _estimate_and_truth(controller_logs: dict, truth: dict) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(estimated, true) trunk positions (3, n) [m] at the estimator's logged samples within the
    truth log's span, aligned by the wall clock, and those samples' wall times (n,) [s]."""
    clock, base = controller_logs["wall_clock"], controller_logs["base_state"]
    n = min(len(clock.times), len(base.times))
    wall = clock.data[0, :n]
    inside = (wall >= truth["wall_time"][0]) & (wall <= truth["wall_time"][-1])
    # The sample logged at t = 0 precedes the estimator's first update (it is all zeros).
    inside &= base.times[:n] > 0.0
    p_true = np.array([np.interp(wall[inside], truth["wall_time"], truth["p_WB"][:, k]) for k in range(3)])
    return base.data[4:7, :n][:, inside], p_true, wall[inside]


def estimator_error(controller_logs: dict, truth: dict) -> dict:
    """Trunk position error of the estimate against the bridge's ground truth over the run [m]."""
    p_estimated, p_true, _ = _estimate_and_truth(controller_logs, truth)
    error = np.linalg.norm(p_estimated - p_true, axis=0)
    return {"max_m": float(np.max(error)), "final_m": float(error[-1])}


def estimator_height_error(controller_logs: dict, truth: dict, standing: float = STANDING_TRUNK_HEIGHT) -> dict:
    """|z_estimated - z_true| of the trunk [m], median and max over the run's samples where the
    robot stands still: the true trunk above `standing` [m] and moving up or down slower than
    STILL_SPEED (a stand-up, a lean on the prongs or the rise from them is not standing); None when
    it never did; how many samples that was."""
    p_estimated, p_true, wall = _estimate_and_truth(controller_logs, truth)
    if wall.size < 2:
        return {"median_m": None, "max_m": None, "samples": 0, "standing_above_m": standing}
    vertical_speed = np.gradient(p_true[2], wall)
    still = (p_true[2] > standing) & (np.abs(vertical_speed) < STILL_SPEED)
    error = np.abs(p_estimated[2, still] - p_true[2, still])
    if error.size == 0:
        return {"median_m": None, "max_m": None, "samples": 0, "standing_above_m": standing}
    return {
        "median_m": float(np.median(error)),
        "max_m": float(np.max(error)),
        "samples": int(error.size),
        "standing_above_m": standing,
    }


def truth_touches(result: dict, touches: list, controller_logs: dict, truth: dict) -> tuple[list[dict], str]:
    """The mission's `touches` judged by the truth log's contact forces (judge_touches): its
    samples taken while the controller side ran, put on the controller's clock (the phases')
    through the wall clock. A truth log without contact forces judges every touch as missed."""
    clock = controller_logs["wall_clock"]
    wall = truth["wall_time"]
    inside = (wall >= clock.data[0, 0]) & (wall <= clock.data[0, -1])
    times = np.interp(wall[inside], clock.data[0], clock.times)
    names = [str(name) for name in truth.get("scene_names", [])]
    forces = truth.get("scene_contact_forces", np.zeros((len(wall), 0)))[inside].T
    missing = [touch.object for touch in touches if touch.object not in names]
    if missing:
        return [], f"the truth log has no contact forces for {sorted(set(missing))}"
    return judge_touches(touches, names, result["phases"], times, forces)


def truth_checks(mission: str, robot_scenario, result: dict, controller_logs: dict, truth: dict) -> tuple[dict, str]:
    """The mission's physical checks judged on the truth log's plant states, put on the controller's
    clock (the phases') through the wall clock, as a simulated run's result.json has them: its
    `object_push`, `button_press` and `walks` rows (pedi_drake.evaluation), and what failed ("" when
    nothing did). `robot_scenario` is the robot side's scenario, whose plant the states are of.
    ({}, "") for a truth log without plant states (the MuJoCo robot's)."""
    if "plant_states" not in truth:
        return {}, ""
    spec = load_mission(mission)
    plant = MakeStation(robot_scenario).GetSubsystemByName("plant")
    clock = controller_logs["wall_clock"]
    wall = truth["wall_time"]
    inside = (wall >= clock.data[0, 0]) & (wall <= clock.data[0, -1])
    times = np.interp(wall[inside], clock.data[0], clock.times)
    states = truth["plant_states"][inside].T
    phases = result["phases"]
    rows, problems = {}, []
    if spec.object_push is not None:
        rows["object_push"], problem = judge_object_push(plant, spec.object_push, phases, times, states)
        problems.append(problem)
    if spec.button_press is not None:
        check = spec.button_press
        phase = next(phase for phase in spec.phases if phase.name == check.phase)
        names = [str(name) for name in truth["scene_names"]]
        forces = truth["scene_contact_forces"][inside].T
        travel = plunger_travel(plant, check.button, states)
        rows["button_press"], problem = judge_button_press(
            check, phase.max_force, phases, times, travel, names, times, forces
        )
        problems.append(problem)
    if any(isinstance(phase, WALK_KINDS) for phase in spec.phases):
        foot_forces = SimpleNamespace(times=times, data=truth["foot_contact_forces"][inside].T)
        rows["walks"], problem = judge_walks(
            spec, phases, {}, plant, times, states, controller_logs["base_state"], foot_forces
        )
        problems.append(problem)
    return rows, "; ".join(filter(None, problems))


def start_transient(controller_logs: dict, truth: dict, window: float = START_WINDOW) -> dict:
    """What the robot did before the loop and in its first `window` [s]: the bridge's true trunk
    height at its first sample and at the loop's first tick [m] (the bridge holds its first pose
    with stiffness alone, no feed-forward, so a robot on its feet sags under that hold), the
    largest change of a measured joint from one tick to the next in the window [rad] (the status
    as the controller received it), and how far the true trunk sank in the window below its height
    at the first tick [m] (the legs settling when the controller's commands replace the hold)."""
    q = controller_logs["go1.position_measured"]
    clock = controller_logs["wall_clock"]
    in_window = q.times <= q.times[0] + window
    steps = np.abs(np.diff(q.data[:, in_window], axis=1))
    largest = np.unravel_index(np.argmax(steps), steps.shape) if steps.size else (0, 0)
    wall_start = float(clock.data[0, 0])
    wall_end = float(np.interp(clock.times[0] + window, clock.times, clock.data[0]))
    z = truth["p_WB"][:, 2]
    z_start = float(np.interp(wall_start, truth["wall_time"], z))
    during = (truth["wall_time"] >= wall_start) & (truth["wall_time"] <= wall_end)
    lowest = float(z[during].min()) if np.any(during) else z_start
    return {
        "true_trunk_height_bridge_start_m": float(z[0]),
        "true_trunk_height_loop_start_m": z_start,
        "window_s": window,
        "largest_joint_step_rad": float(steps[largest]) if steps.size else 0.0,
        "largest_joint_step_joint": robot.JOINT_NAMES[largest[0]] if steps.size else None,
        "largest_joint_step_t": float(q.times[largest[1] + 1]) if steps.size else None,
        "true_trunk_sink_m": z_start - lowest,
    }


def bridge_pace(truth: dict, sample_period: float = TRUTH_LOG_PERIOD, gap: float = BRIDGE_GAP) -> dict:
    """How the robot side kept to real time, from its ground-truth log: a sample every
    `sample_period` [s] of simulated time, stamped with the host's clock. The median wall time
    between samples [ms] (the sample period when the bridge keeps up), and the gaps of more than
    `gap` [s] (the bridge stopped or fell behind: its status messages came late), with the longest
    [ms]."""
    spacing = np.diff(truth["wall_time"])
    if len(spacing) == 0:
        return {"sample_period_ms": 1000 * sample_period, "median_spacing_ms": None, "gaps": 0, "longest_gap_ms": None}
    return {
        "sample_period_ms": 1000 * sample_period,
        "median_spacing_ms": 1000 * float(np.median(spacing)),
        "gaps": int(np.count_nonzero(spacing > gap)),
        "longest_gap_ms": 1000 * float(spacing.max()),
    }


def run_sil(
    mission: str,
    out_dir: Path,
    scenario_text: str = "{}",
    lcm_url: str | None = None,
    realtime_rate: float = 1.0,
    scenario_name: str = "default",
    separate: bool = False,
    operator_log: Path | None = None,
    operator_script: Path | None = None,
    operator_leg: str = "FR",
    operator_search_button: float | None = None,
    records: list | None = None,
    callbacks: bool = False,
    pin: bool = False,
    flood_at: float | None = None,
    flood_duration: float = 1.0,
    flood_rate: float = 500.0,
    robot: str = "drake",
) -> dict:
    """Runs `mission` over UDP against the simulator bridge; returns the run's result with a `sil` entry.

    `realtime_rate` < 1 runs both processes in slow motion (the watchdogs keep their wall-clock
    limits, so they are stricter in simulated time), for machines that cannot run both in real time.
    `separate`: the controller side runs as `run_sim.py --hardware` in a process of its own (see
    the module docstring) instead of in this one.
    `operator_log`: an LCM log of operator messages, played by an operator process (module docstring).
    `operator_script`: a teleop_lcm script, played by an operator process from the robot's offer of
    the foot `operator_leg` (module docstring); `operator_search_button`: the robot's heading at
    the button [deg], for an operator that finds it by touch instead.
    `records`: the controller side's RunRecord is appended to it (pedi_drake.run.run).
    `callbacks`: the controller side's Python callbacks that took more than SLOW_CALL of the loop's
    CPU time, and the collections longer than it, go into the result (`sil.slow_calls`,
    pedi_drake.measuring.callback_profile): what the late ticks computed.
    `pin`: the bridge runs on this process's last CPU and the controller side on the others
    (`pinned_cpus`), so that neither is moved onto the other's CPU.
    `flood_at`, `flood_duration`, `flood_rate`: a flood of malformed status messages `flood_at` [s]
    after the first command, for `flood_duration` [s], at `flood_rate` [1/s] per channel and kind
    (module docstring); None: no flood.
    `robot`: the robot side's engine, a key of BRIDGES ("drake": sim_bridge, "mujoco": mujoco_bridge).
    """
    if robot not in BRIDGES:
        raise ConfigError(f"--robot: expected one of {sorted(BRIDGES)}, got {robot!r}")
    if separate and not RUN_SIM.is_file():
        raise ConfigError(f"--separate: needs run_sim.py beside the package (a source checkout); no {RUN_SIM}")
    if separate and callbacks:
        raise ConfigError("--callbacks: times the controller side in this process; drop --separate")
    cpus = pinned_cpus(sorted(os.sched_getaffinity(0))) if pin else None
    if not (math.isfinite(realtime_rate) and realtime_rate > 0.0):
        raise ConfigError(f"--realtime_rate: must be a positive number (1: real time), got {realtime_rate}")
    if separate and realtime_rate != 1.0:
        raise ConfigError("--separate: run_sim.py --hardware runs at real time only; drop --realtime_rate")
    if flood_at is not None:
        flood_flags = {"--flood_at": flood_at, "--flood_duration": flood_duration, "--flood_rate": flood_rate}
        for flag, value in flood_flags.items():
            problem = number_problem(flag, value, may_be_zero=flag == "--flood_at")
            if problem is not None:
                raise ConfigError(problem)
    url = lcm_url or f"udpm://{GROUP}:{20000 + os.getpid() % 20000}?ttl=0"
    text = scenario_text if scenario_text.strip() not in ("", "{}") else "{}"
    # Everything both sides will read is checked here first: bad input is a ConfigError naming
    # the flag, not a bridge that dies with its message out of sight.
    if not lcm_url_is_valid(url):
        raise ConfigError(f"--lcm_url: expected 'udpm://GROUP:PORT' (a multicast group 224-239.x.x.x), got {url!r}")
    touches = load_mission(mission).touches
    bus = f"{{go1: {{lcm_url: '{url}'}}}}"
    overrides = f"{{mission: {mission}, controller: whole_body, estimator: kalman, lcm_buses: {bus}}}"
    scenario = apply_scenario_text(load_scenario(scenario_name=scenario_name, scenario_text=text), overrides)
    check_out_dir(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    truth_path = out_dir / "bridge_truth.npz"
    operator = flooder = None
    flood_path = out_dir / "flood.json"
    bridge = subprocess.Popen(
        [sys.executable, "-m", BRIDGES[robot], "--mission", mission, "--lcm_url", url]
        + ["--scenario_name", scenario_name, "--scenario_text", text]
        + ["--truth_log", str(truth_path), "--realtime_rate", str(realtime_rate)],
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
    )
    own_cpus = os.sched_getaffinity(0)
    if cpus is not None:
        # Threads the bridge starts from now on inherit its CPU; so do those of the controller side
        # (in this process, or its own program started from here).
        os.sched_setaffinity(bridge.pid, cpus["bridge"])
        os.sched_setaffinity(0, cpus["controller"])
    try:
        start = time.monotonic()
        line, said = "", []
        while "running" not in line:
            line = bridge.stdout.readline()
            said.append(line)
            if not line and bridge.poll() is not None:
                output = "".join(said).strip() or "(no output)"
                raise RuntimeError(f"the simulator bridge exited with {bridge.returncode} before starting:\n{output}")
            if time.monotonic() - start > BRIDGE_START_TIMEOUT:
                raise RuntimeError("the simulator bridge did not start within 60 s")
        # "go1_sim_bridge: running on URL (its scheduling)" (go1_mujoco_bridge: the same)
        bridge_scheduling = line.strip().rpartition("(")[2].rstrip(")")
        plays = None
        if operator_log is not None:
            plays = ["--lcm_log", str(operator_log), "--start_on_feedback"]
        elif operator_script is not None or operator_search_button is not None:
            plays = ["--start_on_leg", operator_leg, "--start_timeout", str(OPERATOR_OFFER_TIMEOUT)] + (
                ["--script", str(operator_script)]
                if operator_script is not None
                else ["--search_button", str(operator_search_button)]
            )
        if plays is not None:
            operator = subprocess.Popen(
                [sys.executable, "-m", "pedi_drake.apps.teleop_lcm", *plays]
                + ["--lcm_url", url, "--scenario_name", scenario_name, "--scenario_text", text],
                stdout=subprocess.PIPE,
                stderr=subprocess.STDOUT,
                text=True,
            )
        if flood_at is not None:
            flooder = subprocess.Popen(
                [sys.executable, "-m", "pedi_drake.apps.status_flood", "--lcm_url", url, "--out", str(flood_path)]
                + ["--start_after", str(flood_at), "--duration", str(flood_duration), "--rate", str(flood_rate)]
                + ["--hold"],
                stdout=subprocess.PIPE,
                stderr=subprocess.STDOUT,
                text=True,
            )
        steal_before = steal_seconds()
        if separate:
            result = _run_controller_program(mission, scenario_name, text, url, out_dir)
        else:
            with slow_calls(SLOW_CALL) if callbacks else contextlib.nullcontext() as calls:
                result = run(
                    scenario=scenario,
                    name=mission,
                    out_dir=out_dir,
                    quiet=True,
                    hardware=True,
                    realtime_rate=realtime_rate,
                    records=records,
                )
        steal_after = steal_seconds()
    finally:
        os.sched_setaffinity(0, own_cpus)
        if bridge.poll() is None:
            bridge.send_signal(signal.SIGTERM)
        bridge.communicate(timeout=120)
        if operator is not None:
            try:
                operator_output, _ = operator.communicate(timeout=OPERATOR_END_TIMEOUT)
            except subprocess.TimeoutExpired:
                operator.send_signal(signal.SIGTERM)
                operator_output, _ = operator.communicate(timeout=30)
        if flooder is not None:  # it holds after the flood (or still waits for it): stopped now
            if flooder.poll() is None:
                flooder.send_signal(signal.SIGTERM)
            flooder_output, _ = flooder.communicate(timeout=FLOOD_END_TIMEOUT)
    with np.load(truth_path) as archive:
        truth = {key: archive[key] for key in archive.files}
    logs = read_run_logs(out_dir)
    touch_rows, touch_problem = truth_touches(result, touches, logs, truth)
    robot_scenario = bridge_scenario(load_scenario(scenario_name=scenario_name, scenario_text=text), mission)
    checks, checks_problem = truth_checks(mission, robot_scenario, result, logs, truth)
    result["sil"] = {
        "robot": robot,
        "foot_errors": true_foot_errors(result, logs, truth),
        "touches": touch_rows,
        "touches_reason": touch_problem,
        "truth_checks": checks,
        "truth_checks_reason": checks_problem,
        "success_by_truth": bool(result["success"]) and not touch_problem and not checks_problem,
        # The robot's feet, which the controller takes to be robot.FOOT_RADIUS [m].
        "robot_foot_radius_m": float(truth["foot_radius"]),
        "estimator_trunk_position_error": estimator_error(logs, truth),
        "estimator_trunk_height_error": estimator_height_error(logs, truth),
        "start": start_transient(logs, truth),
        "bridge_pace": bridge_pace(truth),
        "lcm_url": url,
        "realtime_rate": realtime_rate,
        "bridge_scheduling": bridge_scheduling,
        "controller": "run_sim.py --hardware (own process)" if separate else "in the sil process",
        "cpus": None if cpus is None else {side: sorted(ids) for side, ids in cpus.items()},
    }
    if steal_before is not None and steal_after is not None:
        # What the hypervisor took from this machine's CPUs while the controller side ran (both
        # processes' cores): time a thread may have been charged as its own (pedi_drake.measuring.cpu_steal).
        result["sil"]["cpu_steal_ms"] = 1e3 * (steal_after - steal_before)
    if callbacks:
        result["sil"]["slow_calls"] = calls.summary()
    if operator is not None:
        result["sil"]["operator"] = {"returncode": operator.returncode, "output": operator_output.strip()}
    if flooder is not None:
        if flood_path.is_file():
            flood = json.loads(flood_path.read_text())
            result["sil"]["flood"] = flood_outcome(flood, result, logs, realtime_rate)
        else:  # the run ended before the flood was due, or the publisher failed: say which
            result["sil"]["flood"] = {"returncode": flooder.returncode, "output": flooder_output.strip()}
    (out_dir / "sil.json").write_text(json.dumps(result["sil"], indent=2))
    return result


def pinned_cpus(available: list[int]) -> dict[str, set[int]]:
    """`--pin`: {"bridge": the last of the `available` CPUs, "controller": the others}."""
    if len(available) < 2:
        raise ConfigError(
            f"--pin: needs two CPUs to put the bridge and the controller apart; this process may use {available}"
        )
    return {"bridge": {available[-1]}, "controller": set(available[:-1])}


def flood_outcome(flood: dict, result: dict, controller_logs: dict, realtime_rate: float = 1.0) -> dict:
    """What a flood of malformed messages (`apps.status_flood`'s record) did to the run: the
    driver's rejections by channel and reason against the ones the flood calls for, and the
    lateness of the loop's ticks logged between its first and last message [ms] (each tick's
    wall-clock log against its schedule, as the driver's report measures its publications)."""
    messages = result["driver"]["messages"]
    expected = expected_rejections(flood["sent"])
    rejected = {channel: dict(messages.get(channel, {}).get("rejected", {})) for channel in expected}
    every_one_counted = all(
        rejected[channel].get(reason, 0) == count
        for channel, reasons in expected.items()
        for reason, count in reasons.items()
    )
    period = result["driver"]["loop"]["period_s"]
    clock = controller_logs["wall_clock"]
    wall = clock.data[0]
    lateness = lateness_against_earliest(wall - clock.times / realtime_rate)
    during = (wall >= flood["first_wall"]) & (wall <= flood["last_wall"] + period)
    late = lateness[during]
    return {
        "sent": flood["sent"],
        "expected_rejections": expected,
        "rejected": rejected,
        "every_one_counted": every_one_counted,
        "ticks_during": int(np.count_nonzero(during)),
        "deadline_misses_during": int(np.count_nonzero(late > period)),
        "longest_lateness_during_ms": 1e3 * float(late.max()) if late.size else None,
        "first_wall": flood["first_wall"],
        "last_wall": flood["last_wall"],
    }


def flood_text(flood: dict) -> str:
    """One line for `sil.flood` (flood_outcome, or the publisher's exit when it sent nothing)."""
    if "sent" not in flood:
        return f"flood: none sent (the publisher exited with {flood['returncode']}: {flood['output'] or 'no output'})"
    sent = sum(sum(kinds.values()) for kinds in flood["sent"].values())
    expected = sum(sum(reasons.values()) for reasons in flood["expected_rejections"].values())
    longest = flood["longest_lateness_during_ms"]
    return (
        f"flood: {sent} malformed messages, {expected} to reject: "
        f"{'every one counted' if flood['every_one_counted'] else 'NOT all counted'} by channel and reason; "
        f"{flood['ticks_during']} ticks during it, {flood['deadline_misses_during']} past the period"
        + (f", the latest {longest:.2f} ms late" if longest is not None else "")
    )


def slow_calls_text(summary: dict, count: int = 5) -> str:
    """Lines for `sil.slow_calls` (SlowCalls.summary): the costliest calls and collections."""
    lines = [
        f"callbacks over {summary['threshold_ms']:.1f} ms of CPU: {summary['calls_over_threshold']}; "
        f"collections over it: {summary['collections_over_threshold']}"
    ]
    for call in summary["costliest_calls"][:count]:
        lines.append(
            f"  t = {call['t']:.3f} s  {call['callback']}: {call['cpu_ms']:.2f} ms CPU, {call['wall_ms']:.2f} ms wall, "
            f"{call['page_faults']} page faults"
        )
    for collection in summary["longest_collections"][:count]:
        when = "while building" if collection["t"] is None else f"t = {collection['t']:.3f} s"
        lines.append(f"  {when}  collection of generation {collection['generation']}: {collection['wall_ms']:.2f} ms")
    return "\n".join(lines)


def _run_controller_program(mission: str, scenario_name: str, text: str, url: str, out_dir: Path) -> dict:
    """`python run_sim.py --hardware` on the bridge's bus, as the README's second terminal; its result.json.

    `text` is the user's scenario text; the bus (`url`) is merged into it, as the bridge got it."""
    settings = yaml_load(data=text) or {}
    buses = dict(settings.get("lcm_buses") or {})
    buses["go1"] = {"lcm_url": url}
    settings.update({"lcm_buses": buses, "controller": "whole_body", "estimator": "kalman"})
    command = [sys.executable, str(RUN_SIM), "--hardware", "--mission", mission, "--scenario_name", scenario_name]
    # JSON is YAML: the merged settings as run_sim.py's one --scenario_text.
    command += ["--scenario_text", json.dumps(settings), "--out", str(out_dir)]
    completed = subprocess.run(command, capture_output=True, text=True)
    result_file = out_dir / "result.json"
    if not result_file.is_file():
        raise RuntimeError(
            f"run_sim.py --hardware exited with {completed.returncode} without a result.json:\n"
            f"{(completed.stdout + completed.stderr).strip()[-2000:]}"
        )
    return json.loads(result_file.read_text())


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--mission", default="hit_target_front")
    parser.add_argument("--scenario_name", default="default", help="scenario of both sides, e.g. control_250hz")
    parser.add_argument("--scenario_text", default="{}", help="YAML mapping merged onto both sides' scenario")
    parser.add_argument("--lcm_url", default=None, help="default: the Go1 group on a port of this process's own")
    parser.add_argument("--out", default=None)
    parser.add_argument("--realtime_rate", type=float, default=1.0, help="< 1: both processes in slow motion")
    parser.add_argument(
        "--separate", action="store_true", help="the controller as its own program, run_sim.py --hardware (README)"
    )
    parser.add_argument("--operator_log", default=None, help="LCM log of operator messages, played by an operator")
    parser.add_argument(
        "--operator_script", default=None, help="teleop_lcm script, played from the robot's offer of a foot"
    )
    parser.add_argument("--operator_leg", choices=robot.LEG_NAMES, default="FR", help="the foot the script waits for")
    parser.add_argument(
        "--operator_search_button", type=float, default=None, help="an operator that finds an E-stop by touch [deg]"
    )
    parser.add_argument(
        "--callbacks", action="store_true", help="record the controller side's callbacks over 1 ms of CPU time"
    )
    parser.add_argument("--pin", action="store_true", help="the bridge on the last CPU, the controller on the others")
    parser.add_argument(
        "--flood_at", type=float, default=None, help="flood malformed status this long after the first command [s]"
    )
    parser.add_argument("--flood_duration", type=float, default=1.0, help="of the flood [s]")
    parser.add_argument("--flood_rate", type=float, default=500.0, help="of the flood, per channel and kind [1/s]")
    parser.add_argument("--robot", choices=sorted(BRIDGES), default="drake", help="the robot side's physics engine")
    args = parser.parse_args()
    out_dir = Path(args.out or f"out/sil_{Path(args.mission).stem}")
    try:
        options = {
            "scenario_name": args.scenario_name,
            "separate": args.separate,
            "operator_log": args.operator_log,
            "operator_script": args.operator_script,
            "operator_leg": args.operator_leg,
            "operator_search_button": args.operator_search_button,
            "callbacks": args.callbacks,
            "pin": args.pin,
            "flood_at": args.flood_at,
            "flood_duration": args.flood_duration,
            "flood_rate": args.flood_rate,
            "robot": args.robot,
        }
        result = run_sil(args.mission, out_dir, args.scenario_text, args.lcm_url, args.realtime_rate, **options)
    except ConfigError as error:
        print(f"error: {error}", file=sys.stderr)
        return 2
    print(
        f"{args.mission} over {result['sil']['lcm_url']}: {'succeeded' if result['success'] else 'FAILED'}"
        f" {result['reason']}; wall {result['wall_time_s']:.1f} s"
    )
    print(f"{'phase':<20}{'leg':<5}{'true error [mm]':>16}{'estimated [mm]':>16}")
    for row in result["sil"]["foot_errors"]:
        estimated = row["estimated_error_m"]
        print(
            f"{row['phase']:<20}{row['leg']:<5}{1000 * row['true_error_m']:16.1f}"
            f"{(1000 * estimated if estimated is not None else float('nan')):16.1f}"
        )
    for row in result["sil"]["touches"]:
        print(
            f"touch {row['phase']:<20}{row['leg']:<5}{row['object']:<16}largest normal force "
            f"{row['max_normal_force_n']:.1f} N (need {row['required_force_n']:.1f}): "
            f"{'touched' if row['touched'] else 'NOT touched'}"
        )
    checks = result["sil"]["truth_checks"]
    for row in checks.get("walks", []):
        if "goal_error_m" in row:
            print(
                f"walk {row['phase']:<20}true distance from its goal {100 * row['goal_error_m']:.1f} cm, "
                f"{math.degrees(row['goal_yaw_error_rad']):.1f} deg; largest stance slip "
                f"{1000 * max(row['max_stance_slip_m'].values()):.1f} mm"
            )
    if "object_push" in checks and "moved_m" in checks["object_push"]:
        print(f"{checks['object_push']['object']} moved {100 * checks['object_push']['moved_m']:.1f} cm (truth)")
    if "button_press" in checks:
        press = checks["button_press"]
        print(
            f"{press['button']}: {'pressed' if press.get('pressed') else 'NOT pressed'}, plunger "
            f"{1000 * (press.get('max_travel_m') or 0.0):.1f} mm, "
            f"largest true force {press.get('max_force_n') or 0.0:.1f} N"
        )
    reasons = "; ".join(filter(None, [result["sil"]["touches_reason"], result["sil"]["truth_checks_reason"]]))
    print(
        f"success by truth ({result['sil']['robot']} robot): {'yes' if result['sil']['success_by_truth'] else 'NO'}"
        + (f" ({reasons})" if reasons else "")
    )
    trunk = result["sil"]["estimator_trunk_position_error"]
    print(
        f"estimated trunk position vs truth: max {1000 * trunk['max_m']:.1f} mm, final {1000 * trunk['final_m']:.1f} mm"
    )
    height = result["sil"]["estimator_trunk_height_error"]
    if height["median_m"] is not None:
        print(
            f"estimated trunk height vs truth while standing still (true z > {height['standing_above_m']} m, "
            f"moving vertically under {STILL_SPEED} m/s): median "
            f"{1000 * height['median_m']:.1f} mm, max {1000 * height['max_m']:.1f} mm"
        )
    start = result["sil"]["start"]
    print(
        f"first {1000 * start['window_s']:.0f} ms: largest step of a measured joint "
        f"{1000 * start['largest_joint_step_rad']:.1f} mrad ({start['largest_joint_step_joint']}), "
        f"true trunk sank {1000 * start['true_trunk_sink_m']:.1f} mm; under the bridge's hold before, from "
        f"{1000 * start['true_trunk_height_bridge_start_m']:.1f} to "
        f"{1000 * start['true_trunk_height_loop_start_m']:.1f} mm"
    )
    pace = result["sil"]["bridge_pace"]
    if pace["median_spacing_ms"] is not None:
        print(
            f"bridge: a truth sample every {pace['median_spacing_ms']:.1f} ms of wall time (median; every "
            f"{pace['sample_period_ms']:.0f} ms when on time), {pace['gaps']} gaps over {1000 * BRIDGE_GAP:.0f} ms, "
            f"the longest {pace['longest_gap_ms']:.0f} ms"
        )
    loop = result["driver"]["loop"]
    lateness = loop["lateness_ms"] or {}
    print(
        f"loop: {loop['ticks']} ticks, {loop['deadline_misses_per_1000']:.2f} deadline misses per 1000 "
        f"(longest {loop['longest_miss_ms']:.1f} ms), lateness median {lateness.get('median', 0):.2f} ms, "
        f"max {lateness.get('max', 0):.1f} ms; driver latched: {result['driver']['latched']}"
    )
    stalls = loop["stalls"]
    longest = stalls["longest"][0] if stalls["longest"] else None
    print(
        f"stalls (more than two periods between commands): {stalls['count']}, the loop computing in "
        f"{stalls['computing']} and waiting in {stalls['waiting']}"
        + (
            f"; the longest {longest['gap_ms']:.1f} ms at t = {longest['t']:.3f} s, "
            f"{longest['loop_cpu_ms']:.1f} ms of it computing"
            if longest
            else ""
        )
    )
    print(f"scheduling: controller {loop['scheduling']}, bridge {result['sil']['bridge_scheduling']}")
    if result["sil"].get("cpu_steal_ms") is not None:
        print(f"CPU time the hypervisor took from this machine meanwhile: {result['sil']['cpu_steal_ms']:.0f} ms")
    if "slow_calls" in result["sil"]:
        print(slow_calls_text(result["sil"]["slow_calls"]))
    if "flood" in result["sil"]:
        print(flood_text(result["sil"]["flood"]))
    print(f"wrote {out_dir / 'sil.json'}")
    return 0 if result["success"] else 1


if __name__ == "__main__":
    sys.exit(main())
