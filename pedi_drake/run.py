"""One run of a scenario or mission: `simulate` builds and runs the diagram and keeps what it did;
`pedi_drake.evaluation.judge` judges that record and writes the results.

`run(scenario=..., name=..., out_dir=...)` does both; it is what run_sim.py, the mission
benchmark, the tests and the notebooks call. It writes result.json (keys: docs/results.md),
replay.html, PNG plots and the logged signals (logs.npz, read back with
`pedi_drake.run_logs.read_run_logs`).
"""

import contextlib
import dataclasses
import shutil
import sys
import time
from collections.abc import Callable
from pathlib import Path

from pydrake.geometry import Meshcat, MeshcatAnimation
from pydrake.lcm import DrakeLcm
from pydrake.systems.analysis import Simulator
from pydrake.systems.framework import Context, DiagramBuilder, EventStatus

from pedi_drake.diagram import MakePedipulationDiagram, PedipulationDiagram, apply_mission
from pedi_drake.evaluation.judge import judge_run, write_run
from pedi_drake.evaluation.out_dir import claim_out_dir
from pedi_drake.go1_driver.hardware_run import hardware_run
from pedi_drake.go1_driver.pacing import SpinPacedMonitor
from pedi_drake.mission.progress import FAILED, RUNNING, SUCCEEDED, MissionProgress
from pedi_drake.operator.message_stream import TimedMessage
from pedi_drake.run_logs import SignalLog
from pedi_drake.runtime.interrupt import StopRequest
from pedi_drake.scenario import Scenario
from pedi_drake.viz.meshcat_camera import frame_scene

SETTLE_AFTER_MISSION = 0.5  # [s] simulated after the mission ends, then the run stops
PROGRESS_EVERY = 2.0  # [s] of simulated time between progress lines (not on a terminal)
BAR_EVERY = 0.25  # [s] of wall time between redraws of the progress bar (on a terminal)
BAR_WIDTH = 24  # [characters] of the progress bar
MONITOR_PERIOD = 0.005  # [s] between looks at the mission's status (it changes at 100 Hz)


@dataclasses.dataclass
class RunRecord:
    """What a finished run did: the diagram and its final context, the logs, the clocks."""

    scenario: Scenario
    name: str
    hardware: bool
    built: PedipulationDiagram
    context: Context  # the root context at the end of the run
    logs: dict[str, SignalLog]  # by signal name (see diagram.LOGGED_SIGNALS)
    sim_time: float  # [s]
    wall_time: float  # [s]
    replay_html: str | None  # the Meshcat replay, when one was recorded
    # Why the run was stopped before its end (a signal), or None when it ran its course.
    interrupted: str | None = None

    def subsystem(self, name: str):
        """(system, its context) of the diagram's subsystem `name`."""
        system = self.built.diagram.GetSubsystemByName(name)
        return system, system.GetMyContextFromRoot(self.context)

    def mission_progress(self) -> MissionProgress | None:
        """The mission manager's progress at the end of the run (None without a mission)."""
        if self.built.mission is None:
            return None
        manager, context = self.subsystem("mission")
        return manager.progress(context)


def simulate(
    *,
    scenario: Scenario,
    name: str,
    meshcat: Meshcat | None = None,
    quiet: bool = False,
    hardware: bool = False,
    replay: bool = True,
    realtime_rate: float = 1.0,
    stop: StopRequest | None = None,
    operator_messages: list[TimedMessage] | None = None,
) -> RunRecord:
    """Builds the diagram of `scenario` and advances it until its duration or the mission's end.

    With `hardware=True` the station is the Go1 LCM driver (a Go1, or the simulator bridge in
    another process) and the diagram runs in real time; no replay is recorded then.
    `replay=False` skips the Meshcat recording too (a run without any visualisation).
    `realtime_rate` paces a hardware run (below 1 only against the simulator bridge run at the
    same rate: a slow-motion run for a machine too slow for both processes in real time), and a
    simulation with an operator.
    `stop`: once its reason is set (by a signal, see `pedi_drake.runtime.interrupt`) the simulation ends at
    the current time and the record says why (`interrupted`).
    `operator_messages`: a scripted operator's stream (pedi_drake.operator.message_stream), played
    in lock step on an in-process bus; the simulation then runs as fast as it can.
    """
    stop = stop or StopRequest()
    if not hardware and replay:
        # A Meshcat is made even when nobody watches live: it records the replay.
        meshcat = meshcat or Meshcat()
    built = MakePedipulationDiagram(scenario, meshcat, hardware=hardware, operator_messages=operator_messages)
    diagram = built.diagram
    simulator = Simulator(diagram)
    built.reserve_logs(simulator.get_mutable_context(), scenario.simulation_duration)
    if hardware or (scenario.operator.source != "none" and operator_messages is None):
        # An operator (a person, a program on LCM) acts on the wall clock: a simulation runs at its pace.
        simulator.set_target_realtime_rate(realtime_rate)
    manager = diagram.GetSubsystemByName("mission") if built.mission is not None else None
    monitor = _MissionMonitor(diagram, manager, built.mission, scenario.simulation_duration, quiet, stop)
    simulator.set_monitor(monitor)
    # On hardware every exit of the loop (its end, a stop request, an exception) leaves damping on the wire.
    with hardware_run(diagram, realtime_rate=realtime_rate) if hardware else contextlib.nullcontext() as link:
        if link is not None and link.config.wait == "spin":
            # The loop busy-waits for its periods (pedi_drake.go1_driver.pacing) instead of the
            # Simulator sleeping to them.
            simulator.set_target_realtime_rate(0.0)
            simulator.set_monitor(SpinPacedMonitor(monitor, realtime_rate, link))
        simulator.Initialize()
        recording = meshcat is not None and not hardware
        if recording:
            # The view opens on the robot and the mission's objects, live and in the replay.
            frame_scene(meshcat, apply_mission(scenario, built.mission) if built.mission else scenario)
            meshcat.StartRecording(set_visualizations_while_recording=False)
        wall_start = time.perf_counter()
        if stop.reason is None:
            simulator.AdvanceTo(scenario.simulation_duration)
        wall_time = time.perf_counter() - wall_start
        monitor.finish()
    replay_html = None
    if recording:
        meshcat.StopRecording()
        # The replay plays on opening, once, and stays on the last frame (where the run ended).
        animation = meshcat.get_mutable_recording()
        animation.set_autoplay(True)
        animation.set_loop_mode(MeshcatAnimation.LoopMode.kLoopOnce)
        animation.set_clamp_when_finished(True)
        meshcat.PublishRecording()
        replay_html = meshcat.StaticHtml()
    context = simulator.get_context()
    logs = built.logs(context)
    return RunRecord(
        scenario=scenario,
        name=name,
        hardware=hardware,
        built=built,
        context=context,
        logs=logs,
        sim_time=float(context.get_time()),
        wall_time=wall_time,
        replay_html=replay_html,
        interrupted=stop.reason,
    )


def simulate_with_operator(
    scenario: Scenario, make_operator: Callable, name: str, *, end_with_mission: bool = False
) -> RunRecord:
    """A lock-step run of `scenario` (its operator.source: lcm) with an operator program in the same
    diagram, on an in-process LCM bus: `make_operator(lcm)` returns the operator's system (a
    ScriptedOperator, say). For benchmarks and tests that play an operator without a wall clock.
    It runs to the scenario's simulation_duration or, with `end_with_mission`, until shortly after
    the mission ends (as `simulate` does)."""
    lcm = DrakeLcm("memq://")
    built = MakePedipulationDiagram(scenario, operator_lcm=lcm)
    builder = DiagramBuilder()
    builder.AddSystem(built.diagram)
    builder.AddSystem(make_operator(lcm))
    diagram = builder.Build()
    simulator = Simulator(diagram)
    end = scenario.simulation_duration
    built.reserve_logs(simulator.get_mutable_context(), end)
    if end_with_mission and built.mission is not None:
        manager = built.diagram.GetSubsystemByName("mission")
        simulator.set_monitor(_MissionMonitor(diagram, manager, built.mission, end, True, StopRequest()))
    simulator.Initialize()
    start = time.perf_counter()
    simulator.AdvanceTo(end)
    context = simulator.get_context()
    return RunRecord(
        scenario=scenario,
        name=name,
        hardware=False,
        built=built,
        context=context,
        logs=built.logs(context),
        sim_time=float(context.get_time()),
        wall_time=time.perf_counter() - start,
        replay_html=None,
    )


class _MissionMonitor:
    """The simulator's monitor: shows progress, ends the run once the mission has settled, and
    ends it at once when a stop is requested.

    On a terminal the progress is one redrawn bar (sim time, phase, real-time factor); otherwise
    (a log file, a pipe) it is a plain line every PROGRESS_EVERY of simulated time.
    """

    def __init__(self, diagram, manager, mission, duration: float, quiet: bool, stop: StopRequest):
        self._diagram, self._manager, self._mission, self._duration = diagram, manager, mission, duration
        self._quiet, self._stop = quiet, stop
        self._bar = not quiet and sys.stdout.isatty()
        self._next_print, self._next_check, self._ended = PROGRESS_EVERY, 0.0, None
        self._wall_start, self._next_bar = time.perf_counter(), 0.0

    def __call__(self, root_context) -> EventStatus:
        if self._stop.reason is not None:
            return EventStatus.ReachedTermination(self._diagram, f"stopped: {self._stop.reason}")
        t = root_context.get_time()
        # The mission's status changes only at the manager's updates: no need to look every step.
        if t < self._next_check:
            return EventStatus.Succeeded()
        self._next_check = t + MONITOR_PERIOD
        manager = self._manager
        progress = manager.progress(manager.GetMyContextFromRoot(root_context)) if manager else None
        if self._bar:
            wall = time.perf_counter() - self._wall_start
            if wall >= self._next_bar:
                self._next_bar = wall + BAR_EVERY
                self._draw_bar(t, wall, progress)
        elif not self._quiet and t >= self._next_print:
            self._next_print += PROGRESS_EVERY
            print(f"  t = {t:5.1f} s" + (f"  {phase_label(progress, self._mission)}" if progress else ""), flush=True)
        if progress is not None and progress.status in (SUCCEEDED, FAILED):
            self._ended = self._ended if self._ended is not None else t
            if t >= self._ended + SETTLE_AFTER_MISSION:
                return EventStatus.ReachedTermination(self._diagram, "mission over")
        return EventStatus.Succeeded()

    def _draw_bar(self, t: float, wall: float, progress) -> None:
        filled = int(BAR_WIDTH * min(1.0, t / self._duration)) if self._duration > 0 else BAR_WIDTH
        bar = "#" * filled + "-" * (BAR_WIDTH - filled)
        rate = f"{t / wall:4.2f}x real time" if wall > 0 else ""
        phase = f"  {phase_label(progress, self._mission)}" if progress is not None else ""
        columns = shutil.get_terminal_size((100, 20)).columns
        line = f"  [{bar}] {t:5.1f}/{self._duration:.1f} s  {rate}{phase}"
        sys.stdout.write("\r" + line[: columns - 1].ljust(columns - 1))
        sys.stdout.flush()

    def finish(self) -> None:
        """Ends the progress bar's line, so what is printed next starts on its own."""
        if self._bar:
            sys.stdout.write("\n")
            sys.stdout.flush()


def phase_label(progress, mission) -> str:
    """ "phase k/n NAME (status)" for the phase the mission is in: the record being run names it.

    The phase index counts mission phases; between a phase's end and the next one's start the
    index has already moved on while the last record is still the finished phase, so the
    number shown is the record's own place in the mission (recovery phases are labelled so).
    """
    if not progress.records:
        return f"phase -/{len(mission.phases)} ({progress.status})"
    record = progress.records[-1]
    names = [phase.name for phase in mission.phases]
    if progress.status == RUNNING and record.name in names:
        number = f"{names.index(record.name) + 1}/{len(names)}"
    elif progress.status in (SUCCEEDED, FAILED):
        number = "done"
    else:
        number = "recovery"
    return f"phase {number} {record.name} ({record.status})"


def run(
    *,
    scenario: Scenario,
    name: str,
    out_dir: Path,
    stop: StopRequest | None = None,
    records: list[RunRecord] | None = None,
    **simulate_options,
) -> dict:
    """`simulate`, then judge the run and write result.json, replay.html, plots and logs.npz to `out_dir`.

    `out_dir` is claimed first (`claim_out_dir`: a lock against a second run, and the files a
    previous run left there removed). Ctrl-C or SIGTERM during the run stop the simulation at the
    current time and what ran is judged and written with `interrupted: true`; pass `stop` to
    install the handlers earlier (run_sim.py does, before pydrake loads). Returns the result (the
    content of result.json). `records`: the RunRecord is appended to it, for a caller that judges
    the logs at their full precision (logs.npz keeps 7 digits). `simulate_options`: see `simulate`.
    """
    own_stop = stop is None
    stop = (stop or StopRequest()).install()
    try:
        with claim_out_dir(Path(out_dir)) as out_dir:
            record = simulate(scenario=scenario, name=name, stop=stop, **simulate_options)
            result = judge_run(record)
            write_run(record, result, out_dir)
            if records is not None:
                records.append(record)
    finally:
        if own_stop:
            stop.restore()
    return result
