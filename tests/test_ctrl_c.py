"""Ctrl-C reaches the programs that stop on KeyboardInterrupt (the bridges, the log recorder) also
when they start with SIGINT ignored, as a non-interactive shell's background jobs and their
children do (pedi_drake.runtime.interrupt.ctrl_c_raises)."""

import subprocess
import sys

import pytest

# A process that starts with SIGINT ignored, then signals itself; prints what happened.
PROGRAM = """
import os, signal, sys, time
signal.signal(signal.SIGINT, signal.SIG_IGN)
if sys.argv[1] == "restore":
    from pedi_drake.runtime.interrupt import ctrl_c_raises
    ctrl_c_raises()
try:
    os.kill(os.getpid(), signal.SIGINT)
    time.sleep(0.5)
    print("ran on")
except KeyboardInterrupt:
    print("interrupted")
"""


@pytest.mark.parametrize(("mode", "outcome"), [("ignored", "ran on"), ("restore", "interrupted")])
def test_ctrl_c_raises_where_sigint_was_ignored(mode, outcome):
    run = subprocess.run([sys.executable, "-c", PROGRAM, mode], capture_output=True, text=True, timeout=60)
    assert run.returncode == 0, run.stderr
    assert run.stdout.strip() == outcome
