"""Shared fixtures. Tests are seeded and deterministic."""

import os

# Plots render off screen in tests; the package itself leaves the backend to the user.
os.environ.setdefault("MPLBACKEND", "Agg")

import numpy as np  # noqa: E402 (the backend must be chosen before matplotlib is imported)
import pytest

from pedi_drake import robot  # noqa: E402
from pedi_drake.mission import phases, spec  # noqa: E402

# Tests that judge wall-clock behaviour (real-time bridges, watchdogs, signals at chosen moments)
# or use every core themselves (a local Ray, a browser): `.ci/run` runs them on their own after
# the rest has run on parallel workers, so a neighbour's load cannot make them miss a deadline.
WALL_CLOCK_MODULES = {
    "test_go1_link",
    "test_sim_bridge",
    "test_hardware_station",
    "test_run_interrupt",
    "test_batch",
    "test_replay_browser",
    "test_meshcat_teleop_browser",
    "test_haptic_device_app",
}


def pytest_collection_modifyitems(config, items) -> None:
    for item in items:
        if item.module.__name__.rsplit(".", 1)[-1] in WALL_CLOCK_MODULES:
            item.add_marker(pytest.mark.wall_clock)


@pytest.fixture
def rng() -> np.random.Generator:
    """A fresh seeded generator per test."""
    return np.random.default_rng(20261122)


@pytest.fixture(scope="session")
def go1_plant():
    """(plant, Go1PlantMap) of the Go1 without prongs and without geometry; read-only."""
    return robot.make_go1_plant()


@pytest.fixture
def execute_notebook(tmp_path, monkeypatch):
    """Runs notebooks/<name> headless in a copy under tmp_path; returns its code cells' outputs.

    The kernel imports this checkout (PYTHONPATH) and renders figures inline, so tests can count
    the PNGs a notebook shows.
    """
    import shutil
    from pathlib import Path

    import nbformat
    from nbclient import NotebookClient

    repo = Path(__file__).resolve().parents[1]
    monkeypatch.setenv("PYTHONPATH", os.pathsep.join(filter(None, [str(repo), os.environ.get("PYTHONPATH")])))
    monkeypatch.delenv("MPLBACKEND", raising=False)

    def execute(name: str, timeout: float = 300.0) -> list:
        path = tmp_path / name
        shutil.copy(repo / "notebooks" / name, path)
        nb = nbformat.read(path, as_version=4)
        resources = {"metadata": {"path": str(tmp_path)}}
        NotebookClient(nb, kernel_name="python3", timeout=timeout, resources=resources).execute()
        return [o for cell in nb.cells if cell.cell_type == "code" for o in cell.outputs]

    return execute


@pytest.fixture
def phase_tables_restored():
    """The phase kind and runner tables (mission.spec.PHASE_KINDS, mission.phases.RUNNERS) as they
    were before the test, whatever it registered."""
    kinds, runners = dict(spec.PHASE_KINDS), dict(phases.RUNNERS)
    yield
    spec.PHASE_KINDS.clear()
    spec.PHASE_KINDS.update(kinds)
    phases.RUNNERS.clear()
    phases.RUNNERS.update(runners)


@pytest.fixture(scope="session")
def made_once(tmp_path_factory):
    """`made_once(name, make)`: the folder `make(folder)` filled, made once per test run however
    many test workers ask for it (a worker that asks while another makes it waits, then reads it).

    For a long simulation whose results several tests of a module read: test workers that share a
    module between them would otherwise each run it."""
    import fcntl

    # The test run's folder: under pytest-xdist each worker's own is a subfolder of it.
    base = tmp_path_factory.getbasetemp()
    shared = base.parent if os.environ.get("PYTEST_XDIST_WORKER") else base

    def get(name: str, make):
        folder = shared / name
        with open(shared / f"{name}.lock", "a") as lock:
            fcntl.flock(lock, fcntl.LOCK_EX)
            done = folder / ".made"
            if not done.exists():
                folder.mkdir(exist_ok=True)
                make(folder)
                done.touch()
        return folder

    return get
