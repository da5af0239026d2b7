"""Frequency domain: static equilibrium, linearisation of the same model, RAOs, natural frequencies.

The model of :func:`mfm.simulate` is linearised about its static equilibrium q₀ (DESIGN §4): jax
gives the stiffness ``K = −∂G/∂q`` of the static generalised load G(q) (gravity, buoyancy at the
centre of buoyancy, water-plane stiffness, moorings, joint springs), ``M₀ = M*(q₀)`` and
``H₀ = H(q₀)``. With the complex-amplitude convention of the hydro databases, x(t) = Re[x̂ e^{−iωt}]:

    Z(ω) x̂ = H₀ᵀ X(ω, β),   Z(ω) = −ω² (M₀ + H₀ᵀ A(ω) H₀) − iω (H₀ᵀ B(ω) H₀ + C) + K,

C the joint dampers. x̂ per metre of wave amplitude is the RAO of every coordinate; bodies, hydro
dofs and PTOs follow from the same Jacobians. Quadratic drag is not linearised (it is left out).
"""
from __future__ import annotations

import math

import jax
import jax.numpy as jnp
import numpy as np
import xarray as xr

from .dynamics import gravity_loads, joint_loads, mass_matrix
from .kinematics import kinematics
from .model import Model


def _static_loads(model: Model):
    from .simulate import applied_loads, model_loads

    # still water, no radiation: the static loads (gravity, buoyancy, water plane, moorings, PTOs)
    loads = model_loads(model, None, dt=1.0, duration=1.0, radiation="none")
    mems = tuple(ld.init_memory(model, 0.0, jnp.zeros(model.n_coordinates),
                                jnp.zeros(model.n_coordinates), 1.0) for ld in loads)
    nz = sum(ld.n_states for ld in loads)

    def G(q):
        qd = jnp.zeros_like(q)
        kin = kinematics(model, q, qd)
        body, tau, _, _ = applied_loads(model, loads, 0.0, q, qd, jnp.zeros(nz), kin, mems)
        F = gravity_loads(model) + (0.0 if body is None else body)
        out = jnp.einsum("nai,na->i", kin.B, F) + joint_loads(model, q, qd)
        return out if tau is None else out + tau

    return G, loads


def equilibrium(model: Model, q_guess=None, *, tol: float = 1e-10, max_iter: int = 50):
    """Static equilibrium q₀ with G(q₀) = 0 (Newton with the jax Jacobian; least squares where
    nothing restores a coordinate, which then stays at its guess).

    Returns (q₀, info) with info = dict(residual, iterations, free: coordinates without
    stiffness). Raises ValueError when no equilibrium is found (a body that cannot float freely
    sinks or capsizes), naming the residual by coordinate.
    """
    G, _ = _static_loads(model)
    Gj = jax.jit(G)
    Jj = jax.jit(jax.jacfwd(G))
    q = jnp.zeros(model.n_coordinates) if q_guess is None else jnp.asarray(q_guess, jnp.float64)
    # the size of the loads that must balance: generalised weights, or the largest weight
    scale = max(float(jnp.max(jnp.abs(jnp.einsum("nai,na->i", kinematics(model, q).B,
                                                 gravity_loads(model))))),
                float(jnp.max(model.mass)) * float(model.gravity))
    for it in range(max_iter):
        g = np.asarray(Gj(q))
        if np.abs(g).max() < tol * scale:
            break
        J = np.asarray(Jj(q))
        step = np.linalg.lstsq(J, -g, rcond=1e-10)[0]
        q = q + jnp.asarray(step)
    g = np.asarray(Gj(q))
    J = np.asarray(Jj(q))
    free = [model.coordinates[k] for k in range(model.n_coordinates)
            if np.abs(J[:, k]).max() < 1e-12 * scale]
    if np.abs(g).max() > 1e-6 * scale:
        bad = {model.coordinates[k]: float(g[k]) for k in np.argsort(-np.abs(g))[:3]}
        raise ValueError(f"no static equilibrium of {model.name!r} found from the guess: residual "
                         f"generalised loads {bad} (N or N m). A body whose weight its buoyancy "
                         "cannot carry sinks; one whose centre of mass is too high capsizes.")
    return np.asarray(q), {"residual": float(np.abs(g).max()), "iterations": it, "free": free}


def linearise(model: Model, q0=None):
    """(q₀, M₀, K, C, H₀): mass, stiffness and joint damping matrices (n_q, n_q) about the
    equilibrium, and the hydro Jacobian H₀ (6K, n_q) (None without water)."""
    if q0 is None:
        q0, _ = equilibrium(model)
    q0 = jnp.asarray(q0, jnp.float64)
    G, loads = _static_loads(model)
    K = -np.asarray(jax.jacfwd(G)(q0))
    M0 = np.asarray(mass_matrix(model, q0))
    C = np.diag(np.asarray(model.damping))
    H0 = None
    if model.hydro is not None:
        kin = kinematics(model, q0, jnp.zeros_like(q0))
        H0 = np.asarray(loads[0].geometry.h_matrix(kin)[0])
    return np.asarray(q0), M0, K, C, H0


def _radiation_at(spec, omega, radiation="database", state_space_options=None):
    """A(ω), B(ω) (n_ω, 6K, 6K) of one of the radiation models:

    "database": the BEM values, linearly interpolated on the database grid;
    "convolution": the time-domain model of ``simulate(radiation="convolution")``: A∞ (as used
        there) − ∫K sin ωt dt/ω and ∫K cos ωt dt (Ogilvie), K from B(ω) with its tail;
    "state_space": the fitted model of ``simulate(radiation="state_space")``: its A∞ and impedance
        K̂(iω) = B + iω(A − A∞).
    A database whose A(ω) and B(ω) are not Kramers–Kronig consistent (RM3's surge–pitch couplings
    by 1–3 %) gives different "database" and "convolution" answers; the time domain can only be
    the consistent one.
    """
    db = spec.database()
    om_db = np.asarray(db["omega"].values)
    if omega.min() < om_db[0] * (1 - 1e-9) or omega.max() > om_db[-1] * (1 + 1e-9):
        raise ValueError(f"omega: [{omega.min():.4g}, {omega.max():.4g}] rad/s lies outside the "
                         f"database's [{om_db[0]:.4g}, {om_db[-1]:.4g}] rad/s; choose frequencies "
                         "inside it or regenerate the database")
    if radiation == "database":
        return db["added_mass"].interp(omega=omega).values, db["radiation_damping"].interp(omega=omega).values
    if radiation == "convolution":
        from hydro.radiation import added_mass_from_irf, damping_from_irf

        # graded near τ = 0, where entries with slowly decaying damping have a narrow spike
        step = min(0.02, np.pi / om_db.max() / 4)
        t = np.concatenate([np.linspace(0.0, 25 * step, 2501)[:-1],
                            np.arange(25 * step, max(4 * spec.memory(), 60.0), step)])
        K = spec.impulse_response(t)
        return (np.asarray(added_mass_from_irf(K, t, spec.added_mass_inf(), omega)),
                np.asarray(damping_from_irf(K, t, omega)))
    if radiation == "state_space":
        ss = spec.state_space(**(state_space_options or {}))
        Z = ss.impedance(omega)
        A_inf = np.asarray(ss.added_mass_inf) * spec.mask
        return A_inf[None] + Z.imag / omega[:, None, None], Z.real
    raise ValueError(f"radiation={radiation!r}; accepted: 'database', 'convolution', 'state_space'")


def _hydro_at(spec, omega, heading, radiation="database", state_space_options=None):
    """A(ω), B(ω) (n_ω, 6K, 6K) (see :func:`_radiation_at`) and X(ω, β) (n_ω, 6K)."""
    from hydro.excitation import excitation_coefficients
    from hydro.waves import WaveComponents, wavenumber

    db = spec.database()
    A, B = _radiation_at(spec, omega, radiation, state_space_options)
    comps = WaveComponents(omega=omega, amplitude=np.ones_like(omega), phase=np.zeros_like(omega),
                           heading=np.full_like(omega, heading),
                           wavenumber=wavenumber(omega, spec.water_depth, spec.g),
                           water_depth=spec.water_depth, g=spec.g)
    X = excitation_coefficients(db, comps)
    return A, B, X


def frequency_response(model: Model, omega, heading: float = 0.0, *, q0=None,
                       radiation: str = "database", state_space_options: dict | None = None) -> xr.Dataset:
    """Complex RAOs (per metre of wave amplitude, x(t) = Re[x̂ e^{−iωt}]) of every coordinate,
    body (CoM displacement and small rotation, inertial axes), hydro dof and PTO, with the absorbed
    power per unit wave amplitude squared, from the model linearised about its equilibrium.

    radiation: which A(ω), B(ω): "database" (the BEM values), or exactly those of the time-domain
    models, "convolution" or "state_space" (see :func:`_radiation_at`); ``state_space_options``
    as given to :func:`mfm.simulate` (the same options give the same fit).

    Returns an xarray.Dataset: ``rao`` (omega, coordinate), ``body_rao`` (omega, body, dof) with
    dof = x, y, z, rx, ry, rz, ``xi_rao`` (omega, hydro_dof), ``pto_rao`` and ``pto_power``
    (omega, pto) (W/m², mean power ½ c ω² |x̂|²), ``equilibrium`` (coordinate).
    """
    if model.hydro is None:
        raise ValueError(f"model {model.name!r} has no hydrodynamics: frequency_response needs a "
                         "config with a [hydro] table (and mfm.load(..., hydro=True))")
    omega = np.atleast_1d(np.asarray(omega, dtype=float))
    q0, M0, K, C, H0 = linearise(model, q0)
    A, B, X = _hydro_at(model.hydro, omega, heading, radiation, state_space_options)
    F = np.einsum("ai,wa->wi", H0, X)
    Aq = np.einsum("ai,wab,bj->wij", H0, A, H0)
    Bq = np.einsum("ai,wab,bj->wij", H0, B, H0)
    w = omega[:, None, None]
    Z = -w**2 * (M0[None] + Aq) - 1j * w * (Bq + C[None]) + K[None]
    x = np.linalg.solve(Z, F[..., None])[..., 0]
    kin = kinematics(model, jnp.asarray(q0), jnp.zeros_like(jnp.asarray(q0)))
    Bm = np.asarray(kin.B)
    R = np.asarray(kin.E[:, :3, :3])
    body = np.concatenate([np.einsum("nai,wi->wna", Bm[:, :3], x),
                           np.einsum("nab,nbi,wi->wna", R, Bm[:, 3:], x)], axis=2)
    damped = [k for k in range(model.n_coordinates) if float(model.damping[k]) > 0]
    c = np.asarray(model.damping)[damped]
    ds = xr.Dataset(
        {"rao": (("omega", "coordinate"), x, {"long_name": "coordinate RAO per metre of wave "
                                             "amplitude, x(t) = Re[x e^{-i omega t}]", "units": "m/m or rad/m"}),
         "body_rao": (("omega", "body", "dof"), body, {"long_name": "CoM displacement and small "
                                                        "rotation of each body, inertial axes"}),
         "xi_rao": (("omega", "hydro_dof"), np.einsum("ai,wi->wa", H0, x),
                    {"long_name": "hydro coordinates (reference points) RAO"}),
         "pto_rao": (("omega", "pto"), x[:, damped]),
         "pto_power": (("omega", "pto"), 0.5 * c * omega[:, None] ** 2 * np.abs(x[:, damped]) ** 2,
                       {"long_name": "mean absorbed power per unit wave amplitude squared", "units": "W/m2"}),
         "equilibrium": (("coordinate",), q0, {"units": "m or rad"})},
        coords={"omega": ("omega", omega, {"units": "rad/s"}), "coordinate": list(model.coordinates),
                "body": list(model.body_names), "dof": ["x", "y", "z", "rx", "ry", "rz"],
                "hydro_dof": list(model.hydro.dofs), "pto": [model.coordinates[k] for k in damped]},
        attrs={"model": model.name, "heading": float(heading), "convention": "exp(-i omega t)",
               "body_coupling": str(model.hydro.body_coupling), "source": model.hydro.source,
               "radiation": radiation})
    return ds


def natural_frequencies(model: Model, omega_grid=None, *, q0=None, iterations: int = 30):
    """Undamped natural frequencies (rad/s) two ways.

    eigen: the generalised eigenproblem K v = ω² (M₀ + H₀ᵀ A(ω) H₀) v, iterated on ω for each mode
        (A at that mode's own frequency); coordinates without stiffness have no mode.
    min_det: local minima of |det Λ(ω)|, Λ = −ω²(M₀ + H₀ᵀ A(ω) H₀) + K, over ``omega_grid``
        (seed 000 §2.10), refined parabolically.
    Returns dict(eigen=array, min_det=array, modes=(n_q, n_modes)).
    """
    import scipy.linalg

    q0, M0, K, C, H0 = linearise(model, q0)
    spec = model.hydro
    db = spec.database()
    om_db = np.asarray(db["omega"].values)

    def Aq(w):
        A = db["added_mass"].interp(omega=np.clip(w, om_db[0], om_db[-1])).values
        return H0.T @ A @ H0

    stiff = [k for k in range(model.n_coordinates) if np.abs(K[:, k]).max() > 1e-9 * np.abs(K).max()]
    Ks = K[np.ix_(stiff, stiff)]
    n = len(stiff)
    freqs, modes = [], []
    lam0 = scipy.linalg.eigh(Ks, (M0 + Aq(om_db[-1]))[np.ix_(stiff, stiff)], eigvals_only=True)
    for m in range(n):
        w = math.sqrt(max(lam0[m], 1e-30))
        for _ in range(iterations):
            lam, vec = scipy.linalg.eigh(Ks, (M0 + Aq(w))[np.ix_(stiff, stiff)])
            w_new = math.sqrt(max(lam[m], 1e-30))
            if abs(w_new - w) < 1e-10 * w:
                break
            w = w_new
        freqs.append(w)
        v = np.zeros(model.n_coordinates)
        v[stiff] = vec[:, m]
        modes.append(v)
    grid = np.linspace(om_db[0], om_db[-1], 2000) if omega_grid is None else np.asarray(omega_grid)
    det = np.array([abs(np.linalg.det((-w**2 * (M0 + Aq(w)) + K)[np.ix_(stiff, stiff)])) for w in grid])
    mins = []
    for i in range(1, len(grid) - 1):
        if det[i] < det[i - 1] and det[i] <= det[i + 1]:
            # parabola through the log|det| of three points
            y0, y1, y2 = np.log(det[i - 1:i + 2] + 1e-300)
            h = grid[i + 1] - grid[i]
            den = y0 - 2 * y1 + y2
            mins.append(grid[i] + (0.5 * h * (y0 - y2) / den if den > 0 else 0.0))
    return {"eigen": np.array(freqs), "min_det": np.array(mins), "modes": np.array(modes).T}
