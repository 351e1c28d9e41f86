"""The error a failed contract check raises."""

from __future__ import annotations

from ..errors import DpmError


class ContractError(DpmError, AssertionError):
    """A plugin class failed a check of :mod:`dpm.testing` (an ``AssertionError``, so
    pytest reports it as a failed test); the message names the check, the value found,
    the reference and the tolerance."""
