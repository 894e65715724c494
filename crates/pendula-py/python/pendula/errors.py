"""pendula's exceptions: one hierarchy rooted at :class:`PendulaError`.

Bad input raises a :class:`ValueError` subclass whose message names the offending value and
what is allowed; a run that fails raises :class:`IntegrationError` (a :class:`RuntimeError`)
with the time ``t`` at which it failed and the ``solution`` up to there.
"""

from __future__ import annotations

__all__ = [
    "PendulaError",
    "UnknownNameError",
    "InvalidValueError",
    "UnsuitableMethodError",
    "IntegrationError",
    "NonFiniteStateError",
    "StepSizeTooSmallError",
    "NewtonError",
]


class PendulaError(Exception):
    """Every error pendula raises."""


class UnknownNameError(PendulaError, ValueError):
    """A system, method, parameter or preset name that is not in the catalogue; the message
    lists the valid names and the closest ones."""


class InvalidValueError(PendulaError, ValueError):
    """A value outside what is allowed; the message names the value and the allowed range."""


class UnsuitableMethodError(PendulaError, ValueError):
    """A method whose requirement the system does not meet (an explicit splitting on a
    non-separable system, a symplectic method on a damped one); the message says why and
    which methods apply."""


class IntegrationError(PendulaError, RuntimeError):
    """A run that failed: ``t`` is the time it failed at (s), ``solution`` the steps it took
    before."""

    def __init__(self, message: str, t: float | None = None, solution=None):
        super().__init__(message)
        self.t = t
        self.solution = solution


class NonFiniteStateError(IntegrationError):
    """The state became non-finite (a step too large for the method's stability)."""


class StepSizeTooSmallError(IntegrationError):
    """The adaptive step size fell below its minimum."""


class NewtonError(IntegrationError):
    """An implicit step's iteration did not converge."""
