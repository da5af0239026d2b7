"""External loads: the slot of the equations of motion that the water (and anything else) fills.

A load is an immutable pytree (``equinox.Module``) called as

    load(model, t, q, qd, z, kin, memory, qdd_guess=None) -> LoadOutput

with ``kin`` the :class:`~mfm.kinematics.Kinematics` at (q, q̇), ``z`` its own first-order states
(``n_states`` of them, e.g. radiation state-space states) and ``memory`` its discrete memory (e.g.
the velocity history of a radiation convolution): made by ``init_memory`` and renewed after every
time step by ``update_memory``; read-only within a step. It returns Cartesian body loads
``body`` (n, 6: force in inertial axes, moment about the CoM in body axes), generalised loads
``tau`` (n_q), the state derivative ``zd`` and an optional acceleration-proportional matrix
``mass`` (n_q, n_q) that the solver moves to the left-hand side. Loads enter the equations of
motion as ``Bᵀ body + tau``. ``qdd_guess`` is the current acceleration iterate of a
predictor–corrector integrator (Beeman), for loads that put acceleration terms on the right-hand
side instead (the seed 001 scheme); None otherwise.
"""
from __future__ import annotations

from typing import NamedTuple

import equinox as eqx
import jax.numpy as jnp

from .points import BodyPoints


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

    def init_memory(self, model, t0, q0, qd0, dt):
        """Discrete memory at the start of a run (default: none)."""
        return ()

    def update_memory(self, model, t, q, qd, kin, memory):
        """Memory after a step that ended at (t, q, q̇) (default: unchanged)."""
        return memory

    def reaction_loads(self, model, t, q, qd, qdd, z, kin, memory, out: LoadOutput):
        """Cartesian loads (n, 6) this load puts on the bodies, for the joint reactions: by default
        ``out.body``; a load with acceleration-proportional terms adds them here."""
        return out.body

    def diagnostics(self, model, t, q, qd, qdd, z, kin, memory, out: LoadOutput) -> dict:
        """Named arrays recorded at every saved sample (e.g. wave elevation, PTO power)."""
        return {}

    def annotate(self, ds, records: dict):
        """Add this load's recorded diagnostics to the result dataset (with dims and units)."""
        return ds

    def __call__(self, model, t, q, qd, z, kin, memory=(), qdd_guess=None) -> LoadOutput:  # pragma: no cover
        raise NotImplementedError


class BodyWrench(Load):
    """Constant Cartesian loads per body: ``wrench`` (n, 6) = force (N, inertial axes) and moment
    (N m, body axes, about the CoM)."""
    wrench: jnp.ndarray

    def __call__(self, model, t, q, qd, z, kin, memory=(), qdd_guess=None):
        return LoadOutput(body=self.wrench)


class CoordinateForceSeries(Load):
    """A generalised force given on a uniform time grid, linearly interpolated in time:
    ``tau(t)`` with ``values`` (n_t, n_q) at ``t0 + k·step`` (held constant outside the grid)."""
    t0: jnp.ndarray
    step: jnp.ndarray
    values: jnp.ndarray

    def __call__(self, model, t, q, qd, z, kin, memory=(), qdd_guess=None):
        s = (t - self.t0) / self.step
        n = self.values.shape[0]
        k = jnp.clip(jnp.floor(s), 0, n - 2).astype(int)
        w = jnp.clip(s - k, 0.0, 1.0)
        return LoadOutput(tau=(1.0 - w) * self.values[k] + w * self.values[k + 1])


class PointSprings(Load):
    """Linear springs from points on bodies to their positions at q = 0 (e.g. a linear mooring):
    F = −diag(k) (p − p₀) at each point p (inertial axes), N. ``points`` the attachment points
    (:class:`~mfm.points.BodyPoints`, p₀ = their positions at q = 0); ``stiffness`` (m, 3) N/m."""
    points: BodyPoints
    stiffness: jnp.ndarray

    def __call__(self, model, t, q, qd, z, kin, memory=(), qdd_guess=None):
        f = -self.stiffness * (self.points.positions(kin) - self.points.ref0)
        F = jnp.concatenate([f, jnp.zeros_like(f)], axis=1).reshape(-1)
        return LoadOutput(body=self.points.to_body_wrench(F, kin, model.n_bodies))
