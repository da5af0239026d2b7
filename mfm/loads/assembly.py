"""The loads of a model, summed: the runner every solver shares.

:func:`carried_loads` builds the loads a model carries itself (its water for a sea and a time
grid, then its config's loads); :func:`applied_loads` evaluates a tuple of loads at one state
(their :class:`~mfm.loads.base.LoadOutput` summed, their states concatenated in z). The time domain
(:mod:`mfm.timedomain`), the linearisation at rest and the frequency domain (:mod:`mfm.frequency`)
all call these: one place where loads meet the equations of motion, as Bᵀ body + tau.
"""
from __future__ import annotations

import dataclasses
import math
from typing import Sequence

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from ..backend import device_array
from ..validation import check_sea
from .base import Context, Load, RunGrid
from .water import build_water, build_water_batch

# the stage offsets of RK4 (fractions of dt at which it evaluates the dynamics): what the loads of
# a linearisation are built with when no integrator is named (their tables hold no run either way)
RK4_STAGE_OFFSETS = (0.0, 0.5, 1.0)


def carried_loads(model, sea=None, *, dt, duration, t0=0.0, ramp=0.0, radiation="convolution",
                  memory=None, state_space_options=None, added_mass="lhs",
                  stage_offsets=RK4_STAGE_OFFSETS, extra=(), mean_drift=None,
                  sampled: bool = True) -> tuple[Load, ...]:
    """The loads of a run: with a [hydro] config the model's water for this sea and time grid
    (:func:`mfm.loads.water.build_water`, prepared for an integrator's ``stage_offsets``), then
    the config's loads (``model.loads``: moorings, PTOs, …) and the ``extra`` loads of a front
    door, each laid on the run by its :meth:`~mfm.loads.base.Load.for_run`. The time domain's
    :func:`mfm.timedomain.setup.model_loads` names the integrator instead of its offsets.
    ``mean_drift``: the water's drift table in place of its database's (:func:`build_water`).
    ``sampled``: False for loads that serve at rest only (the nonlinear level's pressure at every
    call whatever ``[hydro] nonlinear_dt``, which is then not checked against ``dt``)."""
    out = []
    run = run_grid(sea, dt=dt, duration=duration, t0=t0, ramp=ramp, stage_offsets=stage_offsets)
    if model.hydro is not None:
        check_sea(sea)
        out.append(build_water(model, model.hydro, sea, dt=dt, duration=duration, t0=t0, ramp=ramp,
                               radiation=radiation, memory=memory,
                               state_space_options=state_space_options, added_mass=added_mass,
                               stage_offsets=run.stage_offsets, mean_drift=mean_drift,
                               sampled=sampled))
    return tuple(out) + laid_on(model, tuple(model.loads) + tuple(extra), run)


def run_grid(sea, *, dt, duration, t0=0.0, ramp=0.0, stage_offsets=RK4_STAGE_OFFSETS) -> RunGrid:
    """The :class:`~mfm.loads.base.RunGrid` of a run of ``duration`` s in steps of ``dt``."""
    return RunGrid(sea, float(t0), float(dt), int(round(float(duration) / float(dt))), float(ramp),
                   tuple(float(o) for o in stage_offsets))


def laid_on(model, loads, run: RunGrid) -> tuple[Load, ...]:
    """``loads`` laid on the run ``run`` (:meth:`~mfm.loads.base.Load.for_run` of each), each
    checked to be a load still."""
    out = []
    for ld in loads:
        laid = ld.for_run(model, run)
        if not isinstance(laid, Load):
            raise TypeError(f"load {type(ld).__name__}: for_run returned {laid!r}, not a Load")
        out.append(laid)
    return tuple(out)


@dataclasses.dataclass(frozen=True)
class CaseLoads:
    """The loads of B cases of one model as one tuple: ``loads`` whose leaves marked in
    ``batched`` (a pytree of bools like it) carry a leading case axis of length ``size``, the
    others shared by every case (:func:`carried_loads_batch`). With water, ``waves`` (a
    :class:`~mfm.loads.water.WaveSum` over the cases) makes the water's tables, which ``loads``
    leaves out (None), for the load at ``waves_at`` (its ``with_tables(exc, eta)`` puts them in);
    :meth:`with_eta` puts the elevation in for the dataset."""
    loads: tuple
    batched: tuple
    size: int
    waves: object = None
    polar: tuple = ()
    waves_at: int = 0

    def with_tables(self, loads: tuple, exc, eta, *more) -> tuple:
        """``loads`` (one case's, or a group's with the case axis) with the tables of ``waves``
        (exc, eta and, with a wave drift, its table) put in the load they belong to."""
        k = self.waves_at
        return loads[:k] + (loads[k].with_tables(exc, eta, *more),) + loads[k + 1:]

    def case(self, i: int) -> tuple:
        """Case i's loads, as :func:`carried_loads` makes them (the water's tables made on the
        host, by build_water's own route, where they are left out)."""
        varying, shared = eqx.partition(self.loads, self.batched)
        loads = eqx.combine(jax.tree_util.tree_map(lambda a: a[i], varying), shared)
        if self.waves is not None and loads[self.waves_at].exc_values is None:
            tables = jax.tree_util.tree_map(lambda a: a[i], self.waves).tables_numpy(
                tuple(np.asarray(a) for a in self.polar))
            loads = self.with_tables(loads, *tables)
        return loads

    def with_eta(self, eta) -> "CaseLoads":
        """These loads with the water's elevation table put in, with its case axis (B, n): what
        the dataset reads of the tables (:meth:`batch_outputs`)."""
        k = self.waves_at
        water = dataclasses.replace(self.loads[k], eta_values=eta)
        mask = dataclasses.replace(self.batched[k], eta_values=True)
        return dataclasses.replace(self, loads=self.loads[:k] + (water,) + self.loads[k + 1:],
                                   batched=self.batched[:k] + (mask,) + self.batched[k + 1:])

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
                        stage_offsets=RK4_STAGE_OFFSETS, extra=(), mean_drift=None) -> CaseLoads:
    """:func:`carried_loads` of B cases of one model at once (case b: ``seas[b]``, ``dts[b]``,
    ``ramps[b]``, ``n_steps`` steps): its water by :func:`mfm.loads.water.build_water_batch`
    (what the cases share made once, what differs vectorised, the tables left to the device),
    its config's loads and the ``extra`` loads each laid on every case's run (:meth:`~mfm.loads.base.Load.for_run`):
    shared where that is the load itself for every case, stacked on a case axis otherwise."""
    B = len(seas)
    out, batched, waves, polar = [], [], None, ()
    if model.hydro is not None:
        for sea in seas:
            check_sea(sea)
        water, mask, waves, polar = build_water_batch(
            model, model.hydro, seas, dts=dts, ramps=ramps, n_steps=n_steps, t0=t0,
            radiation=radiation, memory=memory, state_space_options=state_space_options,
            added_mass=added_mass, stage_offsets=tuple(float(o) for o in stage_offsets),
            mean_drift=mean_drift)
        out.append(water)
        batched.append(mask)
    # the most components of any case's sea: loads that read them pad theirs to it (one structure)
    n_c = max((0 if sea is None else len(sea.components(
        water_depth=model.hydro.water_depth if model.hydro is not None else math.inf).omega)
        for sea in seas), default=0)
    for ld in tuple(model.loads) + tuple(extra):
        laid = [laid_on(model, (ld,), RunGrid(sea, float(t0), float(dt), int(n_steps), float(ramp),
                                              tuple(float(o) for o in stage_offsets), n_c))[0]
                for sea, dt, ramp in zip(seas, dts, ramps)]
        ld_out, mask = stack_cases(ld, laid)
        out.append(ld_out)
        batched.append(mask)
    return CaseLoads(tuple(out), tuple(batched), B, waves, polar, waves_at=0)


def stack_cases(load: Load, laid: Sequence[Load]) -> tuple[Load, object]:
    """One load of B cases (``laid``, the cases' :meth:`~mfm.loads.base.Load.for_run` of
    ``load``) as one: ``load`` itself with a mask of False where every case gave it back, else the
    cases' leaves stacked on a leading axis where they differ (mask True there). Their structure
    (static fields included) must be one."""
    shared = jax.tree_util.tree_map(lambda _: False, load)
    if all(x is load for x in laid):
        return load, shared
    defs = {jax.tree_util.tree_structure(x) for x in laid}
    if len(defs) > 1:
        raise ValueError(f"load {type(load).__name__}: its for_run gives the cases loads of "
                         "different structures; a batch needs one (give the cases one dt, "
                         "or run them apart)")
    first = laid[0]
    leaves = [jax.tree_util.tree_leaves(x) for x in laid]

    def differs(j):
        a0 = np.asarray(leaves[0][j])
        if any(np.shape(lv[j]) != a0.shape for lv in leaves[1:]):
            raise ValueError(f"load {type(load).__name__}: its for_run gives the cases arrays of "
                             f"different shapes ({sorted({np.shape(lv[j]) for lv in leaves})}); a "
                             "batch stacks them on one case axis (give the cases one dt and "
                             "duration; a load that reads the sea's components pads them to "
                             "RunGrid.n_components, as [[morison]] does; or run them apart with "
                             "mfm.simulate)")
        return any(not np.array_equal(np.asarray(lv[j]), a0) for lv in leaves[1:])

    flags = [differs(j) for j in range(len(leaves[0]))]
    stacked = [np.stack([np.asarray(lv[j]) for lv in leaves]) if f else leaves[0][j]
               for j, f in enumerate(flags)]
    treedef = jax.tree_util.tree_structure(first)
    return (jax.tree_util.tree_unflatten(treedef, stacked),
            jax.tree_util.tree_unflatten(treedef, flags))


def compile_view(model, loads=()):
    """(model, loads) as the compiled functions are handed them: the fields that only the host
    reads blanked — the model's name, config path and hash and its HydroSpec, and each load's own
    (:meth:`~mfm.loads.base.Load.host_view`: the water's spec, a state-space fit's report, a
    convolution's memory length) — so that models and loads that differ only in numbers share one
    compilation (a static field is part of jit's key, compared by value; a HydroSpec by the
    content of its database). Nothing traced reads them: tests/test_jax_contract.py checks that a
    reused compilation gives the bits of a fresh one."""
    return model.keyed(), tuple(ld.host_view() for ld in loads)


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


def initial_states(model, loads: Sequence[Load]):
    """z₀ (Σ n_states,): each load's :meth:`~mfm.loads.base.Load.initial_state` end to end, put
    on the device from numpy (:func:`mfm.backend.device_array`: eager ``jnp.concatenate`` and
    ``jnp.zeros`` would each compile a small program in every first run)."""
    parts = [ld.initial_state(model) for ld in loads]
    if any(isinstance(p, jax.core.Tracer) for p in parts):
        # inside a trace (a rollout under a user's jit or vmap): the traced states as they are
        return jnp.concatenate(parts) if parts else jnp.zeros(0)
    parts = [np.asarray(p, dtype=np.float64) for p in parts]
    return device_array(np.concatenate(parts) if parts else np.zeros(0))


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
