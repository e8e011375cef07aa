"""The numbers page: every row names a command that exists, and the committed docs/numbers.md
and README.md table are what the committed JSON files give."""

import importlib.util
import json
import shlex
from pathlib import Path

import pytest

from pedi_drake.benchmarks import report

REPO = Path(__file__).resolve().parents[1]


@pytest.mark.parametrize("row", report.ROWS, ids=lambda row: row.source)
def test_every_row_names_a_command_that_exists(row):
    words = shlex.split(row.command)
    assert words[0] == "python", row.command
    if words[1] == "-m":
        assert importlib.util.find_spec(words[2]) is not None, f"{row.figure}: no module {words[2]}"
    else:
        assert (REPO / words[1]).is_file(), f"{row.figure}: no script {words[1]}"


def test_a_missing_benchmark_reads_not_measured(tmp_path):
    measured = report.measure(report.ROWS, tmp_path)
    assert all(m.value == report.NOT_MEASURED for m in measured)
    page = report.numbers_page(measured)
    for row in report.ROWS:
        assert f"| {row.figure} | not measured | `{row.command}` |" in page


def test_a_benchmark_file_names_its_machine_and_date_in_the_header(tmp_path):
    (tmp_path / "dynamics.json").write_text(
        json.dumps(
            {
                "rows": {"no prongs": {"go1_dynamics from compiled code": 3.0, "drake update": 170.0}},
                "machine": {"cpu_model": "Test CPU", "cores": 4},
                "date": "2030-01-02",
            }
        )
    )
    page = report.numbers_page(report.measure(report.ROWS, tmp_path))
    assert "Measured on Test CPU, 4 cores, 2030-01-02." in page
    assert "3.0 us compiled" in page


def test_the_committed_page_and_readme_table_are_regenerated():
    with pytest.MonkeyPatch.context() as patch:
        patch.chdir(REPO)
        assert report.main(["--check"]) == 0, "run python -m pedi_drake.benchmarks.report and commit"
