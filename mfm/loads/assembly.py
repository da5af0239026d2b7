"""The loads of a model, summed: the runner every solver shares.

:func:`carried_loads` builds the loads a model carries itself (its water for a sea and a time
grid, then its config's loads); :func:`applied_loads` evaluates a tuple of loads at one state
(their :class:`~mfm.loads.base.LoadOutput` summed, their states concatenated in z). The time domain
(:mod:`mfm.timedomain`), the linearisation at rest and the frequency domain (:mod:`mfm.frequency`)
all call these: one place where loads meet the equations of motion, as Bᵀ body + tau.
"""
from __future__ import annotations

import dataclasses
from typing import Sequence

import jax.numpy as jnp
import numpy as np

from ..validation import check_sea
from .base import Context, Load
from .radiation import Convolution, StateSpace
from .water import Water, build_water

# the stage offsets of RK4 (fractions of dt at which it evaluates the dynamics): what the loads of
# a linearisation are built with when no integrator is named (their tables hold no run either way)
RK4_STAGE_OFFSETS = (0.0, 0.5, 1.0)


def carried_loads(model, sea=None, *, dt, duration, t0=0.0, ramp=0.0, radiation="convolution",
                  memory=None, state_space_options=None, added_mass="lhs",
                  stage_offsets=RK4_STAGE_OFFSETS) -> tuple[Load, ...]:
    """The loads a model carries itself: with a [hydro] config its water for this sea and time
    grid (:func:`mfm.loads.water.build_water`, prepared for an integrator's ``stage_offsets``),
    then the config's loads (``model.loads``: moorings, PTOs, …). The time domain's
    :func:`mfm.timedomain.setup.model_loads` names the integrator instead of its offsets."""
    out = []
    if model.hydro is not None:
        check_sea(sea)
        out.append(build_water(model, model.hydro, sea, dt=dt, duration=duration, t0=t0, ramp=ramp,
                               radiation=radiation, memory=memory,
                               state_space_options=state_space_options, added_mass=added_mass,
                               stage_offsets=tuple(float(o) for o in stage_offsets)))
    return tuple(out) + tuple(model.loads)


def compile_view(model, loads=()):
    """(model, loads) as the compiled functions are handed them: the fields that only the host
    reads blanked — the model's name, config path and hash and its HydroSpec, the water's spec
    (traced code reads only its moved dofs, which the water keeps apart), a state-space fit's
    report, a convolution's memory length — so that models and loads that differ only in numbers
    share one compilation (a static field is part of jit's key, compared by value; a HydroSpec by
    the content of its database). Nothing traced reads them: tests/test_jax_contract.py checks
    that a reused compilation gives the bits of a fresh one."""
    def view(ld):
        if isinstance(ld, Water):
            rad = ld.rad
            if isinstance(rad, StateSpace):
                rad = dataclasses.replace(rad, report=())
            elif isinstance(rad, Convolution):
                rad = dataclasses.replace(rad, memory_length=0.0)
            return dataclasses.replace(ld, spec=None, rad=rad)
        return ld

    return model.keyed(), tuple(view(ld) for ld in loads)


def as_loads(loads) -> tuple[Load, ...]:
    """``loads=`` of the front doors as a tuple of loads: None, one load or a sequence of them."""
    if loads is None:
        return ()
    if isinstance(loads, Load):
        return (loads,)
    loads = tuple(loads)
    for ld in loads:
        if not isinstance(ld, Load):
            raise TypeError(f"loads: {ld!r} is not an mfm.loads.Load")
    return loads


def state_offsets(loads: Sequence[Load]) -> np.ndarray:
    """Where each load's states start in z (they are concatenated in ``loads`` order)."""
    return np.concatenate([[0], np.cumsum([ld.n_states for ld in loads])]).astype(int)


def applied_loads(model, loads: Sequence[Load], t, q, qd, z, kin, memories=None,
                  with_outputs=False, qdd_guess=None):
    """Sum the external loads at one state: (body (n, 6) | None, tau (n_q,) | None,
    mass (n_q, n_q) | None, zd (n_states,)), plus the per-load outputs if ``with_outputs``.
    Load states are concatenated in z in ``loads`` order."""
    offsets = state_offsets(loads)
    memories = memories if memories is not None else tuple(() for _ in loads)
    body = tau = mass = None
    zds, outs = [], []
    for k, ld in enumerate(loads):
        out = ld.evaluate(Context(model, t, q, qd, z[offsets[k]:offsets[k + 1]], kin, memories[k],
                                  qdd_guess))
        outs.append(out)
        if out.body is not None:
            body = out.body if body is None else body + out.body
        if out.tau is not None:
            tau = out.tau if tau is None else tau + out.tau
        if out.mass is not None:
            mass = out.mass if mass is None else mass + out.mass
        zds.append(jnp.zeros(ld.n_states) if out.zd is None else out.zd)
    zd = jnp.concatenate(zds) if zds else jnp.zeros(0)
    if with_outputs:
        return body, tau, mass, zd, outs
    return body, tau, mass, zd
