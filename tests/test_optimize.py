"""mfm.optimize (design by gradient) against routes that share none of its code: the spectral
level's numpy solve (:func:`mfm.spectral_response`), central differences of it, a brute-force grid,
the time domain; one compilation per structure counted by TRACES; bad input named."""
import warnings

import numpy as np
import pytest

import mfm
from hydro.waves import Regular
from mfm.errors import OptimizeError
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
    np.testing.assert_array_equal(np.isnan(O._safe_sqrt(v)), [False, False, True])
    assert float(O._safe_sqrt(v)[0]) == 2.0 and float(O._safe_sqrt(v)[1]) == 0.0
    assert float(jax.grad(lambda x: O._safe_sqrt(x))(0.0)) == 0.0


def test_confirm_reads_the_pistons_power_as_simulate_does(tmp_path):
    """The time-domain confirmation of a hydraulic PTO (it asked simulate_batch for a
    'hydraulic_power' output that no run records, a ValueError): β ẇ² from the samples q, q̇ with
    the load's own kinematics against mfm.simulate's recorded piston power, on a slider whose
    inclined piston makes ẇ = g(q) q̇ nonlinear in q: the same samples, round-off apart."""
    from test_ptos_and_checks import _write, slider_config

    data = slider_config(True)
    data["ptos"][0]["anchor"] = [-2.0, 0.0, 0.0]        # inclined: g depends on q
    model = mfm.load(_write(tmp_path / "pto.toml", data))
    run = mfm.simulate(model, duration=1.0, dt=0.002, q0=[0.3])
    p = O._hydraulic_power(model, run.q.values, run.qd.values)
    ref = run.pto_power.sel(pto="piston").values
    assert p.shape == (run.sizes["time"], 1) and np.ptp(ref) > 0.1 * np.abs(ref).max()
    np.testing.assert_allclose(p[:, 0], ref, rtol=1e-10, atol=1e-12 * np.abs(ref).max())


def test_bad_input_is_named(m4):
    with pytest.raises(KeyError, match="float3.angle.damping"):      # lists the tunable ones
        O.optimize(m4, SEA, {"float3.damping": (0.0, 1.0)})
    with pytest.raises(ValueError, match="lower < upper"):
        O.optimize(m4, SEA, {"float3.angle.damping": (5.0, 1.0)})
    with pytest.raises(ValueError, match="finite"):
        O.optimize(m4, SEA, {"float3.angle.damping": (0.0, np.inf)})
    with pytest.raises(KeyError, match="neither a coordinate nor a PTO"):
        O.optimize(m4, SEA, PAIRS, constraints={"float9.pitch": {"rms": 0.1}})
    with pytest.raises(ValueError, match="weights"):
        O.optimize(m4, [SEA, SEA], PAIRS, weights=[1.0, -1.0])
    with pytest.raises(OptimizeError, match="cannot be met") as err:
        O.optimize(m4, SEA, PAIRS, constraints={"float1.pitch": {"rms": 1e-4}})
    assert set(err.value.last_good) == {" + ".join(k) for k in PAIRS}
