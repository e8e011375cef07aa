"""Ships the top-level models/ and scenarios/ folders inside the wheel as pedi_drake/models and
pedi_drake/scenarios.

Everything else about the package is in pyproject.toml; setuptools cannot express "this folder
outside the package becomes a subpackage" there, so the package list lives here.
"""

from setuptools import find_packages, setup

setup(
    packages=find_packages(include=["pedi_drake", "pedi_drake.*"]) + ["pedi_drake.models", "pedi_drake.scenarios"],
    package_dir={"pedi_drake.models": "models", "pedi_drake.scenarios": "scenarios"},
    package_data={
        "pedi_drake.models": ["*.xml", "**/*.urdf", "**/*.sdf", "**/*.obj", "**/*.py"],
        "pedi_drake.scenarios": ["*.yaml"],
    },
)
