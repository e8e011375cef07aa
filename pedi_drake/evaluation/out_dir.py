"""A run's output folder: the files a run owns there, and the claim that makes it the only writer.

A run writes into a folder that may hold a previous run's files. Leaving them would put an old
plot beside a new result.json (a run without a mission writes no leg_tracking.png), so a run
first removes every file it owns, and only those: anything else in the folder is the user's.
Two runs writing into one folder would interleave their files; an exclusive lock on
`.run.lock` in the folder (held until the run's last file is written, released by the kernel
even when the process dies) makes the second run stop before it builds anything.
"""

import contextlib
import errno
import fcntl
import os
from collections.abc import Iterator
from pathlib import Path

from pedi_drake.exceptions import ScenarioError

LOCK_FILE = ".run.lock"
# Every file a run (run_sim.py, apps.sil) writes into its output folder.
OWNED_FILES = (
    "result.json",
    "replay.html",
    "logs.npz",
    "error.txt",
    "joint_positions.png",
    "foot_forces.png",
    "leg_tracking.png",
    "leg_command.png",
    "mission_errors.png",
    "live_suf.png",
    "sil.json",
    "bridge_truth.npz",
    "flood.json",
)


@contextlib.contextmanager
def claim_out_dir(out_dir: Path, where: str = "--out") -> Iterator[Path]:
    """Makes `out_dir`, locks it against other runs and removes the files a run owns in it.

    Raises ScenarioError (naming `where`) when the folder cannot be made or another run holds it.
    """
    out_dir = Path(out_dir)
    try:
        out_dir.mkdir(parents=True, exist_ok=True)
        handle = open(out_dir / LOCK_FILE, "a+")  # noqa: SIM115 (held open for the whole run)
    except OSError as error:
        raise ScenarioError(f"{where}: cannot write into {out_dir}: {error.strerror}") from None
    with handle:
        try:
            fcntl.flock(handle, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError as error:
            if error.errno not in (errno.EAGAIN, errno.EACCES):
                raise
            handle.seek(0)
            holder = handle.read().strip() or "unknown"
            raise ScenarioError(
                f"{where}: another run (process {holder}) is writing into {out_dir}; wait for it or give another folder"
            ) from None
        handle.seek(0)
        handle.truncate()
        handle.write(f"{os.getpid()}\n")
        handle.flush()
        for name in OWNED_FILES:
            (out_dir / name).unlink(missing_ok=True)
        try:
            yield out_dir
        finally:
            fcntl.flock(handle, fcntl.LOCK_UN)
