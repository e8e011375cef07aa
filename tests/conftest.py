"""Shared fixtures. Tests are seeded and deterministic."""

import numpy as np
import pytest

from pedi_drake import robot


@pytest.fixture
def rng() -> np.random.Generator:
    """A fresh seeded generator per test."""
    return np.random.default_rng(20261122)


@pytest.fixture(scope="session")
def go1_plant():
    """(plant, Go1PlantMap) of the Go1 without prongs and without geometry; read-only."""
    return robot.make_go1_plant()
