"""Where the shipped data folders are: models/, scenarios/, missions/ and studies/.

In a source checkout they sit beside the package (<repo>/models, ...); an installed wheel
carries them inside it (pedi_drake/models, ...; see setup.py). One lookup serves them all.
"""

from pathlib import Path

from pedi_drake.exceptions import PediError

_PACKAGE = Path(__file__).resolve().parent


def shipped_dir(name: str, marker: str = "") -> Path:
    """The shipped folder `name` ("models", "scenarios", "missions"): beside the package in a
    source checkout, inside it in a wheel. `marker`: a file the folder must hold."""
    for candidate in (_PACKAGE.parent / name, _PACKAGE / name):
        if candidate.is_dir() and (not marker or (candidate / marker).exists()):
            return candidate
    raise PediError(f"the shipped {name}/ folder was not found next to {_PACKAGE}")


def models_dir() -> Path:
    """The folder holding package.xml of the `pedi_drake` model package (package://pedi_drake/)."""
    return shipped_dir("models", "package.xml")


def scenarios_dir() -> Path:
    """The shipped scenario files."""
    return shipped_dir("scenarios")


def studies_dir() -> Path:
    """The shipped batch studies."""
    return shipped_dir("studies")


def missions_dir() -> Path:
    """The shipped mission library."""
    return shipped_dir("missions")
