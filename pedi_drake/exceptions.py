"""The package's exception hierarchy: every public function raises a subclass of PediError."""


class PediError(Exception):
    """Base class of every error pedi_drake raises on purpose."""


class ConfigError(PediError, ValueError):
    """A scenario, mission or design value is malformed; the message names the file and field."""


class ScenarioError(ConfigError):
    """A scenario file or override is invalid."""


class MissionFileError(ConfigError):
    """A mission file is invalid; the message names the file, phase index and field."""


class ProngDesignError(ConfigError):
    """A prong design has an invalid field."""


class UnreachableTarget(PediError):
    """An IK target lies outside the leg's reachable workspace within its joint limits."""


class QpInfeasible(PediError):
    """A QP of the whole-body controller or the SUF analysis has no solution."""


class LcmTimeout(PediError):
    """No message arrived on an LCM channel in time."""


class SufError(PediError):
    """A Smallest Unrejectable Force problem that cannot be built or solved (names the cause)."""
