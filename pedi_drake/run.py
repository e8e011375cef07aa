"""One run of a scenario or mission: `simulate` builds and runs the diagram and keeps what it did;
`pedi_drake.evaluation.judge` judges that record and writes the results.

`run(scenario=..., name=..., out_dir=...)` does both; it is what run_sim.py, the mission
benchmark, the tests and the notebooks call. It writes result.json (keys: docs/results.md),
replay.html, PNG plots and the logged signals (logs.npz, read back with
`pedi_drake.evaluation.run_logs.read_run_logs`).
"""

import dataclasses
import time
from pathlib import Path

from pydrake.geometry import Meshcat
from pydrake.systems.analysis import Simulator
from pydrake.systems.framework import Context, EventStatus

from pedi_drake.diagram import MakePedipulationDiagram, PedipulationDiagram
from pedi_drake.evaluation.judge import judge_run, write_run
from pedi_drake.evaluation.run_logs import SignalLog
from pedi_drake.mission.progress import FAILED, SUCCEEDED, MissionProgress
from pedi_drake.scenario import Scenario

SETTLE_AFTER_MISSION = 0.5  # [s] simulated after the mission ends, then the run stops
PROGRESS_EVERY = 2.0  # [s] of simulated time between progress lines
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
) -> RunRecord:
    """Builds the diagram of `scenario` and advances it until its duration or the mission's end.

    With `hardware=True` the station is the Go1 LCM driver (a Go1, or the simulator bridge in
    another process) and the diagram runs in real time; no replay is recorded then.
    `replay=False` skips the Meshcat recording too (a run without any visualisation).
    `realtime_rate` paces a hardware run (below 1 only against the simulator bridge run at the
    same rate: a slow-motion run for a machine too slow for both processes in real time).
    """
    if not hardware and replay:
        # A Meshcat is made even when nobody watches live: it records the replay.
        meshcat = meshcat or Meshcat()
    built = MakePedipulationDiagram(scenario, meshcat, hardware=hardware)
    diagram = built.diagram
    simulator = Simulator(diagram)
    if hardware:
        simulator.set_target_realtime_rate(realtime_rate)
    manager = diagram.GetSubsystemByName("mission") if built.mission is not None else None
    monitor = _MissionMonitor(diagram, manager, len(built.mission.phases) if built.mission else 0, quiet)
    simulator.set_monitor(monitor)
    simulator.Initialize()
    recording = meshcat is not None and not hardware
    if recording:
        meshcat.StartRecording(set_visualizations_while_recording=False)
    wall_start = time.perf_counter()
    simulator.AdvanceTo(scenario.simulation_duration)
    wall_time = time.perf_counter() - wall_start
    replay_html = None
    if recording:
        meshcat.StopRecording()
        meshcat.PublishRecording()
        replay_html = meshcat.StaticHtml()
    context = simulator.get_context()
    logs = {}
    for signal, logger in built.loggers.items():
        log = diagram.GetSubsystemByName(logger).FindLog(context)
        logs[signal] = SignalLog(log.sample_times().copy(), log.data().copy())
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
    )


class _MissionMonitor:
    """The simulator's monitor: prints progress and ends the run once the mission has settled."""

    def __init__(self, diagram, manager, num_phases: int, quiet: bool):
        self._diagram, self._manager, self._num_phases, self._quiet = diagram, manager, num_phases, quiet
        self._next_print, self._next_check, self._ended = PROGRESS_EVERY, 0.0, None

    def __call__(self, root_context) -> EventStatus:
        t = root_context.get_time()
        # The mission's status changes only at the manager's updates: no need to look every step.
        if t < self._next_check:
            return EventStatus.Succeeded()
        self._next_check = t + MONITOR_PERIOD
        manager = self._manager
        progress = manager.progress(manager.GetMyContextFromRoot(root_context)) if manager else None
        if not self._quiet and t >= self._next_print:
            self._next_print += PROGRESS_EVERY
            if progress is not None:
                phase = progress.records[-1].name if progress.records else "-"
                print(f"  t = {t:5.1f} s  phase {progress.index + 1}/{self._num_phases} {phase} ({progress.status})")
            else:
                print(f"  t = {t:5.1f} s")
        if progress is not None and progress.status in (SUCCEEDED, FAILED):
            self._ended = self._ended if self._ended is not None else t
            if t >= self._ended + SETTLE_AFTER_MISSION:
                return EventStatus.ReachedTermination(self._diagram, "mission over")
        return EventStatus.Succeeded()


def run(*, scenario: Scenario, name: str, out_dir: Path, **simulate_options) -> dict:
    """`simulate`, then judge the run and write result.json, replay.html, plots and logs.npz to `out_dir`.

    Returns the result (the content of result.json). `simulate_options`: see `simulate`.
    """
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    record = simulate(scenario=scenario, name=name, **simulate_options)
    result = judge_run(record)
    write_run(record, result, out_dir)
    return result
