"""pedi_drake.measuring.cpu_steal: the hypervisor's stolen time from /proc/stat."""

import os

from pedi_drake.measuring.cpu_steal import steal_seconds


def test_steal_is_read_from_the_cpu_line(tmp_path):
    stat = tmp_path / "stat"
    stat.write_text("cpu  225995 0 19741 403961 388 0 2528 118 0 0\ncpu0 93131 0 8767 218488 41 0 1371 52 0 0\n")
    assert steal_seconds(stat) == 118 / os.sysconf("SC_CLK_TCK")


def test_no_steal_field_or_no_file_is_none(tmp_path):
    stat = tmp_path / "stat"
    stat.write_text("cpu  225995 0 19741 403961\n")
    assert steal_seconds(stat) is None
    assert steal_seconds(tmp_path / "missing") is None


def test_this_machine_reports_a_number_or_none():
    value = steal_seconds()
    assert value is None or value >= 0.0
