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

from . import results
from .dynamics import gravity_loads, joint_loads, mass_matrix
from .kinematics import kinematics
from .model import Model


def _as_loads(loads):
    from .simulate import _as_loads as as_loads

    return as_loads(loads)


def system_loads(model: Model, loads=None) -> tuple:
    """The loads of the linearisation: the model's water in still water (no radiation memory: the
    frequency domain adds its radiation as an impedance), the config's loads and ``loads``."""
    from .simulate import model_loads

    return model_loads(model, None, dt=1.0, duration=1.0, radiation="none") + _as_loads(loads)


def _static_parts(model, static, mems, q, qd):
    """Q(q, q̇) (generalised loads other than inertia) and the acceleration-proportional matrix
    of the loads at rest (None when no load has one)."""
    from .simulate import applied_loads

    nz = sum(ld.n_states for ld in static)
    kin = kinematics(model, q, qd)
    body, tau, mass, _ = applied_loads(model, static, 0.0, q, qd, jnp.zeros(nz), kin, mems)
    F = gravity_loads(model) + (0.0 if body is None else body)
    out = jnp.einsum("nai,na->i", kin.B, F) + joint_loads(model, q, qd)
    return (out if tau is None else out + tau), mass


# Compiled once per model structure (model, loads and memories are pytree arguments, not closed
# over): a second equilibrium or linearisation of the same model reuses them.
@jax.jit
def _Q_at_rest(model, static, mems, q):
    return _static_parts(model, static, mems, q, jnp.zeros_like(q))[0]


_dQ_dq = jax.jit(jax.jacfwd(_Q_at_rest, argnums=3))


@jax.jit
def _dQ_dqd(model, static, mems, q):
    return jax.jacfwd(lambda v: _static_parts(model, static, mems, q, v)[0])(jnp.zeros_like(q))


@jax.jit
def _loads_mass(model, static, mems, q):
    mass = _static_parts(model, static, mems, q, jnp.zeros_like(q))[1]
    return jnp.zeros((q.shape[0],) * 2) if mass is None else mass


def _static_functions(model: Model, loads):
    """The loads at rest (:meth:`Load.static_load`) and their memories, ready for the compiled
    functions above: (static, mems)."""
    static = tuple(s for s in (ld.static_load() for ld in loads) if s is not None)
    zero = jnp.zeros(model.n_coordinates)
    mems = tuple(ld.init_memory(model, 0.0, zero, zero, 1.0) for ld in static)
    return static, mems


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
    Gj = lambda q: _Q_at_rest(model, static, mems, q)  # noqa: E731
    Jj = lambda q: _dQ_dq(model, static, mems, q)  # noqa: E731
    q = jnp.zeros(model.n_coordinates) if q_guess is None else jnp.asarray(q_guess, jnp.float64)
    # the size of the loads that must balance: generalised weights, or the largest weight
    scale = max(float(jnp.max(jnp.abs(jnp.einsum("nai,na->i", kinematics(model, q).B,
                                                 gravity_loads(model))))),
                float(jnp.max(model.mass)) * float(model.gravity))
    it = 0
    q_ok = q
    for it in range(max_iter):
        g = np.asarray(Gj(q))
        if not np.isfinite(g).all():
            break
        q_ok = q
        if np.abs(g).max() < tol * scale:
            break
        J = np.asarray(Jj(q))
        step = np.linalg.lstsq(J, -g, rcond=1e-10)[0]
        q = q + jnp.asarray(step)
    g = np.asarray(Gj(q))
    if not np.isfinite(g).all():
        # a load undefined there (a catenary line's fairlead outside its table): say which
        for q_at in (q, q_ok):
            for ld in loads:
                cause = ld.describe_nonfinite(model, np.asarray(q_at), np.zeros(model.n_coordinates))
                if cause:
                    raise ValueError(f"no static equilibrium of {model.name!r} found: the static "
                                     f"loads went non-finite at q = {np.asarray(q).tolist()}. {cause}")
    J = np.asarray(Jj(q))
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
    K = -np.asarray(_dQ_dq(model, static, mems, q0))
    C = -np.asarray(_dQ_dqd(model, static, mems, q0))
    M = np.asarray(mass_matrix(model, q0)) + np.asarray(_loads_mass(model, static, mems, q0))
    return LinearSystem(np.asarray(q0), M, K, C, kinematics(model, q0, jnp.zeros_like(q0)), lds)


def linearise(model: Model, q0=None, *, loads=None):
    """(q₀, M₀, K, C, H₀): the structural mass M*(q₀), stiffness and linear damping (n_q, n_q)
    about the equilibrium, and the hydro Jacobian H₀ (6K, n_q) (None without water)."""
    sys = linear_system(model, q0, loads=loads)
    M0 = np.asarray(mass_matrix(model, jnp.asarray(sys.q0)))
    water = _water(sys.loads)
    H0 = None if water is None else np.asarray(water.geometry.h_matrix(sys.kin0)[0])
    return sys.q0, M0, sys.K, sys.C, H0


def _water(loads):
    from .loads.water import Water

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


def frequency_response(model: Model, omega, heading: float = 0.0, *, q0=None,
                       radiation: str = "database", state_space_options: dict | None = None,
                       loads=None):
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
    ``point_rao``, …), ``equilibrium`` (coordinate).
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
    Zl, F = _terms(model, sys, omega, heading, options)
    w = omega[:, None, None]
    Z = -w**2 * sys.M[None] - 1j * w * sys.C[None] + sys.K[None] + Zl
    x = np.linalg.solve(Z, F[..., None])[..., 0]
    extra = [ld.frequency_outputs(model, sys.kin0, x, omega) for ld in sys.loads]
    settings = {"radiation": radiation}
    if state_space_options:
        settings["state_space_options"] = repr(state_space_options)
    return results.frequency(model, sys.loads, omega, x, sys.q0, sys.kin0, heading, settings,
                             [e for e in extra if e])


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
    damping_ratio: φᵀ C φ / (2 ω φᵀ M(ω) φ) of each mode for the linear damping C (joint dampers,
        hydraulic β, body matrices); radiation_damping_ratio the same with Hᵀ B(ω) H.

    Returns an xarray.Dataset: ``eigen``, ``period``, ``damping_ratio``,
    ``radiation_damping_ratio``, ``damped`` (mode), ``modes`` (coordinate, mode), ``min_det``
    (root); it reads like the former dict (``nat["eigen"]``).
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
    modes = np.array(modes).T if modes else np.zeros((model.n_coordinates, 0))
    return results.natural(model, sys.loads, np.array(freqs), modes, np.array(zeta),
                           np.array(zeta_rad), np.array(mins), {"radiation": radiation})


def critical_damping(model: Model, body: str, mode: str, ratio: float, *, point=None,
                     loads=None, iterations: int = 30) -> float:
    """The damping coefficient (N s/m or N m s/rad) that is ``ratio`` of critical for one
    single-body mode of ``body`` (surge … yaw at ``point``, default its CoM), from the model's own
    linearisation: with φ the least-norm coordinate motion that moves that dof of the point by one
    unit, k = φᵀKφ, m(ω) = φᵀM(ω)φ (added mass at the mode's frequency, iterated), it is
    c = 2 ζ √(k m). Used by ``[[body_matrices]] damping_ratio``."""
    from .loads.base import MODES
    from .points import BodyPoints

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
