"""The live SUF system spreads each update over the control ticks after its start, never the
mission manager's, and publishes what the whole update done in one call gives: the same
sequence of SUF vectors, only later; an update under way is state of the Context."""

import math

import numpy as np
import pytest
from pydrake.systems.analysis import Simulator
from pydrake.systems.framework import DiagramBuilder
from pydrake.systems.primitives import ConstantVectorSource, LogVectorOutput

from pedi_drake.evaluation.live_suf import update_samples
from pedi_drake.exceptions import ScenarioError
from pedi_drake.scenario import load_scenario
from pedi_drake.suf.live import LiveSuf, LiveSufReading, idle_vector, without_timing
from pedi_drake.suf.live_suf_system import LiveSufSystem, slot_at, suf_request_vector
from pedi_drake.suf.stances import teleoperation_stance

PERIOD, OFFSET, TICK = 0.01, 0.004, 0.002
PUSH = np.array([-1.0, 0.0, 0.0])
LOADED = np.array([0.0, 1.0, 1.0, 1.0])  # FR lifted
DURATION = 0.1  # [s]


def _stance_inputs():
    stance = teleoperation_stance()
    base = np.array([1.0, 0.0, 0.0, 0.0, *stance.trunk_xy, stance.trunk_height, *np.zeros(6)])
    return base, stance.joint_angles()


def _diagram(tick_work: float):
    """(diagram, the SUF's log sink): the live SUF of the teleoperation stance, inputs constant."""
    base, q = _stance_inputs()
    builder = DiagramBuilder()
    suf = builder.AddNamedSystem(
        "suf", LiveSufSystem(None, mu=0.6, period=PERIOD, offset=OFFSET, tick=TICK, tick_work=tick_work)
    )
    for port, value in (
        ("base_state", base),
        ("position_measured", q),
        ("contact_set", LOADED),
        ("suf_request", suf_request_vector(0, PUSH)),
    ):
        builder.Connect(builder.AddSystem(ConstantVectorSource(value)).get_output_port(), suf.GetInputPort(port))
    log = LogVectorOutput(suf.GetOutputPort("suf"), builder, TICK)
    return builder.Build(), log


def _run(tick_work: float, duration: float = DURATION):
    """(times [s], readings, vectors) of every finished update in `duration`, as the log saw them:
    a periodic log sample at t shows the state before the updates at t, so one tick later."""
    diagram, log = _diagram(tick_work)
    simulator = Simulator(diagram)
    simulator.AdvanceTo(duration)
    data = log.FindLog(simulator.get_context())
    times, readings = update_samples(data.sample_times(), data.data())
    index = np.searchsorted(data.sample_times(), times)
    return times, readings, data.data()[:, index].T


def _slots(period: float, offset: float, tick: float, duration: float) -> dict[str, list[float]]:
    """The control ticks up to `duration` [s] by what they are to the live SUF (slot_at)."""
    slots = {"start": [], "slice": []}
    for k in range(round(duration / tick) + 1):
        kind = slot_at(k * tick, period, offset, tick)
        if kind is not None:
            slots[kind].append(k * tick)
    return slots


def test_the_slices_are_the_ticks_after_the_start_except_the_managers():
    slots = _slots(PERIOD, OFFSET, TICK, 0.03)
    np.testing.assert_allclose(slots["start"], [0.004, 0.014, 0.024], atol=1e-12)
    np.testing.assert_allclose(slots["slice"], [0.006, 0.008, 0.012, 0.016, 0.018, 0.022, 0.026, 0.028], atol=1e-12)
    # Thousands of periods on: the control ticks' own times, no rounding error apart, still sorted right.
    late = _slots(PERIOD, OFFSET, TICK, 600.0)
    assert len(late["start"]) == 60000 and len(late["slice"]) == 3 * 60000 - 1
    # At 250 Hz the manager's updates fall between control ticks every other period: a start is
    # then the first tick after its time, one an update period.
    slots = _slots(PERIOD, OFFSET, 0.004, 0.04)
    np.testing.assert_allclose(slots["start"], [0.004, 0.016, 0.024, 0.036], atol=1e-12)
    np.testing.assert_allclose(slots["slice"], [0.008, 0.012, 0.028, 0.032], atol=1e-12)


def test_in_one_tick_the_updates_are_the_live_sufs_at_the_start_ticks():
    times, readings, vectors = _run(math.inf)
    np.testing.assert_allclose(times, OFFSET + TICK + PERIOD * np.arange(len(times)), atol=1e-9)
    assert len(times) == round(DURATION / PERIOD) and all(r.slices == 1 for r in readings)
    live, (base, q) = LiveSuf(mu=0.6), _stance_inputs()
    warm, vector = None, idle_vector()
    for k, published in enumerate(vectors):
        vector, warm = live.update(warm, vector, base, q, LOADED, 0, PUSH)
        np.testing.assert_array_equal(without_timing(published), without_timing(vector))
        assert LiveSufReading.from_vector(published).stance_time == pytest.approx(OFFSET + k * PERIOD)


def test_a_small_tick_budget_publishes_the_same_updates_later_on_slot_ticks():
    whole_times, _, whole = _run(math.inf, 3 * DURATION)
    times, readings, sliced = _run(3.0, 3 * DURATION)
    assert len(times) >= 3 and max(r.slices for r in readings) > 1
    for mine, theirs in zip(sliced, whole, strict=False):
        np.testing.assert_array_equal(without_timing(mine), without_timing(theirs))
    # Published on a slot tick, as many ticks after its start as it took, never the manager's.
    assert all(slot_at(t - TICK, PERIOD, OFFSET, TICK) is not None for t in times)
    assert np.all(times[: len(whole_times)] >= whole_times[: len(times)] - 1e-9)
    # Each describes the stance at its start: a start slot, before its publication.
    starts = np.array([r.stance_time for r in readings])
    periods = (starts - OFFSET) / PERIOD
    np.testing.assert_allclose(periods, np.round(periods), atol=1e-9)
    assert np.all(starts < times)


def test_an_update_under_way_is_state_of_the_context():
    diagram, _ = _diagram(1.0)
    suf = diagram.GetSubsystemByName("suf")

    def reading(simulator):
        context = suf.GetMyContextFromRoot(simulator.get_context())
        return np.array(suf.GetOutputPort("suf").Eval(context))

    simulator = Simulator(diagram)
    simulator.AdvanceTo(OFFSET + 1.5 * TICK)  # the first update started and is under way
    assert LiveSufReading.from_vector(reading(simulator)).updates == 0
    clone = Simulator(diagram, simulator.get_context().Clone())
    simulator.AdvanceTo(3 * DURATION)
    clone.AdvanceTo(3 * DURATION)
    assert LiveSufReading.from_vector(reading(simulator)).updates >= 1
    np.testing.assert_array_equal(reading(simulator), reading(clone))


@pytest.mark.parametrize("tick_work", [0.0, -1.0, float("nan"), True])
def test_a_tick_work_that_is_not_a_positive_number_is_named(tick_work):
    scenario = load_scenario(scenario_text="{}")
    scenario.live_suf.tick_work = tick_work
    with pytest.raises(ScenarioError, match="live_suf.tick_work"):
        scenario.validate()
