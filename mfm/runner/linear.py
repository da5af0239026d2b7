"""The linearised time-domain level of the fidelity ladder: the model linearised about its
equilibrium (:func:`mfm.frequency.linear_system`, the linearisation of ``frequency_response``), its
radiation memory realised by the passive state-space fit (:mod:`hydro.statespace`, the fit of
``simulate(radiation="state_space")``), excited by the time series ``simulate`` uses, and stepped
exactly.

About q₀, with x = q − q₀:

    M ẍ + C ẋ + K x = H₀ᵀ (F_exc(t) + F_rad),    M with the fit's A∞ (H₀ᵀ A∞ H₀),
    ż = P z + S H₀ ẋ,   F_rad = −R z              (the fit's modal form; real and imaginary parts)

(K, C and M from every load at rest, H₀ the hydro Jacobian at q₀, F_exc the excitation of
``hydro.excitation.excitation_time_series`` on the same components and ramp) is the LTI system

    ẏ = A y + B f(t),   y = (x, ẋ, z),   f = H₀ᵀ F_exc   (n_q generalised forces).

With A = V Λ V⁻¹ (its modes) and f linear within each step (first-order hold on the samples
f_k = f(t_k), the hold of ``simulate``'s excitation table too), each mode w = V⁻¹ y obeys
ẇ = λ w + b f(t), b = V⁻¹ B, and is advanced exactly:

    w_{k+1} = e^{λh} w_k + h φ₁(λh) b f_k + h φ₂(λh) b (f_{k+1} − f_k)

(:func:`mfm.loads.radiation.phi_functions`); y = Re V w, a conjugate pair of modes stepped once
and counted twice. Nothing depends on the position of a free coordinate (a zero column of K: an
unmoored surge), which would make A defective (0 a double eigenvalue): it is left out of y and
integrated exactly from its velocity,

    q_f(t_{k+1}) − q_f(t_k) = Re v_f ∫ w dt,   ∫_{t_k}^{t_{k+1}} w dt = h φ₁ w_k + h² φ₂ b f_k + h² φ₃ b (f_{k+1} − f_k).

No step size limit and no time-stepping error: against the linear model the one error is the hold's
on the force, O((ωh)²) (the spectral level's steady state has none; this level has the start-up
transient and the ramp, as ``simulate`` has). Cost per step: one (modes × n_q) complex product.

Quadratic drag (the water's, on the body's own velocity or on the relative flow, and any load's
:meth:`~mfm.loads.base.Load.quadratic_drag`) enters linearised stochastically for the sea, as the
spectral level takes it (:mod:`mfm.frequency.drag`, one fixed point for both, here on the
state-space fit's radiation): a damping Σ_p R_pᵀ C_p R_p added to C and, on the relative flow, the
excitation Σ_p R_pᵀ C_p P_p u_p(t) of the linear particle velocity at each point's rest position,
ramped as the excitation is. The equivalent damping is the one of least mean-square error for a
Gaussian response; the drag's odd harmonics are not in it (a few per cent to ~15 % on a
drag-dominated standard deviation, docs/nonlinear.md).
"""
from __future__ import annotations

import functools
import hashlib
import numbers
import time as _time

import jax
import jax.numpy as jnp
import numpy as np
import xarray as xr

from .. import results
from ..loads.pto import load_dampers
from ..mechanics.model import Model
from ..mechanics.points import h_matrix_at
from ..validation import check_model, check_sea, finite_number
from ..frequency.rest import linear_hydro, linear_system

# the largest condition number of the mode matrix V accepted: the modes' round-off grows as
# cond(V)·ε (1e10: 1e-6 relative; in the 1-norm RM3 has 4.6e3, M4 134 2.1e4)
MAX_MODE_CONDITION = 1e10


def lti_matrices(M, C, K, H0=None, rad=None, free=()):
    """(A, B, layout) of the LTI system of the module docstring: M, C, K (n, n); H0 (6K, n) and
    ``rad`` (a :class:`~mfm.loads.radiation.StateSpace`) for the radiation states, or None; ``free``
    the coordinates whose position is left out of y. layout: the rows of y: ``x`` (positions kept,
    their coordinate indices ``stiff``), ``v`` (velocities), then the radiation states."""
    n = M.shape[0]
    stiff = [k for k in range(n) if k not in set(free)]
    ns = len(stiff)
    nx = 0 if rad is None else len(rad.inputs)
    N = ns + n + 2 * nx
    Minv = np.linalg.solve(M, np.eye(n))
    A = np.zeros((N, N))
    vs = slice(ns, ns + n)
    A[np.arange(ns), ns + np.asarray(stiff, dtype=int)] = 1.0
    A[vs, :ns] = -Minv @ K[:, stiff]
    A[vs, vs] = -Minv @ C
    if nx:
        p_host = np.asarray(rad.p)
        pr, pi = p_host[:, 0], p_host[:, 1]
        zr, zi = slice(ns + n, ns + n + nx), slice(ns + n + nx, N)
        out = np.zeros((H0.shape[0], 2 * nx))
        out[np.asarray(rad.outputs)] = np.asarray(rad.C)
        # F_rad = −C [zr; zi] on the output dofs; M ẍ gets H₀ᵀ F_rad
        A[vs, ns + n:] = -Minv @ H0.T @ out
        A[zr, zr] = np.diag(pr)
        A[zr, zi] = -np.diag(pi)
        A[zi, zr] = np.diag(pi)
        A[zi, zi] = np.diag(pr)
        A[zr, vs] = H0[np.asarray(rad.inputs)]
    B = np.zeros((N, n))
    B[vs] = Minv
    return A, B, {"stiff": stiff, "free": list(free), "x": slice(0, ns), "v": vs, "Minv": Minv}


# the modes of the last few systems, by the bytes of (A, B, layout, dt): the eigendecomposition
# (seconds for M4 134's 1,021 states) depends on the model and dt only, not on the sea, so a
# sweep over sea states pays it once (as the state-space fit is cached on the HydroSpec)
_MODES_CACHE: dict = {}
_MODES_CACHE_SIZE = 4


def modal_step(A, B, layout, dt):
    """The exact modal step of the module docstring for steps of ``dt``: the complex arrays the
    scan needs, and the condition number of V (1-norm, ‖V‖ ‖V⁻¹‖). Raises ValueError when A's
    modes are too ill-conditioned to use."""
    key = hashlib.sha1(b"".join([A.tobytes(), B.tobytes(), repr((layout["stiff"], layout["free"],
                                                                 float(dt))).encode()])).hexdigest()
    if key not in _MODES_CACHE:
        if len(_MODES_CACHE) >= _MODES_CACHE_SIZE:
            _MODES_CACHE.pop(next(iter(_MODES_CACHE)))
        _MODES_CACHE[key] = _modal_step(A, B, layout, dt)
    return _MODES_CACHE[key]


def _modal_step(A, B, layout, dt):
    from ..loads.radiation import phi_functions

    lam, V = np.linalg.eig(A)
    W = np.linalg.solve(V, np.eye(len(lam)))
    cond = float(np.linalg.norm(V, 1) * np.linalg.norm(W, 1))
    if not cond < MAX_MODE_CONDITION:
        raise ValueError(f"the linearised system's modes are ill-conditioned (cond V = {cond:.3g} "
                         f"> {MAX_MODE_CONDITION:.0e}): nearly repeated eigenvalues of a "
                         "non-normal system; use the time domain (mfm.simulate)")
    keep = lam.imag >= 0        # LAPACK gives a real A's pairs exactly conjugate, real ones real
    weight = np.where(lam.imag[keep] > 0, 2.0, 1.0)
    W = W[keep]
    lam, V = lam[keep], V[:, keep] * weight[None]
    b = (W @ B).astype(complex)        # complex even where every mode is real
    e, p1, p2, p3 = phi_functions(lam * dt, 3)
    v = layout["v"]
    stiff, free = layout["stiff"], layout["free"]
    n = len(stiff) + len(free)
    # output rows: q (positions kept), q̇ (all), q̈ = (A y)_v + M⁻¹ f (A V = V Λ)
    Yq = np.zeros((n, len(lam)), complex)
    Yq[stiff] = V[layout["x"]]
    Yv = V[v]
    return dict(e=jnp.asarray(e), c0=jnp.asarray(dt * (p1 - p2)), c1=jnp.asarray(dt * p2),
                b=jnp.asarray(b), Yq=jnp.asarray(Yq), Yv=jnp.asarray(Yv),
                Ya=jnp.asarray(Yv * lam[None]), Minv=jnp.asarray(layout["Minv"]),
                # free positions: their velocity rows against ∫ w dt over the step
                Yf=jnp.asarray(Yv[free] if free else np.zeros((0, len(lam)))),
                d_w=jnp.asarray(dt * p1), d0=jnp.asarray(dt**2 * (p2 - p3)),
                d1=jnp.asarray(dt**2 * p3), free=jnp.asarray(np.asarray(free, dtype=int))), cond


# force samples per chunk of the scan, times the modes: the chunk's modal inputs b f_k are one
# matrix product, its outputs another (the serial loop is elementwise only); 5e5 complex numbers
# (8 MB, cache-sized: larger chunks measured slower) per chunk
CHUNK_ENTRIES = 500_000


@functools.partial(jax.jit, static_argnames=("save_every", "chunk"))
def _scan(modes, f, save_every, chunk):
    """(x, ẋ, ẍ) (n_saved, n) at t₀ and every ``save_every`` steps for the force samples f
    (n_steps + 1, n_q), from rest (w = 0), in chunks of ``chunk`` steps (a multiple of
    ``save_every``). The serial loop is w_{k+1} = e w_k + g_k alone; the inputs g_k, the outputs
    and the free positions' increments Re Y_f ∫ w dt are matrix products over each chunk."""
    m = modes
    free = m["free"]
    n, nf = m["Minv"].shape[0], free.shape[0]
    n_steps = f.shape[0] - 1
    n_chunks = -(-n_steps // chunk)
    # zero force past the end: later samples do not reach earlier ones (dropped below)
    f_all = jnp.concatenate([f, jnp.zeros((n_chunks * chunk - n_steps, f.shape[1]))])
    fs_all = f_all[1:].reshape(n_chunks, chunk, f.shape[1])
    # every output row against the modes in one real product, Re(W Yᵀ) = Re W Re Yᵀ − Im W Im Yᵀ
    # (XLA's complex products on the CPU are twice as slow): q, q̇, q̈ − M⁻¹f, and the free
    # positions' increments' part h φ₁ w_k
    Y = jnp.concatenate([m["Yq"], m["Yv"], m["Ya"], m["Yf"] * m["d_w"][None]])
    Yr, Yi = jnp.real(Y).T, jnp.imag(Y).T
    br, bi = jnp.real(m["b"]).T, jnp.imag(m["b"]).T
    Yf_0, Yf_1 = m["Yf"] * m["d0"][None], m["Yf"] * m["d1"][None]

    def step(w, g):
        w = m["e"] * w + g
        return w, w

    def one_chunk(carry, fs):
        w0, u0, qf0 = carry
        U = (fs @ br) + 1j * (fs @ bi)                     # b f_{k+1} over the chunk (f real)
        U_prev = jnp.concatenate([u0[None], U[:-1]])       # b f_k
        w_end, W = jax.lax.scan(step, w0, m["c0"] * U_prev + m["c1"] * U)
        W_prev = jnp.concatenate([w0[None], W[:-1]])
        out = jnp.real(W) @ Yr - jnp.imag(W) @ Yi
        free_w = jnp.real(W_prev) @ Yr[:, 3 * n:] - jnp.imag(W_prev) @ Yi[:, 3 * n:]
        qf = qf0 + jnp.cumsum(free_w + jnp.real(U_prev @ Yf_0.T + U @ Yf_1.T), axis=0)
        k = slice(save_every - 1, None, save_every)
        return (w_end, U[-1], qf[-1]), outputs(out[k], qf[k], fs[k])

    def outputs(out, qf, fk):
        x = out[:, :n].at[:, free].set(qf)
        return x, out[:, n:2 * n], out[:, 2 * n:3 * n] + fk @ m["Minv"].T

    zero = jnp.zeros(m["e"].shape[0], complex)
    qf0 = jnp.zeros(nf)
    _, saved = jax.lax.scan(one_chunk, (zero, m["b"] @ f[0], qf0), fs_all)
    first = outputs(jnp.zeros((1, 3 * n + nf)), qf0[None], f[:1])
    n_saved = n_steps // save_every
    return tuple(jnp.concatenate([a, b.reshape((-1,) + b.shape[2:])[:n_saved]])
                 for a, b in zip(first, saved))


def lti_response(M, C, K, f, dt, *, save_every: int = 1, H0=None, rad=None, free=()):
    """The response from rest of M ẍ + C ẋ + K x = f(t) (+ the radiation of ``rad`` through
    ``H0``) to the force samples f (n_steps + 1, n) at t_k = k dt, linear between them, stepped
    exactly (module docstring): (x, ẋ, ẍ) (n_steps // save_every + 1, n) numpy, and cond(V)."""
    f = np.asarray(f, dtype=float)
    A, B, layout = lti_matrices(np.asarray(M, float), np.asarray(C, float), np.asarray(K, float),
                                None if H0 is None else np.asarray(H0, float), rad, free)
    modes, cond = modal_step(A, B, layout, float(dt))
    nk = modes["e"].shape[0]
    n_steps = f.shape[0] - 1
    chunk = save_every * max(1, min(CHUNK_ENTRIES // (nk * save_every), n_steps // save_every))
    x, v, a = _scan(modes, jnp.asarray(f), save_every=int(save_every), chunk=int(chunk))
    return np.asarray(x), np.asarray(v), np.asarray(a), cond


def _free_columns(K):
    """Coordinates nothing depends on the position of: a zero column of K (≤ 1e-9 of its largest
    entry, the threshold of :func:`mfm.frequency.rest.free_coordinates`)."""
    scale = max(float(np.abs(K).max()), 1e-300)
    return [k for k in range(K.shape[1]) if float(np.abs(K[:, k]).max()) <= 1e-9 * scale]


def linear_response(model: Model, sea, *, duration: float, dt: float, ramp: float = 0.0,
                    save_every: int = 1, q0=None, loads=None,
                    state_space_options: dict | None = None) -> xr.Dataset:
    """The model's response to ``sea`` linearised in the time domain (module docstring): from rest
    at the equilibrium, the excitation of :func:`mfm.simulate` (same components, phases and
    ``ramp``), radiation by the passive state-space fit (``state_space_options`` as for
    ``simulate``), stepped exactly at ``dt`` (any dt is stable; the force is held linear between
    samples).

    model: a Model with hydrodynamics; sea: a sea state of :mod:`hydro.waves`. duration, dt: s
    (``round(duration / dt)`` steps); save_every: keep every k-th step. q0, loads: as
    :func:`mfm.frequency_response` (q0 the linearisation point, default the equilibrium).

    Returns an xarray.Dataset with ``q``, ``qd``, ``qdd`` (time, coordinate), ``pto_power`` and
    ``pto_displacement`` (time, pto) of each joint damper (c q̇², as :func:`mfm.spectral_response`)
    and each hydraulic piston (β ẇ², ẇ = g(q₀) q̇ to first order), ``eta`` (time) and
    ``equilibrium`` (coordinate); with quadratic drag (module docstring) also ``drag_damping``
    (drag_point, flow_axis, flow_axis_col) and ``relative_flow_rms`` (drag_point, flow_axis), as
    :func:`mfm.spectral_response` gives them, and the attributes ``drag_linearisation``,
    ``drag_iterations``, ``drag_change``; the loads' outputs linear about q₀ (a catenary line's
    ``fairlead_tension`` (time, mooring_line) = y₀ + L (q − q₀), and ``<name>_equilibrium``:
    :meth:`~mfm.loads.base.Load.linear_outputs`); attributes: provenance, ``level = "linear"``, the
    state-space fit, ``free_positions``, ``mode_condition`` (‖V‖₁‖V⁻¹‖₁), the wall time.
    Raises ValueError on bad input, NotImplementedError for a load other than the water with a
    frequency-dependent impedance (no time-domain realisation of it here; a load's wave force,
    such as a Morison element's inertia, is synthesised from its frequency terms at the sea's
    components).
    """
    model = check_model(model)
    from hydro.excitation import excitation_time_series
    from hydro.waves import elevation

    from ..loads.base import Load
    from ..loads.radiation import StateSpace

    if model.hydro is None:
        raise ValueError(f"model {model.name!r} has no hydrodynamics: linear_response needs a "
                         "config with a [hydro] table")
    check_sea(sea, still_water=False)
    dt = finite_number(dt, "dt", positive=True)
    duration = finite_number(duration, "duration", positive=True)
    ramp = finite_number(ramp, "ramp", nonnegative=True)
    n_steps = int(round(duration / dt))
    if n_steps < 1:
        raise ValueError(f"duration = {duration} s is shorter than one step dt = {dt} s")
    if isinstance(save_every, bool) or not isinstance(save_every, numbers.Integral) or save_every < 1 \
            or n_steps % save_every:
        raise ValueError(f"save_every: {save_every!r} must be a positive divisor of the {n_steps} "
                         "steps")
    start = _time.perf_counter()
    sys = linear_system(model, q0, loads=loads)
    other = [ld for ld in sys.loads if ld.linear_hydro() is None
             and type(ld).frequency_terms is not Load.frequency_terms]
    water = linear_hydro(sys.loads)
    spec = model.hydro
    rad = StateSpace.build(spec, state_space_options)
    H0 = np.asarray(h_matrix_at(water.geometry, sys.kin0))
    # the fit's A∞ (its corrected one) in place of the database's that the linearisation holds
    M = sys.M + H0.T @ (np.asarray(rad.A_inf) - np.asarray(water.A_inf)) @ H0
    t = dt * np.arange(n_steps + 1)
    comps = sea.components(water_depth=spec.water_depth, g=spec.g)
    f = excitation_time_series(spec.database(), comps, t, ramp_duration=ramp) @ H0
    if other:
        f = f + _wave_forces(model, sys, other, comps, t, ramp)
    C = sys.C
    groups = [g for ld in sys.loads if (g := ld.quadratic_drag(model, sys.kin0)) is not None]
    if groups:
        drag = _linearised_drag(model, sys, comps, groups, state_space_options)
        R = np.concatenate([g.rows for g in groups])                       # (P, 3, n_q)
        C = C + np.einsum("pai,pab,pbj->ij", R, drag["C"][0], R)
        f = f + _flow_force(groups, drag["C"][0], comps, t, ramp, spec.water_depth)
    free = _free_columns(sys.K)
    x, qd, qdd, cond = lti_response(M, C, sys.K, f, dt, save_every=save_every, H0=H0,
                                    rad=rad, free=free)
    ts = t[::save_every]
    q = sys.q0[None] + x
    eta = np.asarray(elevation(comps, ts, ramp_duration=ramp)).reshape(-1)
    wall = _time.perf_counter() - start
    settings = dict(level="linear", dt=dt, dt_units="s", duration=duration, n_steps=n_steps,
                    save_every=int(save_every), ramp_s=ramp, sea=repr(sea),
                    n_components=len(comps), free_positions=", ".join(
                        model.coordinates[k] for k in free) or "none",
                    mode_condition=cond, wall_time_s=wall)
    if groups:
        settings.update(results.drag_settings(groups, drag))
    ds = results.linear_time_series(model, sys.loads + (rad,), ts, q, qd, qdd, sys.q0, eta,
                                    settings, source=spec.source,
                                    dampers=load_dampers(sys.loads, sys.kin0))
    ds = results.add_linear_outputs(ds, *results.linear_outputs(model, sys.loads, sys.kin0),
                                    sys.q0, q)
    if groups:
        ds = results.drag_linearisation(ds, groups, drag["C"][0], drag["sigma"][0], case=False)
    return ds


def _wave_forces(model, sys, loads, comps, t, ramp):
    """The wave forces of loads other than the water's with frequency terms (Morison elements'
    inertia), realised in time: r(t) Re Σ_j a_j e^{iφ_j} F(ω_j, β_j) e^{−iω_j t} (n_t, n_q) of each
    load's :meth:`~mfm.loads.base.Load.frequency_terms` force at the sea's components (exact for a
    force linear in the wave), ramped as the excitation is. A load whose terms also carry an
    impedance (a frequency-dependent mass, damping or stiffness) is refused: this level has no
    realisation of it."""
    from hydro.waves import _harmonic_sum
    from hydro.waves import ramp as ramp_of

    coef = np.zeros((len(comps.omega), model.n_coordinates), dtype=complex)
    for ld in loads:
        for beta in np.unique(comps.heading):
            sel = comps.heading == beta
            terms = ld.frequency_terms(model, sys.q0, sys.kin0, comps.omega[sel], float(beta),
                                       {"excitation": True})
            if terms.impedance is not None and np.any(np.asarray(terms.impedance) != 0):
                raise NotImplementedError(
                    f"load {type(ld).__name__} adds a frequency-dependent impedance (a mass, "
                    "damping or stiffness that depends on ω), which has no time-domain "
                    "realisation in the linear level; use mfm.simulate")
            if terms.force is not None:
                coef[sel] += comps.complex_amplitude[sel, None] * np.asarray(terms.force)
    r = ramp_of(t, ramp)[:, None] if ramp else 1.0
    return r * _harmonic_sum(comps.omega, coef, t)


def _linearised_drag(model, sys, comps, groups, state_space_options):
    """The stochastic linearisation of the loads' quadratic drag for this sea
    (:func:`mfm.runner.spectral.drag_raos`, one place for the fixed point) on the system this
    level steps: the radiation of the state-space fit, so that the damping C matches the level's
    own response statistics."""
    from .spectral import drag_raos

    options = {"radiation": "state_space", "state_space_options": state_space_options}
    return drag_raos(model, sys, [comps], options, groups)[2]


def _flow_force(groups, C, comps, t, ramp, water_depth):
    """The linearised drag's excitation by the flow, Σ_p R_pᵀ C_p P_p u_p(t) (n_t, n_q): u_p(t) =
    r(t) Re Σ_j a_j e^{iφ_j} û_p(ω_j, β_j) e^{−iω_j t} the linear particle velocity at each point's
    rest position (:func:`hydro.wetted.velocity_transfer`), ramped as the excitation is; 0 for a
    drag on the body's own velocity."""
    from hydro.waves import _harmonic_sum
    from hydro.waves import ramp as ramp_of
    from hydro.wetted import velocity_transfer

    f = np.zeros((len(t), groups[0].rows.shape[-1]))
    r = ramp_of(t, ramp)[:, None] if ramp else 1.0
    start = 0
    for g in groups:
        P = len(g.rows)
        if g.flow:
            U = velocity_transfer(g.positions, comps.omega, comps.wavenumber, comps.heading,
                                  water_depth)                                # (n_j, P, 3)
            Pu = np.einsum("pab,jpb->jpa", g.project, U).reshape(len(comps.omega), -1)
            u = r * _harmonic_sum(comps.omega, comps.complex_amplitude[:, None] * Pu, t)
            f += np.einsum("pai,pab,tpb->ti", g.rows, C[start:start + P], u.reshape(len(t), P, 3))
        start += P
    return f
