"""mfm.optimize (design by gradient) against routes that share none of its code: the spectral
level's numpy solve (:func:`mfm.spectral_response`), central differences of it, a brute-force grid,
the time domain; one compilation per structure counted by TRACES; bad input named."""
import warnings

import numpy as np
import pytest

import mfm
from hydro.waves import Regular
from mfm.errors import OptimizeError
from mfm.studies import design as D
from mfm.studies import optimize as O

SEA = Regular(height=0.02, period=1.2)          # M4 134's band (tank scale), linear at 2 cm
PAIRS = {("float3.angle.damping", "float6.angle.damping"): (0.0, 20.0),
         ("float7.angle.damping", "float8.angle.damping"): (0.0, 20.0)}
GRID = np.linspace(0.0, 20.0, 21)               # 1 N m s/rad apart


@pytest.fixture(scope="module")
def m4():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return mfm.load("configs/m4_134.toml")


def _spectral_power(model, values):
    return float(mfm.spectral_response(O.apply(model, values), SEA).pto_power_mean.sum())


def test_objective_and_gradient_against_the_numpy_spectral_level(m4):
    """The objective is the spectral level's mean power, computed by its own numpy route; its jax
    derivatives against central differences of that route, for a damping (linear in Z), a
    stiffness and a mass (both move the equilibrium: the implicit derivative of custom_root)."""
    names = ["float3.angle.damping", "float3.angle.stiffness", "float1.mass"]
    base = np.array([6.0, 0.0, float(m4.mass[0])])
    P = O._setup(m4, SEA, {n: (b - 1.0, b + 1.0) for n, b in zip(names, base)}, "power", None,
                 None, None, "database", None, 40, "forward")
    out, J, _ = O._run(P, (base - P.lower) / (P.upper - P.lower), 1.0)
    values = dict(zip(names, base))
    # two routes of one sum: round-off of a 7×7 complex solve per component, ~1e-15 relative
    assert out[0] == pytest.approx(_spectral_power(m4, values), rel=1e-12)
    grad = J[0] / (P.upper - P.lower)
    for k, (n, b) in enumerate(zip(names, base)):
        # central difference: truncation h² f'''/6 ~ 1e-7 relative at h = 1e-3 of the scale; the
        # equilibrium's Newton tolerance (1e-10 of the weights) adds ≲ 1e-6 after dividing by h
        h = 1e-3 * max(abs(b), 1.0)
        fd = (_spectral_power(m4, {**values, n: b + h}) - _spectral_power(m4, {**values, n: b - h})) / (2 * h)
        assert grad[k] == pytest.approx(fd, rel=1e-4, abs=1e-5 * abs(out[0]) / max(abs(b), 1.0)), n


def test_optimum_against_a_brute_force_grid(m4):
    """Never below the grid's best point, and within one grid step of where it is; the optimum's
    power again by the numpy route."""
    ds = O.optimize(m4, SEA, PAIRS)
    A, B = np.meshgrid(GRID, GRID, indexing="ij")
    ev = O.evaluate(m4, SEA, {k: v.ravel() for k, v in zip(PAIRS, (A, B))})
    best = int(np.argmax(ev["objective"]))
    assert float(ds.objective) >= ev["objective"][best] * (1 - 1e-12)
    step = GRID[1] - GRID[0]
    assert abs(float(ds.optimum[0]) - A.ravel()[best]) <= step
    assert abs(float(ds.optimum[1]) - B.ravel()[best]) <= step
    opt = {n: float(v) for k, v in zip(PAIRS, ds.optimum.values) for n in k}
    assert float(ds.objective) == pytest.approx(_spectral_power(m4, opt), rel=1e-12)
    assert float(ds.gain) > 0.1        # the seed's 6 N m s/rad everywhere is not the optimum here
    assert float(ds.gradient_norm) < 1e-3
    assert list(ds.parameter.values) == [" + ".join(k) for k in PAIRS]


def test_a_pitch_limit_holds_and_the_optimum_beats_the_feasible_grid(m4):
    """rms(float1.pitch) ≤ 0.025 rad (0.032 at the unconstrained optimum): active at the
    optimum, met there, and no feasible grid point does better."""
    limit = 0.025
    cons = {"float1.pitch": {"rms": limit}}
    ds = O.optimize(m4, SEA, PAIRS, constraints=cons)
    assert bool(ds.constraint_active.item())
    assert float(ds.constraint_value.item()) <= limit * (1 + 1e-6)
    # the limit by the numpy route at the optimum
    opt = {n: float(v) for k, v in zip(PAIRS, ds.optimum.values) for n in k}
    q = mfm.spectral_response(O.apply(m4, opt), SEA).q_rms.sel(coordinate="float1.pitch")
    assert float(q) <= limit * (1 + 1e-6)
    A, B = np.meshgrid(GRID, GRID, indexing="ij")
    ev = O.evaluate(m4, SEA, {k: v.ravel() for k, v in zip(PAIRS, (A, B))}, constraints=cons)
    feasible = ev["constraints"][:, 0] <= limit
    assert feasible.any()
    assert float(ds.objective) >= ev["objective"][feasible].max() * (1 - 1e-9)


def test_numeric_variants_reuse_one_compilation(m4):
    """Other bounds, another sea of the same shape, another mass, another limit: no retrace."""
    O.optimize(m4, SEA, PAIRS, constraints={"float1.pitch": {"rms": 0.05}})
    before = O.TRACES["outputs"]
    ds = O.optimize(m4.set_mass("float2", float(m4.mass[1]) * 1.05), Regular(height=0.03, period=1.0),
                    {k: (1.0, 15.0) for k in PAIRS}, constraints={"float1.pitch": {"rms": 0.04}})
    assert O.TRACES["outputs"] == before
    assert np.isfinite(float(ds.objective))


def test_time_domain_confirms_the_optimum(m4):
    """The optimised model stepped (Verlet, exact radiation) in the same regular wave: its mean
    power after 15 s within 1 % of the spectral level's (measured +0.10 %; what differs is the
    model's nonlinearity at 2 cm and the dt = T/200 phase error, each ≲ 0.2 %)."""
    ds = O.optimize(m4, SEA, PAIRS, confirm=dict(dt=0.006, n_steps=5000, settle=15.0))
    assert abs(float(ds.time_domain_relative_difference)) < 0.01
    assert float(ds.time_domain_objective) > float(ds.objective_baseline)


def test_safe_sqrt_keeps_a_nan():
    """A response gone non-finite (an equilibrium Newton diverged) reads NaN in q_rms and the
    limits, never 0 (a met limit); √ at 0 keeps a finite derivative 0."""
    import jax
    import jax.numpy as jnp
    v = jnp.array([4.0, 0.0, jnp.nan])
    np.testing.assert_array_equal(np.isnan(D._safe_sqrt(v)), [False, False, True])
    assert float(D._safe_sqrt(v)[0]) == 2.0 and float(D._safe_sqrt(v)[1]) == 0.0
    assert float(jax.grad(lambda x: D._safe_sqrt(x))(0.0)) == 0.0


def test_bad_input_is_named(m4):
    with pytest.raises(KeyError, match="float3.angle.damping"):      # lists the tunable ones
        O.optimize(m4, SEA, {"float3.damping": (0.0, 1.0)})
    with pytest.raises(ValueError, match="lower < upper"):
        O.optimize(m4, SEA, {"float3.angle.damping": (5.0, 1.0)})
    with pytest.raises(ValueError, match="finite"):
        O.optimize(m4, SEA, {"float3.angle.damping": (0.0, np.inf)})
    with pytest.raises(KeyError, match="neither a coordinate, a PTO nor a catenary"):
        O.optimize(m4, SEA, PAIRS, constraints={"float9.pitch": {"rms": 0.1}})
    with pytest.raises(ValueError, match="weights"):
        O.optimize(m4, [SEA, SEA], PAIRS, weights=[1.0, -1.0])
    with pytest.raises(OptimizeError, match="cannot be met") as err:
        O.optimize(m4, SEA, PAIRS, constraints={"float1.pitch": {"rms": 1e-4}})
    assert set(err.value.last_good) == {" + ".join(k) for k in PAIRS}
    # an objective non-finite past 10 N m s/rad, started at 20: stopped at once, and the last
    # finite point is the model's own (6 N m s/rad on every hinge, evaluated first)
    import jax.numpy as jnp

    def nan_above_10(r):
        return jnp.where(r.values[0] < 10.0, O.mean_power(r), jnp.nan)

    with pytest.raises(OptimizeError, match="non-finite") as err:
        O.optimize(m4, SEA, PAIRS, objective=nan_above_10, x0={" + ".join(k): 20.0 for k in PAIRS})
    assert err.value.last_good == {" + ".join(k): 6.0 for k in PAIRS}


def test_drag_linearisation_is_a_fixed_point_of_the_numpy_route():
    """Stansby & Li (drag on its floats' own velocity): the linearised drag c_eq = D √(8/π) σ_v
    that optimize converges to in jax is (a) the numpy spectral level's own stochastic
    linearisation of the same drag (mfm.frequency.drag: its mean power and its C, another
    implementation of the fixed point) and (b), put on the model as plain linear dampers at the
    water's reference points (LinearBodyMatrix), gives through frequency_response velocity standard
    deviations σ_v that reproduce c_eq (Borgman's condition). Tolerance 1e-6: each fixed point's
    last relative change is below 1e-10 (optimize: 40 iterations; the spectral level: to 1e-10);
    1e-6 leaves room for the two routes' round-off in the 7×7 solves (measured 2e-15 on the
    power)."""
    import jax.numpy as jnp

    from hydro.waves import Jonswap
    from mfm.frequency.rest import linear_hydro, system_loads
    from mfm.loads.body_matrix import LinearBodyMatrix

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        m = mfm.load("configs/stansby_li.toml")
    sea = Jonswap(hs=2.0, tp=9.0, gamma=3.3, seed=1, omega_range=(0.3, 2.0))
    ev = O.evaluate(m, sea, {"floatB.angle.damping": [2e9]})
    P = O._setup(m, sea, {"floatB.angle.damping": (0.0, 4e9)}, "power", None, None, None,
                 "database", None, 40, "auto")
    _, _, r = O._run(P, np.array([0.5]), 1.0)
    assert float(r.drag_change) < 1e-10
    c_eq = r.drag_damping[0].reshape(-1, 6)                 # (K, 6): translations only
    water = linear_hydro(system_loads(m))
    D = np.asarray(water.drag)
    assert np.all(c_eq[:, 3:] == 0) and np.any(c_eq[:, :3] > 0)
    g = water.geometry
    dampers = tuple(LinearBodyMatrix.create(m, m.body_names[b], point=np.asarray(g.ref0[k]),
                                            damping=np.concatenate([c_eq[k, :3], np.zeros(3)]))
                    for k, b in enumerate(g.body_index) if np.any(c_eq[k] > 0))
    linear = m.replace(loads=m.loads + dampers)
    sp = mfm.spectral_response(m, sea)
    assert float(sp.pto_power_mean.sum()) == pytest.approx(float(ev["objective"][0]), rel=1e-6)
    assert "bodies' own velocity" in sp.attrs["drag_linearisation"]
    C = sp.drag_damping.isel(case=0).values if "case" in sp.drag_damping.dims \
        else sp.drag_damping.values                             # (K, 3, 3), diagonal per axis
    np.testing.assert_allclose(np.einsum("kaa->ka", C), c_eq[:, :3], rtol=1e-6,
                               atol=1e-9 * c_eq.max())
    assert np.all(C - np.einsum("ka,ab->kab", np.einsum("kaa->ka", C), np.eye(3)) == 0)
    comps = sea.components(water_depth=m.hydro.water_depth, g=m.hydro.g)
    fr = mfm.frequency_response(linear, comps.omega, heading=float(comps.heading[0]),
                                joint_reactions=False)
    v = fr.xi_rao.values * comps.omega[:, None]             # (n_ω, 6K) per metre
    sigma_v = np.sqrt(np.sum(0.5 * comps.amplitude[:, None] ** 2 * np.abs(v) ** 2, axis=0))
    expect = D * np.sqrt(8 / np.pi) * sigma_v.reshape(-1, 6)[:, :3]
    np.testing.assert_allclose(c_eq[:, :3], expect, rtol=1e-6, atol=1e-9 * expect.max())
    assert jnp.isfinite(r.power).all()


def test_line_tension_against_the_frequency_domain_and_as_a_limit():
    """Wu & Yuan m1's catenary lines: the tension optimize limits is the frequency domain's
    ``fairlead_tension_rao`` (σ_T = |T̂| a/√2 in a regular wave; the same linearisation by another
    route) and T₀ the lines' own tension at the equilibrium; a "peak" limit T₀ + 2σ_T set between
    the baseline and the unconstrained optimum holds the optimum and is met."""
    from mfm.frequency.rest import equilibrium, system_loads
    from mfm.loads.catenary import CatenaryLines
    from mfm.mechanics.kinematics import kinematics

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        m = mfm.load("configs/wu_yuan_m1.toml")
    sea = Regular(height=2.0, period=8.0)
    wecs = (tuple(f"wec{i}.angle.damping" for i in range(1, 13)),)
    free = O.optimize(m, sea, {wecs[0]: (1e6, 2e8)})
    ev = O.evaluate(m, sea, {wecs[0]: [4.1e7, float(free.optimum[0])]})
    P = O._setup(m, sea, {wecs[0]: (1e6, 2e8)}, "power", None, None, None, "database", None, 40,
                 "auto")
    _, _, r = O._run(P, (np.array([4.1e7]) - P.lower) / (P.upper - P.lower), 1.0)
    fr = mfm.frequency_response(m, [sea.omega], heading=0.0, joint_reactions=False)
    np.testing.assert_allclose(r.tension_rms[0], np.abs(fr.fairlead_tension_rao.values[0]) * 1.0
                               / np.sqrt(2), rtol=1e-9)
    lines = next(ld for ld in system_loads(m) if isinstance(ld, CatenaryLines))
    q0 = equilibrium(m)[0]
    zero = np.zeros(m.n_coordinates)
    H, V, _ = lines.tensions(lines.fairleads.positions(kinematics(m, q0, zero)))
    np.testing.assert_allclose(r.tension, np.hypot(H, V), rtol=1e-9)
    # the most loaded line's peak at the baseline and at the free optimum
    name = lines.names[int(np.argmax(r.tension + 2 * r.tension_rms[0]))]
    both = O.evaluate(m, sea, {wecs[0]: [4.1e7, float(free.optimum[0])]},
                      constraints={f"{name}.tension": {"peak": 1.0}})["constraints"][:, 0]
    assert both[0] != both[1]
    limit = 0.5 * (both[0] + both[1])
    ds = O.optimize(m, sea, {wecs[0]: (1e6, 2e8)}, constraints={f"{name}.tension": {"peak": limit}})
    assert bool(ds.constraint_active.item())
    assert float(ds.constraint_value.item()) <= limit * (1 + 1e-9)
    assert float(ds.objective) <= float(free.objective) * (1 + 1e-12)
    assert ev["objective"][1] >= ev["objective"][0]


def test_damped_newton_reaches_the_equilibrium_the_undamped_one_misses(m4):
    """float3 at 12 × its mass: the undamped Newton of 8 steps from the baseline equilibrium (the
    engine's own solver with max_iter=8 takes exactly those steps) does not converge; the damped
    Newton of optimize does, to the root the engine's solver reaches in 50 steps from the same
    start (an independent route: numpy lstsq Newton, its own stopping test). Tolerance 1e-9 rad or
    m: both roots are converged to ~1e-15 of the weights, J is well conditioned there."""
    from mfm.frequency.rest import equilibrium

    b = float(m4.mass[2])
    q_base = equilibrium(m4)[0]
    heavy = O.apply(m4, {"float3.mass": 12 * b})
    with pytest.raises(ValueError, match="no static equilibrium"):
        equilibrium(heavy, q_base, max_iter=8)
    q_engine = equilibrium(heavy, q_base, max_iter=50)[0]
    P = O._setup(m4, SEA, {"float3.mass": (0.0, 20 * b)}, "power", None, None, None, "database",
                 None, 40, "forward")
    out, J, r = O._run(P, np.array([12 / 20]), 1.0)
    assert float(r.equilibrium_residual) < 1e-12
    np.testing.assert_allclose(r.q0, q_engine, atol=1e-9)
    assert np.isfinite(out).all() and np.isfinite(J).all()
    # the spectral power about that equilibrium by the numpy route
    assert out[0] == pytest.approx(_spectral_power(m4, {"float3.mass": 12 * b}), rel=1e-9)


def test_no_equilibrium_is_refused_with_the_parameters_and_the_residual():
    """The sphere 10 % heavier than the water it displaces, with a heave spring −K₃₃ that cancels
    its hydrostatic heave stiffness: Q_heave = ρgV − mg ≠ 0 for every heave, no equilibrium
    exists. optimize refuses it by name (the values, the residual, the cause) with the last point
    that had one; evaluate returns NaN there with the residual."""
    from mfm.frequency.rest import linear_system

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        m = mfm.load("configs/sphere.toml")
    heave = m.coordinates.index("sphere.heave")
    K33 = float(linear_system(m).K[heave, heave])
    assert K33 > 0
    mass = float(m.mass[0])
    sea = Regular(height=0.5, period=6.0)
    params = {"sphere.mass": (0.5 * mass, 2.0 * mass), "sphere.heave.stiffness": (-K33, K33)}
    with pytest.raises(OptimizeError, match="no static equilibrium") as err:
        O.optimize(m, sea, params, x0={"sphere.mass": 1.1 * mass, "sphere.heave.stiffness": -K33})
    msg = str(err.value)
    # the residual is the unbalanced 0.1 m g over the largest weight 1.1 m g: 1/11 (3 digits)
    assert "max|Q(q0)| = 0.0909 " in msg and "sphere.heave.stiffness" in msg and "capsizes" in msg
    assert err.value.last_good == {"sphere.mass": mass, "sphere.heave.stiffness": 0.0}
    ev = O.evaluate(m, sea, {"sphere.mass": [mass, 1.1 * mass],
                             "sphere.heave.stiffness": [0.0, -K33]})
    assert ev["equilibrium_residual"][0] < 1e-12 and ev["equilibrium_residual"][1] > 0.05
    assert np.isfinite(ev["objective"][0]) and np.isnan(ev["objective"][1])


def test_control_stiffness_acts_about_the_equilibrium(m4):
    """float3 at twice its mass (its hinge at rest at 0.17 rad, not at the config's rest 0):
    a controller stiffness k_c about q₀ leaves the equilibrium where it is (against the engine's
    equilibrium, 1e-10 rad: both converged to ~1e-15 of the weights), and the objective and its
    derivative in k_c are those of the numpy spectral route for the same model with a joint spring
    k_c whose rest angle is q₀ (an independent construction of the same force): value 1e-9
    relative (two routes' round-off and q₀ to 1e-12), derivative against central differences,
    h = 1e-3 of the hydrostatic hinge stiffness (truncation ~1e-7 relative) at 1e-5. apply()
    writes the same spring for the time domain; another k_c, mass or model does not retrace."""
    from mfm.frequency.rest import equilibrium, linear_system

    b = float(m4.mass[2])
    heavy = O.apply(m4, {"float3.mass": 2 * b})
    q0 = equilibrium(heavy)[0]
    i = heavy.coordinates.index("float3.angle")
    assert abs(q0[i]) > 0.1
    Kh = float(linear_system(heavy, q0).K[i, i])
    kc = -0.3 * Kh                                     # reactive: cancels 30 % of the restoring
    names = ["float3.angle.control_stiffness", "float3.angle.damping", "float3.mass"]
    bounds = {"float3.angle.control_stiffness": (-Kh, Kh), "float3.angle.damping": (0.0, 20.0),
              "float3.mass": (0.5 * b, 3 * b)}
    P = O._setup(m4, SEA, bounds, "power", None, None, None, "database", None, 40, "forward")
    assert "float3.angle.control_stiffness" in O.tunable_parameters(m4)

    def run(values):
        th = np.array([values[n] for n in names])
        return O._run(P, (th - P.lower) / (P.upper - P.lower), 1.0)

    at = {"float3.angle.control_stiffness": kc, "float3.angle.damping": 6.0, "float3.mass": 2 * b}
    out, J, r = run(at)
    before = O.TRACES["outputs"]
    _, _, r0 = run({**at, "float3.angle.control_stiffness": 0.0})
    np.testing.assert_allclose(r.q0, q0, atol=1e-10)
    np.testing.assert_array_equal(r.q0, r0.q0)          # not in the equilibrium at all

    def numpy_power(k):
        stiff = np.array(heavy.stiffness, dtype=float)
        rest = np.array(heavy.rest, dtype=float)
        stiff[i], rest[i] = k, q0[i]
        sprung = heavy.replace(stiffness=stiff, rest=rest)
        return float(mfm.spectral_response(sprung, SEA).pto_power_mean.sum())

    assert out[0] == pytest.approx(numpy_power(kc), rel=1e-9)
    assert r0.power.sum() == pytest.approx(numpy_power(0.0), rel=1e-9)
    assert abs(out[0] - float(r0.power.sum())) > 1e-3 * out[0]      # it does act
    h = 1e-3 * Kh
    fd = (numpy_power(kc + h) - numpy_power(kc - h)) / (2 * h)
    grad = J[0, 0] / (P.upper[0] - P.lower[0])
    assert grad == pytest.approx(fd, rel=1e-5)
    # apply(): the joint spring about q₀ the time domain steps
    applied = O.apply(m4, {"float3.mass": 2 * b, "float3.angle.control_stiffness": kc})
    assert float(applied.stiffness[i]) == pytest.approx(kc, rel=1e-15)
    assert float(applied.rest[i]) == pytest.approx(q0[i], abs=1e-10)
    # other numbers, another model of the same structure: one compilation
    O._run(P, np.array([0.2, 0.7, 0.4]), 1.0)
    P2 = O._setup(m4.set_mass("float2", float(m4.mass[1]) * 1.05), SEA, bounds, "power", None,
                  None, None, "database", None, 40, "forward")
    O._run(P2, np.array([0.3, 0.5, 0.5]), 1.0)
    assert O.TRACES["outputs"] == before
