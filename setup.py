"""Ships the top-level models/, scenarios/, missions/ and studies/ folders inside the wheel as
pedi_drake/models, pedi_drake/scenarios, pedi_drake/missions and pedi_drake/studies.

Everything else about the package is in pyproject.toml; setuptools cannot express "this folder
outside the package becomes a subpackage" there, so the package list lives here.
"""

from setuptools import find_packages, setup

setup(
    packages=find_packages(include=["pedi_drake", "pedi_drake.*"])
    + [
        "pedi_drake.models",
        "pedi_drake.scenarios",
        "pedi_drake.missions",
        "pedi_drake.studies",
    ],
    package_dir={
        "pedi_drake.models": "models",
        "pedi_drake.scenarios": "scenarios",
        "pedi_drake.missions": "missions",
        "pedi_drake.studies": "studies",
    },
    package_data={
        "pedi_drake.models": ["*.xml", "**/*.xml", "**/*.urdf", "**/*.sdf", "**/*.obj", "**/*.py"],
        "pedi_drake.scenarios": ["*.yaml"],
        # The controller demonstrations (pedi_drake.benchmarks.demos) and the short paper-002
        # evaluations (pedi_drake.reproduce --quick, tests) in their subfolders.
        "pedi_drake.missions": ["*.yaml", "demos/*.yaml", "quick/*.yaml"],
        "pedi_drake.studies": ["*.yaml"],
        "pedi_drake.go1_driver": ["README.md"],
        "pedi_drake.go1_driver.lcmtypes": ["*.lcm", "*.sh"],
    },
)
