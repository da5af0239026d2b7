"""Morison elements ([[morison]], mfm.loads.morison): a fixed vertical cylinder in a regular wave
against Morison's closed form over depth, the flow's acceleration against the potential, a point
element's still-water heave decay against an ODE solved by scipy, and the config's errors."""
from __future__ import annotations

import copy
import dataclasses
import math
import tomllib

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from conftest import CONFIGS

import hydro
import hydro.wetted as W
import mfm
from mfm.errors import ConfigError
from mfm.loads.base import Context, RunGrid
from mfm.mechanics.kinematics import kinematics

pytestmark = pytest.mark.filterwarnings("ignore::hydro.database.HydroDatabaseWarning")

SPHERE = tomllib.loads((CONFIGS / "sphere.toml").read_text())
G = 9.81


def _model(*elements):
    cfg = copy.deepcopy(SPHERE)
    cfg["morison"] = [dict(e) for e in elements]
    return mfm.load(cfg, base=CONFIGS)


# ------------------------------------------------------------------------ the flow's acceleration
@pytest.mark.parametrize("depth", [math.inf, 12.0])
def test_the_particle_acceleration_is_the_potential_s(depth):
    """∂u/∂t against (a) the gradient of the closed-form ∂φ/∂t = −Σ a g f(z) cos θ by central
    differences in space and (b) particle_velocity's central difference in time, at points under
    the surface, two components at two headings, deep and finite water: 1e-6 relative (the
    differences' error at steps 1e-4 m and 1e-4 s is ~1e-8; the stretching moves the decay by
    η, k a ≈ 1e-6 here). Above the instantaneous surface it is 0, as the velocity is."""
    from hydro.waves import wavenumber

    w = np.array([0.7, 1.3])
    k = wavenumber(w, depth, G)
    amp, beta, phi = np.array([1e-6, 2e-6]), np.array([0.3, -1.0]), np.array([0.2, 1.1])
    wave = W.WaveField(*(jnp.asarray(v) for v in (amp, w, k, beta, phi)), water_depth=depth)

    def dphi_dt(p, t):
        th = k * (p[0] * np.cos(beta) + p[1] * np.sin(beta)) - w * t + phi
        f = np.exp(k * p[2]) if math.isinf(depth) else np.cosh(k * (p[2] + depth)) / np.cosh(k * depth)
        return float(np.sum(-amp * G * f * np.cos(th)))

    pts = np.array([[0.5, -1.0, -0.7], [3.0, 2.0, -4.0]])
    t, h = 1.7, 1e-4
    acc = np.asarray(W.particle_acceleration(wave, jnp.asarray(pts), t))
    fd_t = (np.asarray(W.particle_velocity(wave, jnp.asarray(pts), t + h))
            - np.asarray(W.particle_velocity(wave, jnp.asarray(pts), t - h))) / (2 * h)
    for p, a, b in zip(pts, acc, fd_t):
        grad = [(dphi_dt(p + h * e, t) - dphi_dt(p - h * e, t)) / (2 * h) for e in np.eye(3)]
        np.testing.assert_allclose(a, grad, rtol=1e-6, atol=1e-9 * np.abs(grad).max())
        np.testing.assert_allclose(a, b, rtol=1e-6, atol=1e-9 * np.abs(grad).max())
    above = np.array([[0.0, 0.0, 1e-3]])
    assert np.all(np.asarray(W.particle_acceleration(wave, jnp.asarray(above), t)) == 0.0)


# ------------------------------------------------------------- a fixed cylinder in a regular wave
def _horizontal_force(model, laid, times):
    """The generalised force in surge (the total horizontal force: the planar joint's surge is
    the body's x) of the load at rest (q = 0, q̇ = 0: the body held) at each time."""
    q = jnp.zeros(model.n_coordinates)
    kin = kinematics(model, q, q)
    surge = list(model.coordinates).index("sphere.surge")
    f = jax.jit(jax.vmap(lambda t: laid.evaluate(Context(model, t, q, q, jnp.zeros(0), kin)).tau))
    return np.asarray(f(jnp.asarray(times)))[:, surge]


def _closed_form(t, *, a, omega, k, depth, bottom, top, rho, cd, ca, D):
    """Morison's force on a vertical cylinder at x = 0 from z = ``bottom`` to ``top`` (the part
    below the instantaneous surface), the linear kinematics Wheeler-stretched (ζ = z_s(z) =
    h (z − η)/(h + η), z − η deep): ∫ f(z_s(z)) dz = (h + η)/h ∫ f(ζ) dζ, so with θ = −ωt,
    inertia ρ (1 + C_A) π D²/4 a ω² sin θ ∫ f_h, drag ½ ρ C_D D (a ω)² |cos θ| cos θ ∫ f_h²,
    f_h = cosh k(ζ + h)/sinh kh (e^{kζ} deep), whose integrals are closed forms:
    ∫ cosh k(ζ + h) = sinh k(ζ + h)/k, ∫ cosh² k(ζ + h) = sinh 2k(ζ + h)/4k + (ζ + h)/2 (finite,
    from the sea bed); ∫ e^{kζ} = e^{kζ}/k, ∫ e^{2kζ} = e^{2kζ}/2k (deep)."""
    th = -omega * t
    eta = a * np.cos(th)
    if math.isinf(depth):
        zt, zb = np.minimum(top - eta, 0.0), bottom - eta
        I1 = (np.exp(k * zt) - np.exp(k * zb)) / k
        I2 = (np.exp(2 * k * zt) - np.exp(2 * k * zb)) / (2 * k)
    else:
        assert bottom == -depth
        s = (depth + eta) / depth
        zt = np.minimum(depth * (top - eta) / (depth + eta), 0.0) + depth
        I1 = s * np.sinh(k * zt) / (k * np.sinh(k * depth))
        I2 = s * (np.sinh(2 * k * zt) / (4 * k) + zt / 2) / np.sinh(k * depth) ** 2
    inertia = rho * (1 + ca) * math.pi * D**2 / 4 * a * omega**2 * np.sin(th) * I1
    drag = 0.5 * rho * cd * D * (a * omega) ** 2 * np.abs(np.cos(th)) * np.cos(th) * I2
    return inertia + drag


@pytest.mark.parametrize("depth", [math.inf, 20.0])
@pytest.mark.parametrize("top", [3.0, -1.5])
def test_a_fixed_vertical_cylinder_is_morison_s_closed_form(depth, top):
    """A vertical cylinder strip (D 2 m, C_D 1.2, C_A 1) on the held sphere, from z = −30 m
    (deep) or the sea bed (h = 20 m) up through the surface to 3 m above it, or to 1.5 m under
    still water (always submerged: the wave is 2 m high), in a regular wave (T 6 s deep, 8 s in
    20 m): the horizontal force over one period against the closed form (_closed_form), with N =
    25, 50, 100, 200 segments. Through the surface the midpoint rule meets the cut (the flow
    stops at η inside one segment): first order in the segment, measured 7.1, 3.4, 1.7, 0.77 %
    of the force's amplitude (deep; 3.2 … 0.41 % in 20 m): the error halves with the segment
    (ratio 2 ± 0.3) and at N = 200 is under 1 %. Submerged the integrand is smooth: second
    order, the error quarters (measured ratios 4.00), and at N = 200 is 1.1e-5 deep, 1.8e-6 in
    20 m (asserted: ratio 4 ± 0.3, under 1.5e-5)."""
    T, H = (6.0, 2.0) if math.isinf(depth) else (8.0, 2.0)
    bottom = -30.0 if math.isinf(depth) else -depth
    sea = hydro.Regular(height=H, period=T)
    comps = sea.components(water_depth=depth, g=G)
    times = np.linspace(0.0, T, 41)
    errs = []
    for n in (25, 50, 100, 200):
        m = _model({"body": "sphere", "from": [0.0, 0.0, bottom], "to": [0.0, 0.0, top],
                    "segments": n, "cd": 1.2, "diameter": 2.0, "ca": 1.0})
        ld = m.loads[-1]
        laid = ld.for_run(m, RunGrid(sea, 0.0, 0.1, 10, 0.0, (0.0, 0.5, 1.0)))
        if not math.isinf(depth):       # the sphere's database is deep: the wave in 20 m of water
            laid = dataclasses.replace(laid, wave=W.WaveField.of(comps))
        F = _horizontal_force(m, laid, times)
        ref = _closed_form(times, a=H / 2, omega=float(comps.omega[0]), k=float(comps.wavenumber[0]),
                           depth=depth, bottom=bottom, top=top, rho=float(m.hydro.rho), cd=1.2,
                           ca=1.0, D=2.0)
        errs.append(np.abs(F - ref).max() / np.abs(ref).max())
    errs = np.asarray(errs)
    ratios = errs[:-1] / errs[1:]
    order, tol = (2.0, 1e-2) if top > 0 else (4.0, 1.5e-5)
    assert errs[-1] < tol, errs
    assert np.all(np.abs(ratios - order) < 0.3), (errs, ratios)


# ----------------------------------------------------------- a point element's still-water decay
def test_a_point_element_s_heave_decay_is_the_reference_ode():
    """The sphere (heave free, no radiation memory) released 0.3 m above rest in still water,
    a point element at its axis (C_D 1, A 3 m², V 2 m³, C_A 0.5): its heave against scipy's
    solve_ivp of (M + ρ C_A V) z̈ + K z + ½ ρ C_D A |ż| ż = 0, with M and K the heave terms of
    the model without the element (its linear system at rest: the body's mass and A∞, the
    water-plane stiffness; the sphere's heave is linear at radiation="none") and the element's
    added mass and drag written by hand: 1e-5 of the release (RK4 at dt 0.01 s, ω dt ≈ 0.04,
    against rtol 1e-11). The drag takes a third of the amplitude in this time, and with C_A the
    period is longer: both are in the reference, so a missing mass term or a wrong drag fails."""
    from scipy.integrate import solve_ivp

    el = {"body": "sphere", "point": [0.0, 0.0, -0.3], "cd": 1.0, "area": 3.0, "volume": 2.0,
          "ca": 0.5}
    base = mfm.load(CONFIGS / "sphere.toml")
    m = _model(el)
    heave = list(base.coordinates).index("sphere.heave")
    from mfm.frequency.rest import linear_system

    sys = linear_system(base, np.zeros(base.n_coordinates))
    M, K = sys.M, sys.K
    rho = float(m.hydro.rho)
    Mz = M[heave, heave] + rho * 0.5 * 2.0
    Kz = K[heave, heave]
    c = 0.5 * rho * 1.0 * 3.0
    out = mfm.simulate(m, duration=12.0, dt=0.01, radiation="none", q0={"sphere.heave": 0.3},
                       check_stability=False)
    t = out.time.values
    z = out.q.sel(coordinate="sphere.heave").values
    ref = solve_ivp(lambda _, y: [y[1], -(Kz * y[0] + c * abs(y[1]) * y[1]) / Mz], (0, t[-1]),
                    [0.3, 0.0], t_eval=t, rtol=1e-11, atol=1e-13, method="DOP853").y[0]
    assert np.abs(z - ref).max() < 1e-5 * 0.3, np.abs(z - ref).max()
    # the drag mattered and so did the added mass (the reference without either is far off)
    bare = solve_ivp(lambda _, y: [y[1], -Kz * y[0] / M[heave, heave]], (0, t[-1]), [0.3, 0.0],
                     t_eval=t, rtol=1e-11, atol=1e-13).y[0]
    assert np.abs(z - bare).max() > 0.05
    f = out.morison_force.values[:, 0]
    np.testing.assert_allclose(f[:, 2], -c * np.abs(out.qd.sel(coordinate="sphere.heave").values)
                               * out.qd.sel(coordinate="sphere.heave").values
                               - rho * 0.5 * 2.0 * np.gradient(
                                   out.qd.sel(coordinate="sphere.heave").values, t),
                               atol=2e-2 * np.abs(f[:, 2]).max())


# --------------------------------------------------------------------------------- config errors
@pytest.mark.parametrize("change, message", [
    ({"body": "nosuch"}, r"morison\[0\]\.body: 'nosuch' is not a body"),
    ({"segments": 0}, r"morison\[0\]\.segments: 0; give a whole number ≥ 1"),
    ({"cd": -1.0}, r"morison\[0\]\.cd: -1\.0; give a drag coefficient ≥ 0"),
    ({"diameter": None}, r"morison\[0\]: give diameter \(m\) or area"),
    ({"area": 2.0}, r"morison\[0\]: give diameter \(m\) or area .*not both"),
    ({"cd": None}, r"morison\[0\]\.cd: missing"),
    ({"to": [0.0, 0.0, -10.0]}, r"morison\[0\]: from and to are one point"),
    ({"point": [0.0, 0.0, 0.0]}, r"morison\[0\]: give either point"),
    ({"ca": 1.0, "diameter": None, "area": 1.0},
     r"morison\[0\]\.ca: 1 on an element of no volume"),
    ({"colour": "red"}, r"morison\[0\]: unknown key\(s\) \['colour'\]"),
])
def test_config_errors_name_the_key_and_what_is_accepted(change, message):
    el = {"body": "sphere", "from": [0.0, 0.0, -10.0], "to": [0.0, 0.0, 1.0], "segments": 4,
          "cd": 1.0, "diameter": 1.0}
    for k, v in change.items():
        if v is None:
            el.pop(k)
        else:
            el[k] = v
    with pytest.raises(ConfigError, match=message):
        _model(el)


def test_from_python_it_is_the_config_s_load():
    """MorisonElements.create (start/end for the table's from/to) gives the load the config
    builds: the same structure and every array equal (so a run with it as loads= is the
    config's)."""
    from mfm.loads.morison import MorisonElements

    el = {"body": "sphere", "from": [0.0, 0.0, -5.0], "to": [1.0, 0.0, 0.5], "segments": 3,
          "cd": 0.8, "diameter": 0.5, "ca": 1.0}
    m = _model(el)
    ld = MorisonElements.create(mfm.load(CONFIGS / "sphere.toml"), "sphere", start=el["from"],
                                end=el["to"], segments=3, cd=0.8, diameter=0.5, ca=1.0)
    cfg = m.loads[-1]
    assert jax.tree_util.tree_structure(cfg) == jax.tree_util.tree_structure(ld)
    for a, b in zip(jax.tree_util.tree_leaves(cfg), jax.tree_util.tree_leaves(ld)):
        np.testing.assert_array_equal(np.asarray(a), np.asarray(b))
    with pytest.raises(ConfigError, match=r"morison\[0\]\.segments: missing"):
        MorisonElements.create(m, "sphere", start=el["from"], end=el["to"], cd=1.0, area=1.0)


def test_a_model_without_water_refuses_it_and_the_frequency_domain_takes_it():
    """[[morison]] without [hydro] names the table to add; a frequency response to waves and the
    spectral level take the element (its wave force), while the linearisation at rest
    takes the element's added mass ρ C_A V on its point's translations (to round-off) and no
    damping or stiffness (the drag's slope at rest is 0)."""
    cfg = tomllib.loads((CONFIGS / "double_pendulum.toml").read_text())
    cfg["morison"] = [{"body": cfg["bodies"][0]["name"], "point": [0.0, 0.0, 0.0], "cd": 1.0,
                       "area": 1.0}]
    with pytest.raises(ConfigError, match=r"morison\[0\]: \[\[morison\]\] elements need the "
                                          r"model's \[hydro\]"):
        mfm.load(cfg, base=CONFIGS)
    m = _model({"body": "sphere", "point": [0.0, 0.0, -0.3], "cd": 1.0, "area": 3.0,
                "volume": 2.0, "ca": 0.5})
    # a frequency response to waves takes the inertia term's wave force (tests/
    # test_fd_relative_drag.py), the spectral level the drag's stochastic linearisation too
    assert np.all(np.isfinite(mfm.frequency_response(m, np.array([1.0, 2.0])).rao.values))
    assert "drag_damping" in mfm.spectral_response(m, hydro.Jonswap(hs=1.0, tp=6.0))
    # at rest the element is its added mass on its point's translations (the point is the
    # sphere's CoM: surge and heave, not pitch), its drag of zero slope, no stiffness
    from mfm.frequency.rest import linear_system

    q0 = np.zeros(m.n_coordinates)
    a, b = linear_system(m, q0), linear_system(mfm.load(CONFIGS / "sphere.toml"), q0)
    ma = float(m.hydro.rho) * 0.5 * 2.0
    np.testing.assert_allclose(a.M - b.M, np.diag([ma, ma, 0.0]), rtol=0, atol=1e-9 * ma)
    np.testing.assert_allclose(a.K, b.K, rtol=0, atol=1e-9 * np.abs(b.K).max())
    np.testing.assert_allclose(a.C, b.C, rtol=0, atol=1e-9 * max(np.abs(b.C).max(), 1.0))


def test_a_batch_of_regular_seas_is_the_single_runs():
    """simulate_batch of two regular seas (one component each: the load's wave arrays stack on
    the case axis) gives each case's mfm.simulate to round-off (1e-12 of the motion: the same
    arithmetic, vmapped); seas of different numbers of components (a regular wave and a
    JONSWAP, and still water) run together, each case's wave padded with zero-amplitude
    components to the batch's most: each case is its own mfm.simulate, 1e-12 of its motion."""
    m = _model({"body": "sphere", "point": [0.0, 0.0, -0.3], "cd": 1.0, "area": 3.0,
                "volume": 2.0, "ca": 0.5})
    seas = [hydro.Regular(height=0.5, period=5.0), hydro.Regular(height=1.0, period=6.0)]
    run = dict(dt=0.05, radiation="none")
    b = mfm.simulate_batch(m, seas, n_steps=40, **run)
    for i, sea in enumerate(seas):
        r = mfm.simulate(m, sea, duration=2.0, check_stability=False, **run)
        np.testing.assert_allclose(b.q.isel(case=i).values, r.q.values, rtol=0,
                                   atol=1e-12 * np.abs(r.q.values).max())
    mixed = [seas[0], hydro.Jonswap(hs=1.0, tp=6.0, n_components=30), None]
    b = mfm.simulate_batch(m, mixed, n_steps=40, **run)
    for i, sea in enumerate(mixed):
        r = mfm.simulate(m, sea, duration=2.0, check_stability=False, **run)
        scale = max(np.abs(r.q.values).max(), 1e-300)
        np.testing.assert_allclose(b.q.isel(case=i).values, r.q.values, rtol=0,
                                   atol=1e-12 * scale)


def test_a_point_element_at_rest_takes_every_component_at_any_heading():
    """A point element (C_D 0.9, A 1.5 m², V 0.8 m³, C_A 0.7) held at z = −2 m in a 1.2 m wave
    heading 60°: the force (surge, heave on the planar sphere; the sway part has no coordinate,
    so surge reads f_x) against ½ ρ C_D A |u| u + ρ (1 + C_A) V u̇ of the closed-form deep-water
    kinematics, u = a ω e^{kz_s} (cos θ cos β, cos θ sin β, sin θ), u̇ = a ω² e^{kz_s} (sin θ cos β,
    sin θ sin β, −cos θ), z_s = z − η (Wheeler), θ = k(x cos β + y sin β) − ωt: 1e-12 of the
    largest (the same arithmetic in another order). With a ramp of one period the amplitude is
    a ½(1 − cos πt/T) before it, as the water's excitation (hydro.waves.ramp)."""
    x0 = np.array([0.4, 0.0, -2.0])
    m = _model({"body": "sphere", "point": x0.tolist(), "cd": 0.9, "area": 1.5, "volume": 0.8,
                "ca": 0.7})
    beta, a, T = math.radians(60.0), 0.6, 5.0
    sea = hydro.Regular(height=2 * a, period=T, heading=beta)
    times = np.linspace(0.0, 2 * T, 33)
    q = jnp.zeros(m.n_coordinates)
    kin = kinematics(m, q, q)
    w = 2 * math.pi / T
    k = w**2 / G
    th = k * (x0[0] * math.cos(beta) + x0[1] * math.sin(beta)) - w * times
    rho = float(m.hydro.rho)
    for ramp in (0.0, T):
        laid = m.loads[-1].for_run(m, RunGrid(sea, 0.0, 0.1, 10, ramp, (0.0, 0.5, 1.0)))
        f = jax.jit(jax.vmap(lambda t: laid.evaluate(Context(m, t, q, q, jnp.zeros(0), kin)).tau))
        tau = np.asarray(f(jnp.asarray(times)))
        ar = a * (np.where(times < ramp, 0.5 * (1 - np.cos(np.pi * times / T)), 1.0) if ramp
                  else 1.0)
        e = np.exp(k * (x0[2] - ar * np.cos(th)))
        u = ar * w * e * np.stack([np.cos(th) * math.cos(beta), np.cos(th) * math.sin(beta),
                                   np.sin(th)])
        ud = ar * w**2 * e * np.stack([np.sin(th) * math.cos(beta), np.sin(th) * math.sin(beta),
                                       -np.cos(th)])
        ref = 0.5 * rho * 0.9 * 1.5 * np.linalg.norm(u, axis=0) * u + rho * 1.7 * 0.8 * ud
        for c, i in (("sphere.surge", 0), ("sphere.heave", 2)):
            j = list(m.coordinates).index(c)
            np.testing.assert_allclose(tau[:, j], ref[i], rtol=0, atol=1e-12 * np.abs(ref).max())


def test_an_inclined_member_takes_the_flow_normal_to_its_axis():
    """A submerged member inclined at 45° in the x–z plane (from (−3, 0, −12) to (3, 0, −6)),
    held, in a 2 m, 6 s deep-water wave: the surge and heave force and the pitch moment about
    the CoM against scipy's quad along the member of f = ½ ρ C_D D |u_n| u_n + ρ (1 + C_A)
    (π D²/4) u̇_n, u_n = u − e (e·u), with the closed-form stretched kinematics (independent of
    hydro.wetted): within 3e-5 of each series' largest at N = 100, the midpoint rule's error on
    this smooth integrand (measured 4.7e-6 for the forces, 9.9e-6 for the moment, whose lever
    adds to the integrand's curvature; (kΔ)²/24 ≈ 4e-6). Without the projection the axial flow
    would add a force of the order of the normal one."""
    from scipy.integrate import quad

    a0, b0 = np.array([-3.0, 0.0, -12.0]), np.array([3.0, 0.0, -6.0])
    m = _model({"body": "sphere", "from": a0.tolist(), "to": b0.tolist(), "segments": 100,
                "cd": 1.1, "diameter": 0.8, "ca": 0.9})
    a, T = 1.0, 6.0
    sea = hydro.Regular(height=2 * a, period=T)
    laid = m.loads[-1].for_run(m, RunGrid(sea, 0.0, 0.1, 10, 0.0, (0.0, 0.5, 1.0)))
    times = np.linspace(0.0, T, 9)
    q = jnp.zeros(m.n_coordinates)
    kin = kinematics(m, q, q)
    tau = np.asarray(jax.jit(jax.vmap(lambda t: laid.evaluate(
        Context(m, t, q, q, jnp.zeros(0), kin)).tau))(jnp.asarray(times)))
    w = 2 * math.pi / T
    k = w**2 / G
    rho, L = float(m.hydro.rho), float(np.linalg.norm(b0 - a0))
    e = (b0 - a0) / L
    com = np.asarray(m.com)[0]

    def per_metre(s, t):
        x = a0 + s * e
        th = k * x[0] - w * t
        decay = math.exp(k * (x[2] - a * math.cos(th)))
        u = a * w * decay * np.array([math.cos(th), 0.0, math.sin(th)])
        ud = a * w**2 * decay * np.array([math.sin(th), 0.0, -math.cos(th)])
        un, udn = u - e * (e @ u), ud - e * (e @ ud)
        f = 0.5 * rho * 1.1 * 0.8 * np.linalg.norm(un) * un + rho * 1.9 * math.pi * 0.16 * udn
        return f, np.cross(x - com, f)

    ref = np.array([[quad(lambda s: (per_metre(s, t)[0][0], per_metre(s, t)[0][2],
                                     per_metre(s, t)[1][1])[i], 0.0, L, epsabs=0,
                          epsrel=1e-10)[0] for i in range(3)] for t in times])
    for i, c in enumerate(("sphere.surge", "sphere.heave", "sphere.pitch")):
        j = list(m.coordinates).index(c)
        np.testing.assert_allclose(tau[:, j], ref[:, i], rtol=0,
                                   atol=3e-5 * np.abs(ref[:, i]).max(), err_msg=c)
