"""pedi_drake: pedipulation with a Unitree Go1 on Drake."""

from pedi_drake.exceptions import (
    ConfigError,
    MissionFileError,
    PediError,
    ProngDesignError,
    QpInfeasible,
    ScenarioError,
    UnreachableTarget,
)

__all__ = [
    "ConfigError",
    "MissionFileError",
    "PediError",
    "ProngDesignError",
    "QpInfeasible",
    "ScenarioError",
    "UnreachableTarget",
]
__version__ = "0.1.0"
