"""The simulated haptic device at real time, as a user runs it: `run_sim.py` with an LCM operator in
one process, `python -m pedi_drake.apps.haptic_device` in another, on a UDP bus of their own.
The device's hand pushes the handle forward; the lifted FR foot goes to the wall in front of it
and pushes; the fed-back force pushes the handle back; the hand lets go of the button and the
mission ends by physics with the leg put back."""

import json
import os
import re
import subprocess
import sys
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
# A port of its own per test run; ttl=0 keeps every datagram on this host.
URL = f"udpm://239.255.76.67:{21000 + os.getpid() % 20000}?ttl=0"
SCENARIO = f"{{operator: {{source: lcm}}, lcm_buses: {{go1: {{lcm_url: '{URL}'}}}}}}"


def test_the_device_pushes_the_foot_into_the_wall_and_is_pushed_back(tmp_path):
    run = subprocess.Popen(
        [sys.executable, str(REPO / "run_sim.py"), "--mission", "operator/teleop_foot_wall"]
        + ["--scenario_text", SCENARIO, "--out", str(tmp_path / "run")],
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
    )
    try:
        device = subprocess.run(
            [sys.executable, "-m", "pedi_drake.apps.haptic_device", "--scenario_text", SCENARIO]
            + ["--push_at", "7", "--release_at", "11", "--duration", "12", "--start_on_feedback"],
            capture_output=True,
            text=True,
            timeout=300,
        )
        output, _ = run.communicate(timeout=300)
    finally:
        if run.poll() is None:
            run.kill()
    assert device.returncode == 0, device.stderr
    lines = [line for line in device.stdout.splitlines() if line.startswith("t ")]
    handle = [
        (float(m.group(1)), float(m.group(2)))
        for m in (re.search(r"t\s+([\d.]+) s\s+handle \[\s*([-\d.]+)", line) for line in lines)
        if m
    ]
    rendered = [float(re.search(r"rendered \[\s*([-\d.]+)", line).group(1)) for line in lines]
    print("\n" + "\n".join(lines))
    free = [x for t, x in handle if 8.0 <= t < 9.0]
    pushing = [x for t, x in handle if 10.0 <= t < 11.0]
    assert free and min(free) > 25.0  # mm: the hand's 3 cm, nothing pushing back yet
    assert pushing and max(pushing) < 25.0  # the wall's force, fed back, holds the handle back
    assert min(rendered) < -2.0  # N, along -x: the wall pushes the foot back
    assert run.returncode == 0, output[-3000:]
    result = json.loads((tmp_path / "run" / "result.json").read_text())
    (teleop,) = result["teleop"]
    assert teleop["ended_by"] == "operator" and teleop["max_force_n"] < 17.0
