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

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from ..validation import check_sea
from .base import Context, Load
from .radiation import Convolution, StateSpace
from .water import Water, build_water, build_water_batch

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


@dataclasses.dataclass(frozen=True)
class CaseLoads:
    """The loads of B cases of one model as one tuple: ``loads`` whose leaves marked in
    ``batched`` (a pytree of bools like it) carry a leading case axis of length ``size``, the
    others shared by every case (:func:`carried_loads_batch`). With water, ``waves`` (a
    :class:`~mfm.loads.water.WaveSum` over the cases) makes the water's tables, which ``loads``
    leaves out (None); :meth:`with_eta` puts the elevation in for the dataset."""
    loads: tuple
    batched: tuple
    size: int
    waves: object = None
    polar: tuple = ()

    def case(self, i: int) -> tuple:
        """Case i's loads, as :func:`carried_loads` makes them (the water's tables made on the
        host, by build_water's own route, where they are left out)."""
        varying, shared = eqx.partition(self.loads, self.batched)
        loads = eqx.combine(jax.tree_util.tree_map(lambda a: a[i], varying), shared)
        if self.waves is not None and loads[0].exc_values is None:
            exc, eta = jax.tree_util.tree_map(lambda a: a[i], self.waves).tables_numpy(
                tuple(np.asarray(a) for a in self.polar))
            loads = (dataclasses.replace(loads[0], exc_values=exc, eta_values=eta),) \
                + tuple(loads[1:])
        return loads

    def with_eta(self, eta) -> "CaseLoads":
        """These loads with the water's elevation table put in, with its case axis (B, n): what
        the dataset reads of the tables (:meth:`batch_outputs`)."""
        water = dataclasses.replace(self.loads[0], eta_values=eta)
        mask = dataclasses.replace(self.batched[0], eta_values=True)
        return dataclasses.replace(self, loads=(water,) + self.loads[1:],
                                   batched=(mask,) + self.batched[1:])

    def __len__(self):
        return self.size

    def __getitem__(self, i):
        return self.case(i)

    def batch_outputs(self, save_every: int, n_saved: int) -> dict:
        """The loads' :meth:`~mfm.loads.base.Load.batch_outputs` for every case at once:
        name → (array (B, n_saved), attrs)."""
        out = {}
        for ld in self.loads:
            for name, (v, attrs) in ld.batch_outputs(save_every, n_saved).items():
                v = np.asarray(v)
                out[name] = (np.broadcast_to(v, (self.size,) + v.shape[-1:]) if v.ndim == 1
                             else v, attrs)
        return out


def carried_loads_batch(model, seas, *, dts, ramps, n_steps: int, t0=0.0, radiation="convolution",
                        memory=None, state_space_options=None, added_mass="lhs",
                        stage_offsets=RK4_STAGE_OFFSETS) -> CaseLoads:
    """:func:`carried_loads` of B cases of one model at once (case b: ``seas[b]``, ``dts[b]``,
    ``ramps[b]``, ``n_steps`` steps): its water by :func:`mfm.loads.water.build_water_batch`
    (what the cases share made once, what differs vectorised, the tables left to the device),
    its config's loads shared."""
    B = len(seas)
    out, batched, waves, polar = [], [], None, ()
    if model.hydro is not None:
        for sea in seas:
            check_sea(sea)
        water, mask, waves, polar = build_water_batch(
            model, model.hydro, seas, dts=dts, ramps=ramps, n_steps=n_steps, t0=t0,
            radiation=radiation, memory=memory, state_space_options=state_space_options,
            added_mass=added_mass, stage_offsets=tuple(float(o) for o in stage_offsets))
        out.append(water)
        batched.append(mask)
    for ld in model.loads:
        out.append(ld)
        batched.append(jax.tree_util.tree_map(lambda _: False, ld))
    return CaseLoads(tuple(out), tuple(batched), B, waves, polar)


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
