"""The documentation's own floors: a README of one sitting's length that starts with the two
set-up commands, reference pages instead of a journal (no times of day, commit hashes or logs of
sittings), a reference page for every module, and real_time.md within its length."""

import re
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
README = REPO / "README.md"
DOCS = REPO / "docs"
SETUP_COMMANDS = [
    "pip install -e . && python run_sim.py --out out/default",
    "bash .ci/run",
]
# A time of day, a commit hash (7 or more hex digits) or a work session: journal, not reference.
JOURNAL = re.compile(r"sitting|[0-2][0-9]:[0-5][0-9]|[0-9a-f]{7,}\b")


def prose_lines(path: Path) -> list[tuple[int, str]]:
    """(line number, line) of a Markdown file outside its fenced code blocks."""
    lines, fenced = [], False
    for number, line in enumerate(path.read_text().splitlines(), start=1):
        if line.startswith("```"):
            fenced = not fenced
        elif not fenced:
            lines.append((number, line))
    return lines


def test_the_readme_is_at_most_200_lines():
    assert len(README.read_text().splitlines()) <= 200


def test_the_readme_starts_with_the_two_setup_commands():
    lines = README.read_text().splitlines()
    block = lines[lines.index("```bash") + 1 : lines.index("```bash") + 3]
    assert lines.index("```bash") <= 3
    assert [line.split("#")[0].strip() for line in block] == SETUP_COMMANDS


def test_real_time_is_a_reference_page_of_at_most_300_lines():
    assert len((DOCS / "real_time.md").read_text().splitlines()) <= 300


@pytest.mark.parametrize("page", [README, *sorted(DOCS.rglob("*.md"))], ids=lambda p: str(p.relative_to(REPO)))
def test_no_page_logs_times_of_day_hashes_or_sittings(page):
    lines = prose_lines(page)
    if page.name == "numbers.md":
        lines = [(n, line) for n, line in lines if not line.startswith("Measured on ")]
    found = [f"{page.name}:{n}: {line}" for n, line in lines if JOURNAL.search(line)]
    assert not found, "\n".join(found)


def test_every_module_has_a_reference_page():
    # A subpackage's page renders its modules itself (show_submodules); the root's lists them.
    pages = "".join(p.read_text() for p in (DOCS / "reference").glob("*.md"))
    listed = set(re.findall(r"^::: ([\w.]+)$", pages, re.M))
    package = REPO / "pedi_drake"
    subpackages = {
        f"pedi_drake.{path.parent.name}" for path in package.glob("*/__init__.py") if path.parent.name != "models"
    }
    root_modules = {f"pedi_drake.{path.stem}" for path in package.glob("*.py") if path.stem != "__init__"}
    assert (subpackages | root_modules) - listed == set(), "add them to docs/reference/ and mkdocs.yml's nav"
