"""result.json: a finished run's result, written as strict JSON (the keys are listed in docs/results.md).

Numbers are written at the resolution they mean something at: times (`t_start`, `t_end`,
`sim_time_s`) on the control period's grid, lengths (keys ending in `_m`, and everything inside
them) to 0.1 mm, so that 2.0100000000000002 s is written 2.01 s and a foot error 0.0034 m.
"""

import json
import math
import os
from pathlib import Path

import numpy as np

TIME_KEYS = ("t_start", "t_end", "sim_time_s")
LENGTH_DECIMALS = 4  # [m]: 0.1 mm
# Digits kept after snapping a time to the control grid: removes the binary noise of k * period.
TIME_DECIMALS = 9


def _is_length_key(key: str) -> bool:
    return key.endswith("_m")


def rounded_result(result: dict, time_step: float | None = None) -> dict:
    """`result` with times snapped to multiples of `time_step` [s] (when given), lengths to 0.1 mm,
    numpy scalars as Python numbers and non-finite numbers as None (null)."""

    def clean(value, key: str, length: bool):
        if isinstance(value, dict):
            return {k: clean(v, k, length or _is_length_key(k)) for k, v in value.items()}
        if isinstance(value, list | tuple):
            return [clean(v, key, length) for v in value]
        if isinstance(value, np.generic):
            value = value.item()
        if isinstance(value, bool) or not isinstance(value, float):
            return value
        if not math.isfinite(value):
            return None
        if key in TIME_KEYS:
            if time_step:
                value = round(value / time_step) * time_step
            return round(value, TIME_DECIMALS)
        if length:
            return round(value, LENGTH_DECIMALS)
        return value

    return clean(result, "", False)


def write_result(out_dir: Path, result: dict, time_step: float | None = None) -> Path:
    """Writes `result` (see `rounded_result`) as out_dir/result.json.

    The file is written beside and then renamed into place, so a reader (or a run stopped while
    writing) never sees half a result.json.
    """
    path = Path(out_dir) / "result.json"
    partial = path.with_name(".result.json.partial")
    partial.write_text(json.dumps(rounded_result(result, time_step), indent=2, allow_nan=False) + "\n")
    os.replace(partial, path)
    return path
