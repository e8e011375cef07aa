"""Paper 002 (Xin et al.) Section IV: the evaluations of its whole-body controller."""

from pathlib import Path

from pedi_drake.reproduce.report import Section


def reproduce(folder: Path, *, quick: bool = False) -> Section:
    section = Section("002", "Variable autonomy of whole-body control")
    section.not_yet += [
        "Figs. 3-5 (torso circle while one foot holds its pose)",
        "Fig. 7 (torso rotations about one prong and the rear feet)",
    ]
    return section
