"""result.json's `live_suf`: the live SUF along a run's lifted-leg phases, from the logged `mission.suf`.

The log samples the live SUF's state output every control tick; each update of the live SUF
(pedi_drake.suf.live_suf_system) appears once as the sample where its `updates` counter rose, and
only updates with a lifted foot count. Per phase that had any: the number of updates, how many
were exact and how many used the single-direction SUF instead (the exact projection did not
finish within its budget), and the SUF's smallest, median and largest value [N] with the time of
the smallest. The whole run's figures are the same over every such update.
"""

import numpy as np

from pedi_drake.suf.live import SUF_SIZE, LiveSufReading
from pedi_drake.suf.warm_projection import EXACT, INCOMPLETE, STATUS_NAMES


def update_samples(times: np.ndarray, data: np.ndarray) -> tuple[np.ndarray, list[LiveSufReading]]:
    """(times [s], readings) of every live SUF update with a lifted foot in a `mission.suf` log
    (SUF_SIZE rows)."""
    if data.shape[0] != SUF_SIZE or data.shape[1] == 0:
        return np.zeros(0), []
    counter = data[12]  # `updates`: the updates with a lifted foot so far
    new = np.flatnonzero(np.diff(np.concatenate([[0.0], counter])) > 0.5)
    return times[new], [LiveSufReading.from_vector(data[:, k]) for k in new]


def _figures(readings: list[LiveSufReading], times: np.ndarray) -> dict:
    values = np.array([r.value for r in readings], float)
    finite = np.isfinite(values)
    exact = sum(r.status == EXACT for r in readings)
    fallbacks = sum(r.status == INCOMPLETE for r in readings)
    figures = {
        "updates": len(readings),
        "exact": int(exact),
        "fallbacks": int(fallbacks),
        "fallback_share": fallbacks / len(readings) if readings else None,
        "other": {
            STATUS_NAMES[s]: sum(r.status == s for r in readings)
            for s in sorted({r.status for r in readings} - {EXACT, INCOMPLETE})
            if s in STATUS_NAMES
        },
        "min_n": None,
        "median_n": None,
        "max_n": None,
        "min_at_s": None,
    }
    if finite.any():
        k = int(np.nanargmin(np.where(finite, values, np.nan)))
        figures.update(
            min_n=float(values[k]),
            median_n=float(np.median(values[finite])),
            max_n=float(np.max(values[finite])),
            min_at_s=float(times[k]),
        )
    return figures


def live_suf_summary(times: np.ndarray, data: np.ndarray, phases: list[dict]) -> dict | None:
    """The `live_suf` entry of result.json (see the module docstring); None without any update."""
    t, readings = update_samples(times, data)
    if not readings:
        return None
    summary = _figures(readings, t)
    summary["lps_median"] = float(np.median([r.lps for r in readings]))
    summary["lps_max"] = int(max(r.lps for r in readings))
    # Control ticks from an update's start to its publication, that one included.
    summary["ticks_median"] = float(np.median([r.slices for r in readings]))
    summary["ticks_max"] = int(max(r.slices for r in readings))
    rows = []
    for phase in phases:
        if phase["status"] == "skipped" or phase["t_start"] is None:
            continue
        end = np.inf if phase["t_end"] is None else phase["t_end"]
        inside = [k for k in range(len(t)) if phase["t_start"] <= t[k] < end]
        if inside:
            row = {"phase": phase["name"], "kind": phase["kind"]}
            row.update(_figures([readings[k] for k in inside], t[inside]))
            rows.append(row)
    summary["phases"] = rows
    return summary
