"""Loads given directly by the user: constant body wrenches and generalised force series."""
from __future__ import annotations

import jax.numpy as jnp

from .base import Load, LoadOutput


class BodyWrench(Load):
    """Constant Cartesian loads per body: ``wrench`` (n, 6) = force (N, inertial axes) and moment
    (N m, body axes, about the CoM)."""
    wrench: jnp.ndarray

    def evaluate(self, ctx):
        return LoadOutput(body=self.wrench)


class CoordinateForceSeries(Load):
    """A generalised force given on a uniform time grid, linearly interpolated in time:
    ``tau(t)`` with ``values`` (n_t, n_q) at ``t0 + k·step`` (held constant outside the grid).
    A time history: it takes no part in the equilibrium or the frequency domain."""
    t0: jnp.ndarray
    step: jnp.ndarray
    values: jnp.ndarray

    def evaluate(self, ctx):
        s = (ctx.t - self.t0) / self.step
        n = self.values.shape[0]
        k = jnp.clip(jnp.floor(s), 0, n - 2).astype(int)
        w = jnp.clip(s - k, 0.0, 1.0)
        return LoadOutput(tau=(1.0 - w) * self.values[k] + w * self.values[k + 1])

    def static_load(self):
        return None
