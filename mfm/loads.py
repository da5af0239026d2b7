"""External loads: the slot of the equations of motion that the water (and anything else) fills.

A load is an immutable pytree (``equinox.Module``) called as

    load(model, t, q, qd, z, kin) -> LoadOutput

with ``kin`` the :class:`~mfm.kinematics.Kinematics` at q and ``z`` its own first-order states
(``n_states`` of them, e.g. radiation state-space states). It returns Cartesian body loads
``body`` (n, 6: force in inertial axes, moment about the CoM in body axes), generalised loads
``tau`` (n_q), the state derivative ``zd`` and an optional acceleration-proportional matrix
``mass`` (n_q, n_q) that the solver moves to the left-hand side. Loads enter the equations of
motion as ``Bᵀ body + tau``.
"""
from __future__ import annotations

from typing import NamedTuple

import equinox as eqx
import jax.numpy as jnp


class LoadOutput(NamedTuple):
    body: jnp.ndarray | None = None
    tau: jnp.ndarray | None = None
    zd: jnp.ndarray | None = None
    mass: jnp.ndarray | None = None


class Load(eqx.Module):
    """Base class: no states, override ``__call__``."""

    @property
    def n_states(self) -> int:
        return 0

    def initial_state(self, model) -> jnp.ndarray:
        return jnp.zeros(self.n_states)

    def __call__(self, model, t, q, qd, z, kin) -> LoadOutput:  # pragma: no cover - abstract
        raise NotImplementedError


class BodyWrench(Load):
    """Constant Cartesian loads per body: ``wrench`` (n, 6) = force (N, inertial axes) and moment
    (N m, body axes, about the CoM)."""
    wrench: jnp.ndarray

    def __call__(self, model, t, q, qd, z, kin):
        return LoadOutput(body=self.wrench)


class CoordinateForceSeries(Load):
    """A generalised force given on a uniform time grid, linearly interpolated in time:
    ``tau(t)`` with ``values`` (n_t, n_q) at ``t0 + k·step`` (held constant outside the grid)."""
    t0: jnp.ndarray
    step: jnp.ndarray
    values: jnp.ndarray

    def __call__(self, model, t, q, qd, z, kin):
        s = (t - self.t0) / self.step
        n = self.values.shape[0]
        k = jnp.clip(jnp.floor(s), 0, n - 2).astype(int)
        w = jnp.clip(s - k, 0.0, 1.0)
        return LoadOutput(tau=(1.0 - w) * self.values[k] + w * self.values[k + 1])
