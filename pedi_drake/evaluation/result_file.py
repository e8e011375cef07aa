"""result.json: a finished run's result, written as strict JSON (the keys are listed in docs/results.md)."""

import json
import math
from pathlib import Path

import numpy as np


def write_result(out_dir: Path, result: dict) -> Path:
    """Writes `result` as out_dir/result.json; non-finite numbers become null (valid JSON)."""

    def clean(value):
        if isinstance(value, dict):
            return {k: clean(v) for k, v in value.items()}
        if isinstance(value, list | tuple):
            return [clean(v) for v in value]
        if isinstance(value, np.generic):
            value = value.item()
        if isinstance(value, float) and not math.isfinite(value):
            return None
        return value

    path = Path(out_dir) / "result.json"
    path.write_text(json.dumps(clean(result), indent=2, allow_nan=False) + "\n")
    return path
