"""pedi_drake.apps.status_flood and its judgement in apps.sil: every malformed message it sends is
one the driver turns away for the reason it is named after, and a run is judged by the ticks that
ran while it lasted."""

import json
import types

import lcm
import numpy as np
import pytest

from pedi_drake.apps import status_flood
from pedi_drake.apps.sil import flood_outcome, flood_text
from pedi_drake.benchmarks.sil_floors import meets_floors
from pedi_drake.go1_driver import constants as c
from pedi_drake.go1_driver.config import Go1DriverConfig
from pedi_drake.go1_driver.link import Go1Link

URL = "udpm://239.255.76.67:7667?ttl=0"


def _flood_into_a_link(duration: float = 0.02, rate: float = 500.0):
    bus = lcm.LCM("memq://")
    link = Go1Link(bus, Go1DriverConfig(), url="memq://", threaded=False)
    record = status_flood.flood(bus, duration, rate)
    link.poll()
    return record, link.report()


def test_the_driver_rejects_every_flooded_message_for_the_reason_its_kind_names():
    record, report = _flood_into_a_link()
    sent = record["sent"]
    assert set(sent) == set(c.STATUS_CHANNELS)
    assert all(count >= 5 for kinds in sent.values() for count in kinds.values()), sent
    expected = status_flood.expected_rejections(sent)
    for channel in c.STATUS_CHANNELS:
        assert report["messages"][channel]["rejected"] == expected[channel], channel
    # The remote's floats are its sticks, which the driver does not read: NaN there is valid.
    assert report["messages"][c.RC_COMMAND_CHANNEL]["received"] == sent[c.RC_COMMAND_CHANNEL]["nonfinite"]
    assert record["first_wall"] <= record["last_wall"]


def test_an_unknown_kind_is_a_clear_error():
    with pytest.raises(ValueError, match="kind must be one of"):
        status_flood.malformed(c.LEG_CONTROL_CHANNEL, "garbled")


@pytest.mark.parametrize(
    "argv",
    [
        ["--lcm_url", URL, "--rate", "0"],
        ["--lcm_url", URL, "--duration", "nan"],
        ["--lcm_url", URL, "--start_after", "-1"],
        ["--lcm_url", "udp://nowhere"],
    ],
)
def test_bad_input_exits_2_before_touching_the_bus(argv, capsys):
    assert status_flood.main(argv) == 2
    assert "status_flood: --" in capsys.readouterr().err


def _run(wall: np.ndarray, rejected: dict, sent: dict, window: tuple[float, float]) -> dict:
    """flood_outcome on a run whose ticks were logged at `wall` [s], 2 ms apart in diagram time."""
    logs = {"wall_clock": types.SimpleNamespace(times=0.002 * np.arange(len(wall)), data=wall[np.newaxis, :])}
    messages = {channel: {"received": 0, "dropped": 0, "rejected": rejected.get(channel, {})} for channel in sent}
    result = {"driver": {"messages": messages, "loop": {"period_s": 0.002}}}
    flood = {"sent": sent, "first_wall": window[0], "last_wall": window[1]}
    return flood_outcome(flood, result, logs)


SENT = {channel: dict.fromkeys(status_flood.FLOOD_KINDS, 500) for channel in c.STATUS_CHANNELS}


def test_the_ticks_during_the_flood_are_judged_and_the_others_are_not():
    wall = 100.0 + 0.002 * np.arange(1000)
    wall[300] += 0.004  # late, before the flood
    wall[600] += 0.003  # late, during it
    wall[610] += 0.001  # late, within its period
    # The flood from 100.9991 to 101.4991 s: the ticks logged from 101.000 to 101.500 s (and the
    # period after its last message), 251 of them.
    outcome = _run(wall, status_flood.expected_rejections(SENT), SENT, (100.9991, 101.4991))
    assert outcome["every_one_counted"]
    assert outcome["ticks_during"] == 251
    assert outcome["deadline_misses_during"] == 1
    assert outcome["longest_lateness_during_ms"] == pytest.approx(3.0)
    assert "every one counted" in flood_text(outcome) and "1 past the period" in flood_text(outcome)


def test_a_message_not_counted_is_reported():
    wall = 100.0 + 0.002 * np.arange(1000)
    rejected = status_flood.expected_rejections(SENT)
    rejected[c.LEG_CONTROL_CHANNEL] = {**rejected[c.LEG_CONTROL_CHANNEL], "wrong_size": 499}
    outcome = _run(wall, rejected, SENT, (101.0, 102.0))
    assert not outcome["every_one_counted"]
    assert "NOT all counted" in flood_text(outcome)


GOOD_RUN = {
    "success": True,
    "latched": None,
    "max_true_foot_error_mm": 2.0,
    "deadline_misses_per_1000": 0.5,
    "longest_miss_ms": 6.0,
}
GOOD_FLOOD = {"sent": SENT, "every_one_counted": True, "ticks_during": 500, "deadline_misses_during": 0}


@pytest.mark.parametrize(
    ("flood", "meets"),
    [
        (GOOD_FLOOD, True),
        ({**GOOD_FLOOD, "every_one_counted": False}, False),
        ({**GOOD_FLOOD, "deadline_misses_during": 1}, False),
        ({**GOOD_FLOOD, "ticks_during": 0}, False),  # the flood came after the run
        ({"returncode": 1, "output": "no command"}, False),  # nothing was sent
    ],
)
def test_a_flooded_run_meets_the_floors_only_if_the_flood_changed_nothing(flood, meets):
    assert meets_floors({**GOOD_RUN, "flood": flood}) is meets


def test_the_program_floods_after_the_first_command_then_holds_until_stopped(tmp_path):
    """`python -m pedi_drake.apps.status_flood --hold` over UDP, as `apps.sil --flood_at` runs it."""
    import os
    import signal
    import subprocess
    import sys
    import time

    url = f"udpm://239.255.76.67:{30000 + os.getpid() % 20000}?ttl=0"
    out = tmp_path / "flood.json"
    process = subprocess.Popen(
        [sys.executable, "-m", "pedi_drake.apps.status_flood", "--lcm_url", url, "--out", str(out)]
        + ["--start_after", "0", "--duration", "0.05", "--rate", "200", "--wait", "60", "--hold"],
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
    )
    bus = lcm.LCM(url)
    heard = {kind: 0 for kind in status_flood.FLOOD_KINDS}
    leg = status_flood.malformed(c.LEG_CONTROL_CHANNEL, "wrong_fingerprint")

    def on_leg(_channel, data):
        heard["wrong_fingerprint" if data == leg else "wrong_size" if len(data) < len(leg) else "nonfinite"] += 1

    bus.subscribe(c.LEG_CONTROL_CHANNEL, on_leg)
    command = c.CHANNEL_TYPES[c.COMMAND_CHANNEL]().encode()
    deadline = time.monotonic() + 60
    try:
        while not out.exists() and time.monotonic() < deadline:
            bus.publish(c.COMMAND_CHANNEL, command)
            bus.handle_timeout(10)
        assert out.exists(), "no flood within 60 s"
        while bus.handle_timeout(50) > 0:
            pass
        assert process.poll() is None  # holding, not exiting into the run it floods
    finally:
        process.send_signal(signal.SIGTERM)
        output, _ = process.communicate(timeout=30)
    assert process.returncode == 0, output
    record = json.loads(out.read_text())
    assert record["sent"][c.LEG_CONTROL_CHANNEL] == {kind: 10 for kind in status_flood.FLOOD_KINDS}
    assert heard == record["sent"][c.LEG_CONTROL_CHANNEL]
    assert "sent 90 malformed messages" in output
