"""Exceptions raised by dpm: each names the call, the parameter, its value and what is allowed."""

from __future__ import annotations


class DpmError(Exception):
    """Base class of every dpm error."""


class ParameterError(DpmError, ValueError):
    """A parameter is out of range, of the wrong shape, or unknown.

    Message form: ``sim.contact(glass, steel): restitution=1.3 is outside (0, 1]``.
    Several problems found at once are listed one per line.
    """


class UnknownNameError(ParameterError, KeyError):
    """A registered name (shape, boundary, model, integrator) does not exist."""

    def __str__(self) -> str:  # KeyError would quote the message
        return str(self.args[0]) if self.args else ""


class SceneError(DpmError, ValueError):
    """The scene as a whole is invalid (overlaps, particles outside boundaries, missing laws)."""


class UnstableRunError(DpmError, RuntimeError):
    """The run became unstable (NaN, exploding overlap or energy); frames written so far stay."""


class OutputError(DpmError, OSError):
    """Writing the output or a checkpoint failed (disk full, quota, a removed directory):
    the run stops; what was written before stays complete and readable, and the message
    says from which checkpoint the run restarts."""
