"""What mfm raises and warns, in one place: every module imports its exceptions from here (the
bottom of the package: it imports nothing), and ``mfm`` exports them all.

Errors name the argument or config key, the value, what is accepted and, where there is one, the
fix. :class:`PerformanceWarning` lives in :mod:`mfm.runner.xla`, which must be imported first of all.
"""
from __future__ import annotations


class ConfigError(ValueError):
    """A float tree or config that cannot be built. The message names the key, the value and the fix."""


class SeaStateError(TypeError, ValueError):
    """An argument that should be a sea state of :mod:`hydro.waves` is something else. A
    TypeError (the wrong kind of object) and a ValueError (a bad argument value), as the time and
    the frequency domains raised before they shared one check."""


class SimulationError(RuntimeError):
    """The simulation went non-finite; the message gives the time, the state and the likely cause.
    ``dataset`` holds what was computed up to the last finite sample (attribute
    ``complete = "false"``), or None."""

    def __init__(self, message, dataset=None):
        super().__init__(message)
        self.dataset = dataset


class SweepError(RuntimeError):
    """Every chunk of a sweep failed: there is nothing to gather. ``errors`` lists each chunk's
    error (text); the first chunk's exception is the ``__cause__`` where it could be sent back."""

    def __init__(self, message, errors=()):
        super().__init__(message)
        self.errors = list(errors)


class StabilityWarning(UserWarning):
    """dt is beyond the integrator's stability limit for the model's shortest natural period."""


class AccuracyWarning(UserWarning):
    """The run's accuracy is in doubt: dt too coarse for the periods the sea excites (the expected
    period error is given), or a coordinate without restoring integrated by Verlet (it drifts)."""


class OptimizeError(ValueError):
    """:func:`mfm.optimize` stopped: the objective or a constraint went non-finite, or the
    constraints cannot be met within the bounds. ``last_good`` the last parameter values (name →
    value) where everything was finite, or None."""

    def __init__(self, message, last_good=None):
        super().__init__(message)
        self.last_good = last_good
