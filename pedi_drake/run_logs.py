"""The logged signals of a run, saved beside result.json as logs.npz and read back for analysis.

`run()` writes every logged signal (the plots come from the same logs): the go1.* station
signals, the command, the base-state estimate, the controller diagnostics, the mission status
and references, and in simulation the plant state, the applied motor torques and the pushes
(`sim.*`: ground truth, for evaluation only). Samples are stored as float32 (about 7
significant digits, plenty for plots and statistics; signals beyond 1e6, such as the wall
clock, as float64) and compressed, so a 25 s mission at 500 Hz takes a few megabytes.

    logs = read_run_logs("out/hit_target_front")
    t, tau = logs["go1.command"].times, logs["go1.command"].data[48:60]
"""

import dataclasses
from pathlib import Path

import numpy as np

LOGS_FILE = "logs.npz"


@dataclasses.dataclass(frozen=True)
class SignalLog:
    """One logged signal: sample times (N,) [s] and samples as columns (size, N)."""

    times: np.ndarray
    data: np.ndarray


def write_run_logs(out_dir: Path, logs: dict[str, SignalLog]) -> Path:
    """Writes `logs` to out_dir/logs.npz (keys `<signal>/times` and `<signal>/data`)."""
    arrays = {}
    for name, log in logs.items():
        arrays[f"{name}/times"] = np.asarray(log.times, dtype=np.float64)
        data = np.asarray(log.data, dtype=np.float64)
        # float32 keeps 7 digits: plenty for every signal but clocks (1.8e9 s since the epoch).
        exact = data.size and np.max(np.abs(data)) > 1e6
        arrays[f"{name}/data"] = data if exact else data.astype(np.float32)
    path = Path(out_dir) / LOGS_FILE
    np.savez_compressed(path, **arrays)
    return path


def read_run_logs(out_dir: str | Path) -> dict[str, SignalLog]:
    """The logs a run wrote to `out_dir` (or the logs.npz file itself), by signal name."""
    path = Path(out_dir)
    if path.is_dir():
        path = path / LOGS_FILE
    if not path.exists():
        raise FileNotFoundError(f"{path}: no run logs here (run_sim.py writes them to its --out folder)")
    with np.load(path) as archive:
        names = sorted({key.rsplit("/", 1)[0] for key in archive.files})
        return {name: SignalLog(archive[f"{name}/times"], archive[f"{name}/data"]) for name in names}
