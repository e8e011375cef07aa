"""A study's results: one row per finished task, appended to the files as each task finishes.

Two files in the study's folder hold the same rows: `results.jsonl` (one JSON object a line, the
exact values: what `--resume` and the summary read) and `results.csv` (the flat columns, for a
spreadsheet or pandas; a mission's whole result dictionary stays in the JSON file only). Rows
survive an interrupted study; `--resume` runs only the tasks whose id has no row yet.
"""

import csv
import json
import subprocess
from pathlib import Path

import pedi_drake

ROWS_FILE = "results.jsonl"
TABLE_FILE = "results.csv"


def code_version() -> str:
    """The package version and, in a git checkout, the commit (with `+dirty` for local changes)."""
    repo = Path(pedi_drake.__file__).resolve().parents[1]
    try:
        commit = subprocess.run(
            ["git", "-C", str(repo), "describe", "--always", "--dirty=+dirty"],
            capture_output=True,
            text=True,
            timeout=5,
            check=True,
        ).stdout.strip()
    except (OSError, subprocess.SubprocessError):
        return pedi_drake.__version__
    return f"{pedi_drake.__version__} ({commit})"


class ResultsFile:
    """The rows of one study folder: those already there, and `append` for each new one."""

    def __init__(self, folder: Path):
        self.folder = Path(folder)
        self.rows = read_rows(self.folder) if (self.folder / ROWS_FILE).exists() else []

    def done_ids(self) -> set[str]:
        return {row["task_id"] for row in self.rows}

    def append(self, row: dict) -> None:
        self.folder.mkdir(parents=True, exist_ok=True)
        self.rows.append(row)
        with (self.folder / ROWS_FILE).open("a") as handle:
            handle.write(json.dumps(row, default=str) + "\n")
            handle.flush()
        self._write_table()

    def _write_table(self) -> None:
        flat = [{k: v for k, v in row.items() if not isinstance(v, dict | list)} for row in self.rows]
        columns = list(dict.fromkeys(k for row in flat for k in row))
        temporary = self.folder / (TABLE_FILE + ".tmp")
        with temporary.open("w", newline="") as handle:
            writer = csv.DictWriter(handle, columns)
            writer.writeheader()
            writer.writerows(flat)
        temporary.replace(self.folder / TABLE_FILE)  # atomic: never half a table


def read_rows(folder: Path) -> list[dict]:
    """The rows of a study folder's results.jsonl; a line cut short by a crash is skipped."""
    rows = []
    for line in (Path(folder) / ROWS_FILE).read_text().splitlines():
        try:
            rows.append(json.loads(line))
        except json.JSONDecodeError:
            continue
    return rows
