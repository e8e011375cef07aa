"""apps.sil --pin: which CPUs the bridge and the controller side get."""

import pytest

from pedi_drake.apps.sil import pinned_cpus
from pedi_drake.exceptions import ConfigError


def test_the_bridge_gets_the_last_cpu_and_the_controller_the_rest():
    assert pinned_cpus([0, 1]) == {"bridge": {1}, "controller": {0}}
    assert pinned_cpus([0, 2, 3, 5]) == {"bridge": {5}, "controller": {0, 2, 3}}


def test_one_cpu_is_a_clear_error():
    with pytest.raises(ConfigError, match="--pin: needs two CPUs"):
        pinned_cpus([3])
