"""Ctrl-C and SIGTERM end a run cleanly: what ran is judged and written, marked interrupted, exit 130."""

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[1]
ARGS = ("--scenario_name", "stand", "--duration", "2.0")
RESULT_KEYS = ("success", "reason", "interrupted", "interrupt_reason", "phases", "fell", "sim_time_s")


def _start(out: Path, *args: str) -> subprocess.Popen:
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(filter(None, [str(REPO), os.environ.get("PYTHONPATH")])))
    return subprocess.Popen(
        [sys.executable, "run_sim.py", "--out", str(out), *args],
        cwd=REPO,
        env=env,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )


def _stop_after(process: subprocess.Popen, delay: float, signum: int) -> tuple[int, str]:
    deadline = time.monotonic() + delay
    while time.monotonic() < deadline and process.poll() is None:
        time.sleep(0.02)
    if process.poll() is None:
        process.send_signal(signum)
    _, err = process.communicate(timeout=300)
    return process.returncode, err


def test_sigint_at_random_times_always_leaves_a_valid_result_json(tmp_path):
    # The machine's speed varies several-fold: a run like these, uninterrupted, sets the window.
    start = time.monotonic()
    code, err = _stop_after(_start(tmp_path / "reference", *ARGS), 600.0, signal.SIGINT)
    lifetime = time.monotonic() - start
    assert code == 0, err
    # From half a second in (the stop handlers are loaded first) to the end of a run, one random
    # time in each third of it: the signal lands while loading or building, simulating, and
    # judging or writing.
    thirds = (np.arange(3) + np.random.default_rng(7).uniform(size=3)) / 3.0
    delays = 0.5 + (lifetime - 0.5) * thirds
    interrupted = 0
    for k, delay in enumerate(delays):
        out = tmp_path / f"run{k}"
        code, err = _stop_after(_start(out, *ARGS), delay, signal.SIGINT)
        assert "Traceback" not in err, f"SIGINT after {delay:.1f} s: {err}"
        result = json.loads((out / "result.json").read_text())  # valid JSON, every time
        for key in RESULT_KEYS:
            assert key in result, key
        if result["interrupted"]:
            interrupted += 1
            assert code == 130, (delay, code, err)
            assert result["success"] is False and "SIGINT" in result["reason"]
            assert result["interrupt_reason"] == "SIGINT received"
        else:
            # The run ended before the signal: 0 or 1 by its result. A signal that lands while the
            # interpreter shuts down (its handlers already given back) ends the process as Ctrl-C
            # does by default; by then result.json is complete and says what happened.
            assert code in (0, 1, -signal.SIGINT), (delay, code, err)
        for name in ("logs.npz", "joint_positions.png", "foot_forces.png", "replay.html"):
            assert (out / name).stat().st_size > 0, name
    assert interrupted >= 1, f"no run was interrupted (delays {np.round(delays, 1).tolist()} s)"


def test_sigterm_mid_simulation_writes_what_ran_and_exits_130(tmp_path):
    out = tmp_path / "run"
    process = _start(out, "--scenario_name", "stand", "--duration", "30")
    # Wait for the simulation to be under way (its first progress line), then stop it.
    for line in process.stdout:
        if line.strip().startswith("t ="):
            break
    process.send_signal(signal.SIGTERM)
    _, err = process.communicate(timeout=300)
    assert process.returncode == 130, err
    result = json.loads((out / "result.json").read_text())
    assert result["interrupted"] is True and result["interrupt_reason"] == "SIGTERM received"
    assert 2.0 <= result["sim_time_s"] < 30.0
    from pedi_drake.run_logs import read_run_logs

    logs = read_run_logs(out)
    assert abs(logs["base_state"].times[-1] - result["sim_time_s"]) < 0.01  # the logs hold what ran


def test_a_second_signal_aborts_and_gives_back_the_previous_handlers():
    import pytest

    from pedi_drake.runtime.interrupt import StopRequest

    before = signal.getsignal(signal.SIGINT)
    stop = StopRequest().install()
    try:
        os.kill(os.getpid(), signal.SIGINT)
        time.sleep(0.05)  # the handler runs between bytecodes of this thread
        assert stop.reason == "SIGINT received"
        with pytest.raises(KeyboardInterrupt):
            os.kill(os.getpid(), signal.SIGINT)
            time.sleep(0.05)
        assert signal.getsignal(signal.SIGINT) is before
    finally:
        stop.restore()
