"""The time integrators, as the front door names them (``mfm.integrators.Beeman(tol=0.01)``;
their module is :mod:`mfm.timedomain.integrators`, the same objects)."""
from .timedomain.integrators import (INTEGRATORS, AbstractIntegrator, Beeman, Newmark, RK4,  # noqa: F401
                                     SemiImplicitEuler, State, Verlet, get, phase_error)

__all__ = ["INTEGRATORS", "AbstractIntegrator", "Beeman", "Newmark", "RK4", "SemiImplicitEuler",
           "State", "Verlet", "get", "phase_error"]
