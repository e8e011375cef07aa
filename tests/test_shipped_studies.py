"""Every study shipped in studies/ loads: its missions, scenarios and seeds resolve to tasks.

Apart from tests/test_batch.py, whose runs judge wall-clock behaviour and run alone: loading
builds no engine and may share the machine.
"""

from pathlib import Path

import pytest

from pedi_drake.batch.study import load_study

REPO = Path(__file__).resolve().parents[1]


@pytest.mark.parametrize("path", sorted((REPO / "studies").glob("*.yaml")), ids=lambda path: path.stem)
def test_a_shipped_study_loads(path):
    assert load_study(path).tasks, path
