"""docs/extending.md's Python blocks run, in order, in one namespace: the guide cannot rot.

The blocks add a phase kind (`crouch`) and run it in a short simulated mission, build a task's
rows, check a config's problems, load a scene object from a model of its own,
run an operator source and write a benchmark's JSON and its row. The phase kind the guide
registers is removed again afterwards, so no other test sees it.
"""

import re
from pathlib import Path

from pedi_drake.mission import spec

GUIDE = Path(__file__).resolve().parents[1] / "docs" / "extending.md"


def python_blocks(text: str) -> list[str]:
    """The bodies of the ```python fenced blocks of a Markdown text, in order."""
    return re.findall(r"^```python\n(.*?)^```", text, flags=re.DOTALL | re.MULTILINE)


def test_the_guide_has_a_block_per_extension():
    # A phase kind (two), a mission file, a task, a scenario field (two), a scene object, an
    # operator source and a benchmark.
    assert len(python_blocks(GUIDE.read_text())) == 9


def test_every_python_block_of_the_guide_runs(tmp_path, monkeypatch, phase_tables_restored):
    monkeypatch.chdir(tmp_path)
    namespace = {"__name__": "extending_guide"}
    for k, block in enumerate(python_blocks(GUIDE.read_text())):
        code = compile(block, f"{GUIDE.name}, python block {k}", "exec")
        exec(code, namespace)  # noqa: S102 - the guide's own code, which this test exists to run
    assert "crouch" in spec.PHASE_KINDS
