"""The model at rest: its one linearisation, shared by the equilibrium, the frequency domain and
the checks of a time-domain run.

With Q(q, q̇) the generalised loads other than inertia — gravity, the joint spring–dampers and the
loads at rest in still water (:meth:`~mfm.loads.base.Load.static_load`) — jax gives at (q, q̇ = 0)

    K = −∂Q/∂q,   C = −∂Q/∂q̇,   M = M*(q) + Σ (acceleration-proportional loads, A∞ included),

compiled once per model and loads structure (:func:`_static_jet`). From it come:

- the static equilibrium Q(q₀, 0) = 0 (:func:`equilibrium`, Newton on K),
- the linear system about q₀ of every frequency-domain level (:func:`linear_system`),
- the checks of :func:`mfm.simulate` at its q0: the coordinates nothing pulls back
  (:func:`free_coordinates`, ``K_kk`` ≈ 0) and the shortest natural period
  2π/√λ_max(M⁻¹K) of the stability check (:func:`shortest_natural_period`).

"At rest" means in still water and at no particular time. A load whose ``static_load()`` is None
has nothing static and is left out: a time history (:class:`~mfm.loads.CoordinateForceSeries`),
a probe. A time history's value at t = 0 is not part of what restores the model, so it moves
neither the equilibrium nor the natural periods (tests/test_rest.py: a double pendulum under a
torque series keeps its analytic equilibrium and periods).
"""
from __future__ import annotations

import dataclasses
import math
from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from .. import host
from ..backend import device_array
from ..loads.assembly import (RK4_STAGE_OFFSETS, applied_loads, as_loads, carried_loads,
                              compile_view)
from ..mechanics.dynamics import gravity_loads, joint_loads, mass_matrix
from ..mechanics.kinematics import kinematics
from ..mechanics.model import Model
from ..mechanics.points import h_matrix_at
from ..validation import check_model, initial_vector


def still_water_loads(model: Model, loads=None, *, added_mass="lhs",
                      stage_offsets=RK4_STAGE_OFFSETS) -> tuple:
    """The loads of the linearisation: the model's water in still water (no radiation memory: the
    frequency domain adds its radiation as an impedance), the config's loads and ``loads``. Their
    loads at rest have the structure of every run's, whatever its sea, radiation and length
    (:meth:`~mfm.loads.water.Water.static_load` holds no table of the run's length), so one
    compiled linearisation serves them all."""
    return carried_loads(model, None, dt=1.0, duration=1.0, radiation="none",
                         added_mass=added_mass, stage_offsets=stage_offsets,
                         sampled=False) + as_loads(loads)


def system_loads(model: Model, loads=None) -> tuple:
    """:func:`still_water_loads` with the defaults: what the frequency domain linearises."""
    return still_water_loads(model, loads)


def static_loads(loads) -> tuple:
    """Each load at rest (:meth:`~mfm.loads.base.Load.static_load`); those with nothing static
    (None) left out."""
    return tuple(s for s in (ld.static_load() for ld in as_loads(loads)) if s is not None)


def _static_parts(model, static, mems, q, qd):
    """Q(q, q̇) (generalised loads other than inertia) and the acceleration-proportional matrix
    of the loads at rest (None when no load has one)."""
    nz = sum(ld.n_states for ld in static)
    kin = kinematics(model, q, qd)
    body, tau, mass, _ = applied_loads(model, static, 0.0, q, qd, jnp.zeros(nz), kin, mems)
    F = gravity_loads(model) + (0.0 if body is None else body)
    out = jnp.einsum("nai,na->i", kin.B, F) + joint_loads(model, q, qd)
    return (out if tau is None else out + tau), mass


class _Jet(NamedTuple):
    """The model at (q, q̇ = 0) with its loads at rest: Q, ∂Q/∂q, ∂Q/∂q̇ (n_q, n_q), the mass
    M*(q) with the loads' acceleration-proportional terms, the kinematics and the generalised
    weights Bᵀ(m g)."""
    Q: jnp.ndarray
    dQ_dq: jnp.ndarray
    dQ_dqd: jnp.ndarray
    M: jnp.ndarray
    kin: object
    weights: jnp.ndarray


# Compiled once per model structure (model, loads and memories are pytree arguments, not closed
# over): a second equilibrium or linearisation of the same model reuses it. One compilation for
# everything the equilibrium and the linearisation need: one forward-mode jacobian over (q, q̇)
# shares the primal; separate functions for Q, ∂Q/∂q, ∂Q/∂q̇, the masses and the kinematics cost
# about twice the compile time (hallak_fwwp: 49 s → 23 s on the loaded 2-core machine).
@jax.jit
def _static_jet(model, static, mems, q) -> _Jet:
    n = q.shape[0]

    def f(z):
        Q, mass = _static_parts(model, static, mems, z[:n], z[n:])
        return Q, (Q, mass)

    zero = jnp.zeros_like(q)
    J, (Q, mass) = jax.jacfwd(f, has_aux=True)(jnp.concatenate([q, zero]))
    M = mass_matrix(model, q) + (0.0 if mass is None else mass)
    kin = kinematics(model, q, zero)
    return _Jet(Q, J[:, :n], J[:, n:], M, kin, jnp.einsum("nai,na->i", kin.B, gravity_loads(model)))


@jax.jit
def _init_memories(model, static):
    zero = jnp.zeros(model.n_coordinates)
    return tuple(ld.init_memory(model, 0.0, zero, zero, 1.0) for ld in static)


def _static_functions(model: Model, loads):
    """The model and its loads at rest as the compiled functions see them (numbers-only variants
    share one compilation: :func:`mfm.loads.assembly.compile_view`) and the loads' memories,
    ready for :func:`_static_jet`: (model, static, mems)."""
    model, static = compile_view(model, static_loads(loads))
    return model, static, _init_memories(model, static)


def _jet_program(model, static, mems, q):
    """:func:`_static_jet` for these arguments' structure, as the host makes it
    (:meth:`mfm.host.Host.program`; the runner's: from disk where an earlier process traced it):
    called from the host, not inside a trace."""
    return host.current().program(_static_jet, "static_jet", (model, static, mems, q), once=True)


def jet(model: Model, q, loads) -> _Jet:
    """The model's jet at (q, q̇ = 0) under ``loads`` at rest (:func:`_static_jet`)."""
    model, static, mems = _static_functions(model, loads)
    q = jnp.asarray(q, jnp.float64)
    return _jet_program(model, static, mems, q)(model, static, mems, q)


def compile_jet(model: Model, loads, q):
    """Compile :func:`jet` for these loads' structure (for a thread beside other work): a later
    call with loads of the same structure finds it compiled."""
    model, static, mems = _static_functions(model, loads)
    q = jnp.asarray(q, jnp.float64)
    _jet_program(model, static, mems, q).compile(model, static, mems, q)


# ------------------------------------------------------------------------------- equilibrium
def equilibrium(model: Model, q_guess=None, *, loads=None, sea=None, mean_drift=None,
                tol: float = 1e-10, max_iter: int = 50):
    """Static equilibrium q₀ with Q(q₀, 0) = 0 (Newton with the jax Jacobian; least squares where
    nothing restores a coordinate, which then stays at its guess), under the model's own loads and
    ``loads`` (e.g. a :class:`~mfm.loads.JointLoad` preload).

    ``sea`` (a :mod:`hydro` sea state): the mean position in that sea, under the mean wave drift
    force F̄ = Σ_j D(ω_j, β_j) a_j² of the database's ``mean_drift`` besides the loads at rest
    (:meth:`~mfm.loads.water.Water.in_mean_drift`): a moored body's mean offset, about which
    :func:`linear_system` can linearise. The first-order wave forces average to zero there; the
    slow drift's oscillation (Newman) and the nonlinear level's own mean wave force are not in it.
    ``mean_drift``: a table D (omega, wave_direction, influenced_dof) in place of the database's
    (:func:`mfm.equilibrium` passes the drift of the model's own motions where the database has
    the Kochin functions, :mod:`mfm.frequency.drift`).

    Returns (q₀, info) with info = dict(residual, iterations, free: coordinates without
    stiffness). Raises ValueError when no equilibrium is found (a body that cannot float freely
    sinks or capsizes), naming the residual by coordinate.
    """
    model = check_model(model)
    lds = system_loads(model, loads)
    if sea is not None:
        lds = _in_mean_drift(lds, sea, mean_drift)
    elif mean_drift is not None:
        raise ValueError("mfm.equilibrium: mean_drift without sea; give the sea whose mean drift "
                         "it is")
    return _equilibrium(model, lds, q_guess, tol, max_iter)


def _in_mean_drift(loads, sea, mean_drift=None) -> tuple:
    """The loads with each one's mean wave drift in ``sea`` at rest (:meth:`Load.in_mean_drift`:
    the water's, from its database's mean_drift or the table ``mean_drift``)."""
    made = [getattr(ld, "in_mean_drift", lambda _sea, _table: None)(sea, mean_drift)
            for ld in loads]
    if all(m is None for m in made):
        raise ValueError("mfm.equilibrium(sea=...): no load of the model carries a mean wave drift "
                         "force (the water, [hydro]); leave sea out for the equilibrium at rest")
    return tuple(ld if m is None else m for ld, m in zip(loads, made))


def _equilibrium(model, loads, q_guess=None, tol=1e-10, max_iter=50):
    keyed, static, mems = _static_functions(model, loads)
    # the iterate on the host, put on the device from numpy (eager jnp would compile a small
    # program for each operation in every first call); the same IEEE arithmetic
    q = device_array(np.zeros(model.n_coordinates) if q_guess is None
                     else np.asarray(q_guess, np.float64))
    at_q = _jet_program(keyed, static, mems, q)
    jet_at = lambda q: at_q(keyed, static, mems, q)  # noqa: E731
    # the size of the loads that must balance: generalised weights, or the largest weight
    scale = max(float(np.max(np.abs(np.asarray(jet_at(q).weights)))),
                float(np.max(np.asarray(model.mass))) * float(model.gravity))
    it = 0
    q_ok = q
    for it in range(max_iter):
        at = jet_at(q)
        g = np.asarray(at.Q)
        if not np.isfinite(g).all():
            break
        q_ok = q
        if np.abs(g).max() < tol * scale:
            break
        J = np.asarray(at.dQ_dq)
        step = np.linalg.lstsq(J, -g, rcond=1e-10)[0]
        q = device_array(np.asarray(q) + step)
    at = jet_at(q)
    g = np.asarray(at.Q)
    if not np.isfinite(g).all():
        # a load undefined there (a catenary line's fairlead outside its table): say which
        for q_at in (q, q_ok):
            for ld in loads:
                cause = ld.describe_nonfinite(model, np.asarray(q_at), np.zeros(model.n_coordinates))
                if cause:
                    raise ValueError(f"no static equilibrium of {model.name!r} found: the static "
                                     f"loads went non-finite at q = {np.asarray(q).tolist()}. {cause}")
    J = np.asarray(at.dQ_dq)
    free = [model.coordinates[k] for k in range(model.n_coordinates)
            if np.abs(J[:, k]).max() < 1e-12 * scale]
    if not np.isfinite(g).all() or np.abs(g).max() > 1e-6 * scale:
        bad = {model.coordinates[k]: float(g[k]) for k in np.argsort(-np.abs(g))[:3]}
        raise ValueError(f"no static equilibrium of {model.name!r} found from the guess: residual "
                         f"generalised loads {bad} (N or N m). A body whose weight its buoyancy "
                         "cannot carry sinks; one whose centre of mass is too high capsizes.")
    return np.asarray(q), {"residual": float(np.abs(g).max()), "iterations": it, "free": free}


# ------------------------------------------------------------------------------- the linear system
class LinearSystem(NamedTuple):
    """The model linearised about q₀: M, K, C (n_q, n_q) (M with the loads' acceleration-
    proportional terms, A∞ included), the kinematics at q₀ and the loads it was made from."""
    q0: np.ndarray
    M: np.ndarray
    K: np.ndarray
    C: np.ndarray
    kin0: object
    loads: tuple


def linear_system(model: Model, q0=None, *, loads=None) -> LinearSystem:
    """Linearise the model with its loads (:func:`system_loads`) about q₀ (default: the
    equilibrium)."""
    model = check_model(model)
    lds = system_loads(model, loads)
    return _linear_system(model, lds, q0)


def _linear_system(model, lds, q0=None):
    if q0 is None:
        q0, _ = _equilibrium(model, lds)
    at = jet(model, q0, lds)
    return LinearSystem(np.asarray(q0, dtype=float), np.asarray(at.M), -np.asarray(at.dQ_dq),
                        -np.asarray(at.dQ_dqd), at.kin, lds)


def linearise(model: Model, q0=None, *, loads=None):
    """(q₀, M₀, K, C, H₀): the structural mass M*(q₀), stiffness and linear damping (n_q, n_q)
    about the equilibrium, and the hydro Jacobian H₀ (6K, n_q) (None without water)."""
    sys = linear_system(model, q0, loads=loads)
    M0 = np.asarray(mass_matrix(model, jnp.asarray(sys.q0)))
    water = linear_hydro(sys.loads)
    H0 = None if water is None else np.asarray(h_matrix_at(water.geometry, sys.kin0))
    return sys.q0, M0, sys.K, sys.C, H0


def linear_hydro_index(loads) -> int | None:
    """Where among ``loads`` the one that carries a linear potential-flow model is
    (:meth:`~mfm.loads.base.Load.linear_hydro`), or None. Two such loads are refused: the levels
    built on it read one BEM model."""
    found = [k for k, ld in enumerate(loads) if ld.linear_hydro() is not None]
    if len(found) > 1:
        raise ValueError("loads: " + ", ".join(type(loads[k]).__name__ for k in found)
                         + " each carry a linear potential-flow model (linear_hydro); the spectral "
                         "and linear levels read one: give the model one [hydro] table")
    return found[0] if found else None


def linear_hydro(loads):
    """The :class:`~mfm.loads.base.LinearHydro` of ``loads`` (:func:`linear_hydro_index`), or
    None."""
    k = linear_hydro_index(loads)
    return None if k is None else loads[k].linear_hydro()


def linearise_lines(model: Model, q0=None) -> Model:
    """``model`` with each of its :class:`~mfm.loads.CatenaryLines` loads replaced by
    :meth:`~mfm.loads.CatenaryLines.linearised` about ``q0`` (default: the static equilibrium of
    the model, :func:`equilibrium`). Raises ValueError when the model has no catenary lines."""
    from ..loads.catenary import CatenaryLines

    if not any(isinstance(ld, CatenaryLines) for ld in model.loads):
        raise ValueError(f"model: {model.name!r} has no [[catenary_lines]] to linearise")
    if q0 is None:
        q0 = equilibrium(model)[0]
    loads = tuple(ld.linearised(model, q0) if isinstance(ld, CatenaryLines) and not ld.linear else ld
                  for ld in model.loads)
    return dataclasses.replace(model, loads=loads)


# ------------------------------------------------------------------------------- a run's checks
def linearised_at_rest(model: Model, q, loads=()) -> tuple[np.ndarray, np.ndarray]:
    """(J, K), each (n_q, n_q), at configuration q, q̇ = 0 with ``loads`` at rest: the static
    stiffness K = −∂Q/∂q of the generalised loads Q (gravity, buoyancy, water plane, moorings,
    joint springs) and J = −M⁻¹K, the q̈ ≈ J δq of a small displacement δq about q in the linear
    system of :func:`linear_system` (its eigenvalues give the stability check's periods)."""
    at = jet(model, q, loads)
    M, K = np.asarray(at.M), -np.asarray(at.dQ_dq)
    return -np.linalg.solve(M, K), K


def free_coordinates(model: Model, K) -> list[str]:
    """The coordinates nothing pulls back: K_kk ≤ 1e-9 of the largest |K| for the static
    stiffness K (:func:`linearised_at_rest`), i.e. displaced alone, q_k feels no load back towards
    where it was. An unmoored body's surge (RM3's spar, the M4's bow float: a column of exact
    zeros) drifts after the start-up transient under wave drift and any mean load; K_kk < 0 (a
    slider on a hanging arm) is unstable alone. Where K is positive semi-definite, K_kk = 0 means
    the whole column is zero. 1e-9: far below any restoring entry of the shipped configs (the
    smallest is ≥ 1e-5 of their largest) and far above the round-off of a zero one."""
    K = np.asarray(K)
    scale = max(float(np.abs(K).max()), 1e-300)
    return [c for k, c in enumerate(model.coordinates) if float(K[k, k]) <= 1e-9 * scale]


def no_restoring(model: Model, q0=None, *, loads=None) -> list[str]:
    """The coordinates of ``model`` nothing pulls back at q0 (default 0, the start of
    :func:`mfm.simulate` and ``mfm simulate`` without ``--initial``), under its own loads in still
    water and ``loads`` (:func:`free_coordinates`): what ``mfm info`` reports, and what
    :func:`mfm.simulate` records in its ``no_restoring`` attribute for a run from the same q0 with
    the same extra loads, whatever its sea."""
    _, K = linearised_at_rest(model, initial_vector(model, q0, "q0"),
                              still_water_loads(model, loads))
    return free_coordinates(model, K)


def shortest_natural_period(model: Model, q, loads=()) -> float:
    """Estimate of the shortest natural period (s) at configuration q (q̇ = 0): 2π/√λ_max with λ
    the eigenvalues of M⁻¹K (:func:`linearised_at_rest`: the mass matrix, added mass included,
    and every restoring load). Returns inf when nothing is restoring."""
    return period_from_jacobian(linearised_at_rest(model, q, loads)[0])


def period_from_jacobian(J) -> float:
    """2π/√λ_max for λ the eigenvalues of −J (inf when none is positive)."""
    lam = np.linalg.eigvals(-np.asarray(J)).real
    lam_max = lam.max() if lam.size else 0.0
    return math.inf if lam_max <= 0 else 2.0 * math.pi / math.sqrt(lam_max)
