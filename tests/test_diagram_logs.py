"""The run's one log: every logged signal is its own rows of it, at every sample."""

import numpy as np
from pydrake.systems.analysis import Simulator

from pedi_drake.diagram import LOG_SINK, SAMPLED_SENSOR_SIGNALS, MakePedipulationDiagram
from pedi_drake.scenario import load_scenario

DURATION = 0.2  # [s]


def test_each_logged_signal_is_its_own_rows_of_the_one_log():
    scenario = load_scenario(scenario_text="{controller: whole_body, mission: hit_target_front}")
    built = MakePedipulationDiagram(scenario)
    simulator = Simulator(built.diagram)
    built.reserve_logs(simulator.get_mutable_context(), DURATION)
    simulator.AdvanceTo(DURATION)
    context = simulator.get_context()
    logs = built.logs(context)
    rows = sorted(built.log_rows.values(), key=lambda part: part.start)
    size = built.diagram.GetSubsystemByName(LOG_SINK).get_input_port().size()
    # The signals tile the log: no row shared, none left over.
    assert [part.start for part in rows] == [0] + [part.stop for part in rows[:-1]] and rows[-1].stop == size
    assert "mission.body_reference" in logs and "sim.plant_state" in logs
    for name, log in logs.items():
        port = built.diagram.GetOutputPort(name)
        assert log.data.shape == (port.size(), round(DURATION / built.log_period) + 1), name
        if name not in SAMPLED_SENSOR_SIGNALS:
            # The last sample is the signal at the end (a sampled sensor is logged through a hold).
            np.testing.assert_array_equal(log.data[:, -1], port.Eval(context), err_msg=name)
