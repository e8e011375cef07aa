"""No compiled kernel is loaded inside a control tick: the systems and the mission's phases load the
kernels they call as they are built (their `warm_up`s; the phases': pedi_drake.mission.phases.warm_up).

A kernel first called in a tick is loaded from the disk cache (or compiled) there, and on a hardware
run that tick is late by the load. Each case is a short mission from standing that reaches the
phase code calling kernels from Python: a trot, a static walk, a foot held with its calf's rotation,
a guarded touch. They run in a fresh process (a test before them in this one may have loaded the
kernels already); every diagram is built first, then each is simulated, and the package's kernels
that gained an argument signature meanwhile are reported.
"""

import json
import subprocess
import sys
from pathlib import Path

import pytest

from pedi_drake.runtime import jit

REPO = Path(__file__).resolve().parents[1]

SIMULATE_AND_REPORT = """
import json, sys
import numba
from pydrake.systems.analysis import Simulator
from pedi_drake.diagram import MakePedipulationDiagram
from pedi_drake.scenario import load_scenario

def signatures():
    counts = {}
    for name, module in list(sys.modules.items()):
        if name.startswith("pedi_drake"):
            for value in vars(module).values():
                if isinstance(value, numba.core.registry.CPUDispatcher):
                    counts[value.py_func.__module__ + "." + value.py_func.__name__] = len(value.signatures)
    return counts

runs = []
for mission, duration in zip(sys.argv[1::2], sys.argv[2::2]):
    scenario = load_scenario(scenario_text="{robot: {initial_pose: standing}}")
    scenario.mission = mission
    simulator = Simulator(MakePedipulationDiagram(scenario).diagram)
    simulator.Initialize()
    runs.append((simulator, float(duration)))
loaded = []
for simulator, duration in runs:
    before = signatures()
    simulator.AdvanceTo(duration)
    loaded.append(sorted(name for name, count in signatures().items() if count != before.get(name)))
print(json.dumps(loaded))
"""

# (mission text, simulated time [s]): each long enough to run the phase code it is there for. The
# trot goes first: the static walk calls what the trot calls, and more.
CASES = {
    "trot": (
        "contact_ramp_time: 0.02\nphases:\n"
        "  - {kind: walk_velocity, twist: [0.3, 0.0, 0.0], duration: 0.6, gait: trot}\n",
        1.2,
    ),
    "static walk": (
        "contact_ramp_time: 0.06\nphases:\n  - {kind: walk_velocity, twist: [0.1, 0.0, 0.0], duration: 1.0}\n",
        2.5,
    ),
    "calf held": (
        "phases:\n  - {kind: leg_to_pedipulation, leg: FL}\n"
        "  - {kind: hold_foot_pose, leg: FL, orientation: true, duration: 0.2}\n",
        4.0,
    ),
    "guarded touch": (
        "scene:\n  - {kind: target_panel, position: [0.47, -0.13, 0.0], yaw: 3.14159}\nphases:\n"
        "  - {kind: leg_to_pedipulation, leg: FR}\n"
        "  - {kind: reach, leg: FR, target: [0.447, -0.13, 0.20], approach_offset: [-0.05, 0.0, 0.0],\n"
        "     touch: {force: 3.0, over_travel: 0.02}}\n",
        5.0,
    ),
}


@pytest.mark.skipif(not jit.ENABLED, reason="PEDI_DRAKE_JIT=0")
def test_no_kernel_is_loaded_inside_a_tick(tmp_path):
    args = []
    for k, (text, duration) in enumerate(CASES.values()):
        path = tmp_path / f"case{k}.yaml"
        path.write_text("description: A short mission from standing.\n" + text)
        args += [str(path), str(duration)]
    run = subprocess.run(
        [sys.executable, "-c", SIMULATE_AND_REPORT, *args], cwd=REPO, capture_output=True, text=True, timeout=600
    )
    assert run.returncode == 0, run.stderr[-2000:]
    loaded = json.loads(run.stdout.strip().splitlines()[-1])
    assert dict(zip(CASES, loaded, strict=True)) == {name: [] for name in CASES}
