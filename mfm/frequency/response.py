"""Frequency domain: static equilibrium, linearisation of the same model, RAOs, natural frequencies.

The model of :func:`mfm.simulate`, with exactly the loads it carries (its water, its config's
loads, and any ``loads=``), is linearised about its static equilibrium q₀ (DESIGN §4). With Q(q, q̇)
the generalised loads other than inertia (gravity, the loads at rest in still water —
:meth:`~mfm.loads.base.Load.static_load` — and the joint spring–dampers), jax gives

    K = −∂Q/∂q,   C = −∂Q/∂q̇   at (q₀, 0),   M = M*(q₀) + Σ (acceleration-proportional loads),

and each load adds what has memory or comes from the waves (:meth:`Load.frequency_terms`): the
water its radiation impedance −ω² Hᵀ(A(ω) − A∞)H − iω HᵀB(ω)H and its wave force Hᵀ X(ω, β).
With x(t) = Re[x̂ e^{−iωt}] (the hydro databases' convention):

    Z(ω) x̂ = F(ω),   Z(ω) = −ω² M − iω C + K + Σ Z_load(ω).

x̂ per metre of wave amplitude is the RAO of every coordinate; bodies, hydro dofs, PTOs and named
points follow from the same Jacobians. Quadratic drag has zero slope at rest (it drops out).
"""
from __future__ import annotations

import math
from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from .. import results
from ..mechanics.dynamics import Evaluation, gravity_loads, joint_loads, mass_matrix, reaction_loads
from ..mechanics.kinematics import kinematics
from ..mechanics.model import Model


def _as_loads(loads):
    from ..timedomain.simulation import _as_loads as as_loads

    return as_loads(loads)


def system_loads(model: Model, loads=None) -> tuple:
    """The loads of the linearisation: the model's water in still water (no radiation memory: the
    frequency domain adds its radiation as an impedance), the config's loads and ``loads``."""
    from ..timedomain.simulation import model_loads

    return model_loads(model, None, dt=1.0, duration=1.0, radiation="none") + _as_loads(loads)


def _static_parts(model, static, mems, q, qd):
    """Q(q, q̇) (generalised loads other than inertia) and the acceleration-proportional matrix
    of the loads at rest (None when no load has one)."""
    from ..timedomain.simulation import applied_loads

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


def _static_functions(model: Model, loads):
    """The loads at rest (:meth:`Load.static_load`) and their memories, ready for the compiled
    functions above: (static, mems)."""
    static = tuple(s for s in (ld.static_load() for ld in loads) if s is not None)
    return static, _init_memories(model, static)


@jax.jit
def _init_memories(model, static):
    zero = jnp.zeros(model.n_coordinates)
    return tuple(ld.init_memory(model, 0.0, zero, zero, 1.0) for ld in static)


def equilibrium(model: Model, q_guess=None, *, loads=None, tol: float = 1e-10, max_iter: int = 50):
    """Static equilibrium q₀ with Q(q₀, 0) = 0 (Newton with the jax Jacobian; least squares where
    nothing restores a coordinate, which then stays at its guess), under the model's own loads and
    ``loads`` (e.g. a :class:`~mfm.loads.JointLoad` preload).

    Returns (q₀, info) with info = dict(residual, iterations, free: coordinates without
    stiffness). Raises ValueError when no equilibrium is found (a body that cannot float freely
    sinks or capsizes), naming the residual by coordinate.
    """
    return _equilibrium(model, system_loads(model, loads), q_guess, tol, max_iter)


def _equilibrium(model, loads, q_guess=None, tol=1e-10, max_iter=50):
    static, mems = _static_functions(model, loads)
    jet = lambda q: _static_jet(model, static, mems, q)  # noqa: E731
    q = jnp.zeros(model.n_coordinates) if q_guess is None else jnp.asarray(q_guess, jnp.float64)
    # the size of the loads that must balance: generalised weights, or the largest weight
    scale = max(float(jnp.max(jnp.abs(jet(q).weights))),
                float(jnp.max(model.mass)) * float(model.gravity))
    it = 0
    q_ok = q
    for it in range(max_iter):
        at = jet(q)
        g = np.asarray(at.Q)
        if not np.isfinite(g).all():
            break
        q_ok = q
        if np.abs(g).max() < tol * scale:
            break
        J = np.asarray(at.dQ_dq)
        step = np.linalg.lstsq(J, -g, rcond=1e-10)[0]
        q = q + jnp.asarray(step)
    at = jet(q)
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
    lds = system_loads(model, loads)
    return _linear_system(model, lds, q0)


def _linear_system(model, lds, q0=None):
    if q0 is None:
        q0, _ = _equilibrium(model, lds)
    q0 = jnp.asarray(q0, jnp.float64)
    static, mems = _static_functions(model, lds)
    jet = _static_jet(model, static, mems, q0)
    return LinearSystem(np.asarray(q0), np.asarray(jet.M), -np.asarray(jet.dQ_dq),
                        -np.asarray(jet.dQ_dqd), jet.kin, lds)


def linearise(model: Model, q0=None, *, loads=None):
    """(q₀, M₀, K, C, H₀): the structural mass M*(q₀), stiffness and linear damping (n_q, n_q)
    about the equilibrium, and the hydro Jacobian H₀ (6K, n_q) (None without water)."""
    sys = linear_system(model, q0, loads=loads)
    M0 = np.asarray(mass_matrix(model, jnp.asarray(sys.q0)))
    water = _water(sys.loads)
    H0 = None if water is None else np.asarray(water.geometry.h_matrix(sys.kin0)[0])
    return sys.q0, M0, sys.K, sys.C, H0


def _water(loads):
    from ..loads.water import Water

    return next((ld for ld in loads if isinstance(ld, Water)), None)


def _terms(model, sys, omega, heading, options):
    """Σ of the loads' impedances (n_ω, n_q, n_q) and wave forces (n_ω, n_q)."""
    n = model.n_coordinates
    Z = np.zeros((len(omega), n, n), dtype=complex)
    F = np.zeros((len(omega), n), dtype=complex)
    for ld in sys.loads:
        t = ld.frequency_terms(model, sys.q0, sys.kin0, omega, heading, options)
        if t.impedance is not None:
            Z = Z + t.impedance
        if t.force is not None:
            F = F + t.force
    return Z, F


def _amplitudes(model, sys, omega, heading, options):
    """x̂ (n_ω, n_q) per metre of wave amplitude: [−ω² M − iω C + K + Σ Z_load(ω)] x̂ = F(ω, β)."""
    Zl, F = _terms(model, sys, omega, heading, options)
    w = omega[:, None, None]
    Z = -w**2 * sys.M[None] - 1j * w * sys.C[None] + sys.K[None] + Zl
    return np.linalg.solve(Z, F[..., None])[..., 0]


def _reaction_function(model, loads):
    """The joint reactions of :func:`mfm.simulate` (``_record``: every load's
    :meth:`~mfm.loads.base.Load.reaction_loads` on the bodies, gravity, then
    :func:`mfm.mechanics.dynamics.reaction_loads`) as a function R(q, q̇, q̈) → (n, 6) [force; moment about
    the joint point], inertial axes, with the loads at rest in still water (their static loads):
    the joint springs and dampers, and loads acting on the coordinates directly, reach the joints
    through each body's Newton–Euler residual, as in the time domain."""
    from ..timedomain.simulation import _state_offsets, applied_loads
    from ..loads.base import Context

    static, mems = _static_functions(model, loads)
    offs = _state_offsets(static)
    z = jnp.zeros(int(offs[-1]))

    def R(q, qd, qdd):
        kin = kinematics(model, q, qd)
        _, _, _, _, outs = applied_loads(model, static, 0.0, q, qd, z, kin, mems, with_outputs=True)
        F = gravity_loads(model)
        for k, (ld, out) in enumerate(zip(static, outs)):
            ctx = Context(model, 0.0, q, qd, z[offs[k]:offs[k + 1]], kin, mems[k], None, qdd)
            Fk = ld.reaction_loads(ctx, out)
            if Fk is not None:
                F = F + Fk
        Xdot = jnp.einsum("nai,i->na", kin.B, qdd) + kin.bias
        f, m = reaction_loads(model, Evaluation(qdd=qdd, kin=kin, X=kin.X, Xdot=Xdot, F=F, Q=None))
        return jnp.concatenate([f, m], axis=1)

    return R


@jax.jit
def _reaction_derivatives(model, loads, q0):
    """R(q₀, 0, 0) and ∂R/∂q, ∂R/∂q̇, ∂R/∂q̈ there (compiled once per model structure)."""
    R = _reaction_function(model, loads)
    zero = jnp.zeros_like(q0)
    return R(q0, zero, zero), jax.jacfwd(R, argnums=(0, 1, 2))(q0, zero, zero)


def _joint_reactions(model, sys, omega, heading, options, x):
    """(static (n, 6), complex amplitudes (n_ω, n, 6)): see :func:`joint_reactions`."""
    static, (Jq, Jv, Ja) = jax.tree_util.tree_map(
        np.asarray, _reaction_derivatives(model, sys.loads, jnp.asarray(sys.q0, jnp.float64)))
    w = omega[:, None, None, None]
    D = Jq[None] - 1j * w * Jv[None] - w**2 * Ja[None]           # (n_ω, n, 6, n_q)
    out = np.einsum("wnai,wi->wna", D, x)
    n = model.n_bodies
    zeros6 = jnp.zeros((n, 6))

    def of_wrench(W):
        """The reactions that balance extra body loads W (n, 6) at q₀, the bodies at rest."""
        f, m = reaction_loads(model, Evaluation(qdd=None, kin=sys.kin0, X=zeros6, Xdot=zeros6,
                                                F=W, Q=None))
        return jnp.concatenate([f, m], axis=1)

    L = None   # the linear map of_wrench as a matrix (n, 6, n, 6): one jacobian, not one call per ω
    for ld in sys.loads:
        W = ld.frequency_body_loads(model, sys.q0, sys.kin0, omega, heading, options, x)
        if W is None:
            continue
        if L is None:
            L = np.asarray(jax.jacfwd(of_wrench)(zeros6))
        out = out + np.einsum("naKb,wKb->wna", L, W)
    return static, out


def joint_reactions(model: Model, omega, x, *, heading: float = 0.0, q0=None, loads=None,
                    radiation: str = "database", state_space_options: dict | None = None):
    """The loads each joint transmits (the time domain's ``joint_force`` and ``joint_moment``: from
    the parent, or the inertial frame, to the body; inertial axes; moment about the joint point),
    linearised about q₀ for the coordinate amplitudes x (n_ω, n_q) (x(t) = Re[x̂ e^{−iωt}]).

    With R(q, q̇, q̈) the reactions of the time domain (:func:`mfm.mechanics.dynamics.reaction_loads` of each
    body's Newton–Euler residual M_i Ẋ_i + ω × J ω − F_i, summed from the leaves) under the loads
    at rest (gravity, hydrostatics and buoyancy, A∞, PTO μ/β/κ, joint springs and dampers),

        R̂(ω) = (∂R/∂q − iω ∂R/∂q̇ − ω² ∂R/∂q̈) x̂ + L(Ŵ(ω)),

    all derivatives at (q₀, 0, 0) (jax), Ŵ(ω) the body loads of each load's frequency terms
    (:meth:`~mfm.loads.base.Load.frequency_body_loads`: the water's excitation X(ω, β) and its
    radiation memory −[−ω²(A(ω) − A∞) − iωB(ω)] H₀ x̂) and L the (linear) reaction that balances a
    body load on bodies at rest. Products of two first-order quantities (the rotation of a
    first-order load, Ḣq̇, gyroscopic terms) are second order and drop out; the static preload
    R(q₀, 0, 0) is returned separately.

    Along a joint's free directions the result is the joint's own generalised load (its spring and
    damper: −(k − iωc) x̂ for a hinge); across them, the constraint load.

    Returns (static (n_bodies, 6) N and N m, amplitudes (n_ω, n_bodies, 6) N/m and N m/m per metre of
    wave amplitude when x is a RAO); the last axis is (fx, fy, fz, mx, my, mz). Raises
    NotImplementedError naming a load whose frequency terms cannot be put on the bodies.
    """
    omega = np.atleast_1d(np.asarray(omega, dtype=float))
    x = np.asarray(x)
    if x.shape != (omega.size, model.n_coordinates):
        raise ValueError(f"x: shape {x.shape}; expected (n_omega, n_coordinates) = "
                         f"({omega.size}, {model.n_coordinates})")
    sys = linear_system(model, q0, loads=loads)
    options = {"radiation": radiation, "state_space_options": state_space_options}
    return _joint_reactions(model, sys, omega, float(heading), options, x)


def frequency_response(model: Model, omega, heading: float = 0.0, *, q0=None,
                       radiation: str = "database", state_space_options: dict | None = None,
                       loads=None, joint_reactions: bool = True):
    """Complex RAOs (per metre of wave amplitude, x(t) = Re[x̂ e^{−iωt}]) of every coordinate,
    body (CoM displacement and small rotation, inertial axes), hydro dof and PTO, with the absorbed
    power per unit wave amplitude squared, from the model linearised about its equilibrium with
    every load it carries and ``loads``.

    omega: rad/s, inside the database's range. heading: rad (direction the waves travel to,
    from +x towards +y).
    radiation: which A(ω), B(ω): "database" (the BEM values), or exactly those of the time-domain
    models, "convolution" or "state_space" (:mod:`mfm.loads.radiation`); ``state_space_options``
    as given to :func:`mfm.simulate` (the same options give the same fit).

    Returns an xarray.Dataset: ``rao`` (omega, coordinate), ``body_rao`` (omega, body, dof) with
    dof = x, y, z, rx, ry, rz, ``xi_rao`` (omega, hydro_dof), ``pto_rao`` and ``pto_power``
    (omega, pto) (W/m², mean power ½ c ω² |x̂|²), the loads' own outputs (``hydraulic_pto_power``,
    ``point_rao``, ``hydraulic_pto_force_rao``, …), ``equilibrium`` (coordinate); with
    ``joint_reactions`` (default) ``joint_force_rao`` and ``joint_moment_rao`` (omega, body, axis)
    per metre of wave amplitude and the static preload ``joint_force_static``,
    ``joint_moment_static`` (body, axis) (:func:`joint_reactions`).
    """
    if model.hydro is None:
        raise ValueError(f"model {model.name!r} has no hydrodynamics: frequency_response needs a "
                         "config with a [hydro] table (and mfm.load(..., hydro=True))")
    try:
        omega = np.atleast_1d(np.asarray(omega, dtype=float))
    except (TypeError, ValueError):
        raise ValueError(f"omega: {omega!r} is not an array of frequencies (rad/s)") from None
    if omega.ndim != 1 or omega.size == 0 or not np.all(np.isfinite(omega)) or np.any(omega <= 0):
        raise ValueError(f"omega: give positive, finite frequencies in rad/s (got {omega!r})")
    heading = float(heading)
    options = {"radiation": radiation, "state_space_options": state_space_options}
    sys = linear_system(model, q0, loads=loads)
    x = _amplitudes(model, sys, omega, heading, options)
    extra = [ld.frequency_outputs(model, sys.kin0, x, omega) for ld in sys.loads]
    reactions = _joint_reactions(model, sys, omega, heading, options, x) if joint_reactions else None
    settings = {"radiation": radiation}
    if state_space_options:
        settings["state_space_options"] = repr(state_space_options)
    return results.frequency(model, sys.loads, omega, x, sys.q0, sys.kin0, heading, settings,
                             [e for e in extra if e], reactions)


def _frequency_range(loads):
    lo, hi = 0.0, math.inf
    for ld in loads:
        r = ld.frequency_range()
        if r is not None:
            lo, hi = max(lo, r[0]), min(hi, r[1])
    return lo, hi


def _mass_and_damping_at(model, sys, w, options):
    """M(ω) = M + Re Σ Z_load(ω)/(−ω²) and the loads' damping −Im Σ Z_load(ω)/ω at ω clipped to
    where every load is defined (A(ω) held at the ends of a database)."""
    lo, hi = _frequency_range(sys.loads)
    wc = np.clip(np.atleast_1d(w), lo, hi)
    Z, _ = _terms(model, sys, wc, 0.0, dict(options, excitation=False))
    return sys.M[None] + Z.real / (-wc[:, None, None] ** 2), -Z.imag / wc[:, None, None]


def natural_frequencies(model: Model, omega_grid=None, *, q0=None, iterations: int = 30,
                        loads=None, radiation: str = "database"):
    """Natural frequencies (rad/s) and damping ratios, two ways.

    eigen: the generalised eigenproblem K φ = ω² M(ω) φ, M(ω) = M + Hᵀ(A(ω) − A∞)H, iterated on ω
        for each mode (A at that mode's own frequency); coordinates without stiffness have no mode
        of their own and move freely with the others (condensed out of the mass:
        M_ss − M_sf M_ff⁻¹ M_fs, the free part of each mode shape −M_ff⁻¹ M_fs φ_s).
    min_det: local minima of |det Λ(ω)|, Λ = −ω² M_eff(ω) + K_ss, over ``omega_grid``
        (seed 000 §2.10), refined parabolically.
    min_det_damped: the same with the damping kept (seed 000 eq. 27's remark):
        |det(−ω² M(ω) − iω (C + B(ω)) + K)|, B(ω) the radiation damping, C the joint, PTO and
        body-matrix damping, free coordinates condensed out dynamically; refined by a bounded
        search (:func:`_damped_minima`). These are the peaks of the response to a force of
        constant amplitude, not the damped natural frequencies ω_n √(1 − ζ²) of free decay: for
        one dof |det|² = (k − mω²)² + (cω)², and d/d(ω²) = 0 gives
        ω² = (2km − c²)/(2m²) = ω_n² (1 − 2ζ²), ζ = c / (2√(km)). Seed 000 eq. 32 writes
        ω_n √(1 − ζ²) there, which is the free-decay frequency, not the minimum.
    damping_ratio: φᵀ C φ / (2 ω φᵀ M(ω) φ) of each mode for the linear damping C (joint dampers,
        hydraulic β, body matrices); radiation_damping_ratio the same with Hᵀ B(ω) H.

    Returns an xarray.Dataset: ``eigen``, ``period``, ``damping_ratio``,
    ``radiation_damping_ratio``, ``damped`` (mode), ``modes`` (coordinate, mode), ``min_det``
    (root), ``min_det_damped`` (root_damped); it reads like the former dict (``nat["eigen"]``).
    """
    import scipy.linalg

    options = {"radiation": radiation}
    sys = linear_system(model, q0, loads=loads)
    K = sys.K
    lo, hi = _frequency_range(sys.loads)
    stiff = [k for k in range(model.n_coordinates) if np.abs(K[:, k]).max() > 1e-9 * np.abs(K).max()]
    # coordinates without stiffness move freely with the modes (a floating body's surge under
    # its pitch): condensed out of the mass, M_ss − M_sf M_ff⁻¹ M_fs, not clamped
    free = [k for k in range(model.n_coordinates) if k not in stiff]
    ix = np.ix_(stiff, stiff)
    Ks = K[ix]
    n = len(stiff)

    def condensed(Mw):
        """(M_eff (n, n), G (n_free, n)): the free coordinates follow as x_f = G x_s."""
        if not free:
            return Mw[ix], np.zeros((0, n))
        G = -np.linalg.solve(Mw[np.ix_(free, free)], Mw[np.ix_(free, stiff)])
        return Mw[ix] + Mw[np.ix_(stiff, free)] @ G, G

    def M_at(w):
        return _mass_and_damping_at(model, sys, w, options)[0][0]

    freqs, modes, zeta, zeta_rad = [], [], [], []
    w_start = hi if math.isfinite(hi) else 1.0
    lam0 = scipy.linalg.eigh(Ks, condensed(M_at(w_start))[0], eigvals_only=True) if n else []
    for m in range(n):
        w = math.sqrt(max(lam0[m], 1e-30))
        for _ in range(iterations):
            Me, G = condensed(M_at(w))
            lam, vec = scipy.linalg.eigh(Ks, Me)
            w_new = math.sqrt(max(lam[m], 1e-30))
            if abs(w_new - w) < 1e-10 * w:
                break
            w = w_new
        freqs.append(w)
        v = np.zeros(model.n_coordinates)
        v[stiff] = vec[:, m]
        v[free] = G @ vec[:, m]
        modes.append(v)
        Mw, Cr = _mass_and_damping_at(model, sys, w, options)
        mm = float(v @ Mw[0] @ v)
        zeta.append(float(v @ sys.C @ v) / (2 * w * mm))
        zeta_rad.append(float(v @ Cr[0] @ v) / (2 * w * mm))
    if omega_grid is None:
        top = hi if math.isfinite(hi) else 3.0 * max(freqs, default=1.0)
        grid = np.linspace(lo if lo > 0 else top / 2000, top, 2000)
    else:
        grid = np.asarray(omega_grid, dtype=float)
    Mg = _mass_and_damping_at(model, sys, grid, options)[0] if n else np.zeros((len(grid), 0, 0))
    det = np.array([abs(np.linalg.det(-w**2 * condensed(Mg[i])[0] + Ks)) for i, w in enumerate(grid)])
    mins = []
    for i in range(1, len(grid) - 1):
        if det[i] < det[i - 1] and det[i] <= det[i + 1]:
            # parabola through the log|det| of three points
            y0, y1, y2 = np.log(det[i - 1:i + 2] + 1e-300)
            h = grid[i + 1] - grid[i]
            den = y0 - 2 * y1 + y2
            mins.append(grid[i] + (0.5 * h * (y0 - y2) / den if den > 0 else 0.0))
    mins_damped = _damped_minima(model, sys, grid, stiff, free, options)
    modes = np.array(modes).T if modes else np.zeros((model.n_coordinates, 0))
    return results.natural(model, sys.loads, np.array(freqs), modes, np.array(zeta),
                           np.array(zeta_rad), np.array(mins), {"radiation": radiation},
                           min_det_damped=np.array(mins_damped))


def _damped_minima(model, sys, grid, stiff, free, options):
    """Local minima over ``grid`` of |det Λ_d(ω)|, Λ_d = −ω² M(ω) − iω (C + B(ω)) + K, the free
    coordinates condensed out dynamically (Schur complement Λ_ss − Λ_sf Λ_ff⁻¹ Λ_fs, which is the
    undamped condensation when C = B = 0), each refined by a bounded Brent search on log|det|
    between its grid neighbours (|det Λ_d| is smooth at a damped minimum: no cusp)."""
    import scipy.optimize

    if not stiff:
        return []
    ss, sf, fs, ff = (np.ix_(a, b) for a, b in ((stiff, stiff), (stiff, free), (free, stiff),
                                                 (free, free)))

    def log_det(w):
        w = np.atleast_1d(np.asarray(w, dtype=float))
        Mw, Cr = _mass_and_damping_at(model, sys, w, options)
        W = w[:, None, None]
        L = -W**2 * Mw - 1j * W * (sys.C[None] + Cr) + sys.K[None]
        if free:
            L = L[(slice(None),) + ss] - L[(slice(None),) + sf] @ np.linalg.solve(
                L[(slice(None),) + ff], L[(slice(None),) + fs])
        return np.linalg.slogdet(L)[1]

    y = log_det(grid)
    out = []
    for i in range(1, len(grid) - 1):
        if y[i] < y[i - 1] and y[i] <= y[i + 1]:
            r = scipy.optimize.minimize_scalar(lambda w: float(log_det(w)[0]),
                                               bounds=(grid[i - 1], grid[i + 1]), method="bounded",
                                               options={"xatol": 1e-12 * grid[i]})
            out.append(float(r.x))
    return out


def cubic_natural_frequencies(M, K):
    """The three natural frequencies (rad/s, ascending) of a 3-dof undamped system with constant
    mass M and stiffness K (3, 3), from the cubic of seed 000 §2.11 (eqs. 37–44):

        P(λ) = det(K − λM) = â λ³ + b̂ λ² + ĉ λ + d̂,   λ = ω²,
        â = −det M,  b̂ = tr(adj(M) K),  ĉ = −tr(adj(K) M),  d̂ = det K

    (the expansion det(A + tB) = det A + t tr(adj(A) B) + t² tr(A adj(B)) + t³ det B). Its
    discriminant Δ₃ = 18âb̂ĉd̂ − 4b̂³d̂ + b̂²ĉ² − 4âĉ³ − 27â²d̂² (eq. 40) is > 0 for three distinct
    real roots; with Δ₀ = b̂² − 3âĉ, Δ₁ = 2b̂³ − 9âb̂ĉ + 27â²d̂ (eqs. 43, 44) Cardano's E of eq. 42
    is complex there, |E| = √Δ₀, arg E = φ/3 with cos φ = Δ₁ / (2 Δ₀^{3/2}), and eq. 41 becomes
    the trigonometric form

        λ_k = −(b̂ + 2 √Δ₀ cos((φ + 2πk)/3)) / (3â),   k = 0, 1, 2,

    (real arithmetic, no cancellation of complex parts). Each root is then polished by Newton
    steps on P itself. For symmetric M positive definite and symmetric K the roots are the
    generalised eigenvalues of (K, M): real; positive when K is positive definite.

    Raises ValueError when M or K is not a finite 3×3 matrix, when det M = 0 (no cubic), when
    Δ₃ < 0 (complex roots: M and K are not a symmetric pair with M positive definite) or when a
    root ω² ≤ 0 (K not positive definite: a mode without restoring stiffness, or unstable).
    """
    M = np.asarray(M, dtype=float)
    K = np.asarray(K, dtype=float)
    for name, A in (("M", M), ("K", K)):
        if A.shape != (3, 3) or not np.isfinite(A).all():
            raise ValueError(f"{name}: give a finite 3×3 matrix (got shape {A.shape}); the cubic "
                             "is for three coordinates (reduce the model first)")

    def adj(A):
        """The adjugate: the transposed cofactors (defined for a singular A too)."""
        return np.array([[(-1) ** (i + j) * np.linalg.det(np.delete(np.delete(A, j, 0), i, 1))
                          for j in range(3)] for i in range(3)])

    detM = np.linalg.det(M)
    if not abs(detM) > 1e-14 * np.abs(M).max() ** 3:
        raise ValueError(f"M: det M = {detM:.4g}: singular, so det(K − ω²M) is not a cubic in ω² "
                         "(a coordinate without inertia); give a positive definite mass matrix")
    a, b, c, d = -detM, np.trace(adj(M) @ K), -np.trace(adj(K) @ M), np.linalg.det(K)
    disc = 18 * a * b * c * d - 4 * b**3 * d + b**2 * c**2 - 4 * a * c**3 - 27 * a**2 * d**2
    d0 = b**2 - 3 * a * c
    d1 = 2 * b**3 - 9 * a * b * c + 27 * a**2 * d
    # scale of Δ₃ (each of its terms is of the size of (b̂ĉ)²): below it, a rounding of a double root
    scale = max(abs(18 * a * b * c * d), abs(b**3 * d), (b * c) ** 2, abs(a * c**3), (a * d) ** 2)
    if disc < -1e-10 * scale:
        raise ValueError(f"M, K: the cubic det(K − ω²M) has complex roots (discriminant Δ₃ = "
                         f"{disc:.4g} < 0): M and K are not a symmetric pair with M positive "
                         "definite")
    cos_phi = np.clip(d1 / (2 * max(d0, 0.0) ** 1.5), -1.0, 1.0) if d0 > 0 else 1.0
    phi = math.acos(cos_phi)
    lam = np.array([-(b + 2 * math.sqrt(max(d0, 0.0)) * math.cos((phi + 2 * math.pi * k) / 3))
                    / (3 * a) for k in range(3)])
    for _ in range(3):            # Newton on P: the rounding of the trigonometric form away
        P = ((a * lam + b) * lam + c) * lam + d
        dP = (3 * a * lam + 2 * b) * lam + c
        step = np.where(np.abs(dP) > 0, P / np.where(dP == 0, 1.0, dP), 0.0)
        lam = lam - step
    lam = np.sort(lam)
    if not lam[0] > 0:
        raise ValueError(f"K: the cubic det(K − ω²M) has the root ω² = {lam[0]:.4g} ≤ 0: K is not "
                         "positive definite (a mode without restoring stiffness, or an unstable "
                         "one); remove free coordinates first")
    return np.sqrt(lam)


def critical_damping(model: Model, body: str, mode: str, ratio: float, *, point=None,
                     loads=None, iterations: int = 30) -> float:
    """The damping coefficient (N s/m or N m s/rad) that is ``ratio`` of critical for one
    single-body mode of ``body`` (surge … yaw at ``point``, default its CoM), from the model's own
    linearisation: with φ the least-norm coordinate motion that moves that dof of the point by one
    unit, k = φᵀKφ, m(ω) = φᵀM(ω)φ (added mass at the mode's frequency, iterated), it is
    c = 2 ζ √(k m). Used by ``[[body_matrices]] damping_ratio``."""
    from ..loads.base import MODES
    from ..mechanics.points import BodyPoints

    j = MODES.index(mode)
    i = model.body_index(body)
    pt = np.asarray(model.com[i]) if point is None else np.asarray(point, dtype=float)
    sys = linear_system(model, loads=loads)
    Hp = np.asarray(BodyPoints.on_bodies(model.com, [i], [pt]).h_matrix(sys.kin0)[0])
    phi = np.linalg.pinv(Hp)[:, j]
    moved = float((Hp @ phi)[j]) if phi.size else 0.0
    if abs(moved) < 1e-9:
        raise ValueError(f"damping_ratio.{mode} of body {body!r}: no coordinate of the model moves "
                         f"that body in {mode}; give damping for the modes it has")
    phi = phi / moved
    k = float(phi @ sys.K @ phi)
    if not k > 0:
        raise ValueError(f"damping_ratio.{mode} of body {body!r}: the mode has no restoring "
                         f"stiffness (φᵀKφ = {k:.4g}), so critical damping is undefined; give the "
                         "damping in N s/m (or N m s/rad) instead")
    w = math.sqrt(k / float(phi @ sys.M @ phi))
    for _ in range(iterations):
        m = float(phi @ _mass_and_damping_at(model, sys, w, {"radiation": "database"})[0][0] @ phi)
        w_new = math.sqrt(k / m)
        if abs(w_new - w) < 1e-12 * w:
            break
        w = w_new
    return 2.0 * float(ratio) * math.sqrt(k * m)
