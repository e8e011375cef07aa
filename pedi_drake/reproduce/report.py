"""report.md: each reproduced table or figure beside the published number it reproduces."""

import dataclasses
from pathlib import Path


@dataclasses.dataclass
class Comparison:
    """One published figure and ours."""

    item: str  # "Table I, exact, teleoperation"
    published: str  # as the paper states it
    ours: str  # as measured in this run
    note: str = ""  # where and why they differ


@dataclasses.dataclass
class Section:
    """A paper's part of the report."""

    paper: str  # "000"
    title: str
    comparisons: list[Comparison] = dataclasses.field(default_factory=list)
    figures: list[tuple[str, str]] = dataclasses.field(default_factory=list)  # (file name, caption)
    not_yet: list[str] = dataclasses.field(default_factory=list)  # what the project cannot produce yet
    notes: list[str] = dataclasses.field(default_factory=list)

    def markdown(self) -> str:
        lines = [f"# Paper {self.paper}: {self.title}", ""]
        if self.comparisons:
            lines += ["| item | published | ours | note |", "|---|---|---|---|"]
            lines += [f"| {c.item} | {c.published} | {c.ours} | {c.note} |" for c in self.comparisons]
            lines.append("")
        for name, caption in self.figures:
            lines += [f"![{caption}]({name})", "", f"*{caption}*", ""]
        for note in self.notes:
            lines += [note, ""]
        if self.not_yet:
            lines += ["Not yet reproduced:", ""] + [f"- {item}" for item in self.not_yet] + [""]
        return "\n".join(lines)


def write_report(section: Section, folder: Path, *, header: str = "") -> Path:
    """Writes `folder`/report.md for `section`."""
    path = Path(folder) / "report.md"
    path.write_text((header + "\n\n" if header else "") + section.markdown())
    return path
