"""The nonlinear level with its hull pressure sampled every few steps (``[hydro] nonlinear_dt``,
:class:`mfm.loads.water.HeldHulls`): every stage takes the linear level's loads plus the pressure
integral's excess over them, Δ, sampled at the end of every k-th step and extrapolated
quadratically from the last three samples.

Shown against the every-stage level (the reference: the same hull, the pressure at each of
RK4's evaluations): its linear part is the linear level's to round-off (the Froude–Krylov sum
against the tables' own, the hydrostatics against the linear water's); linearised at rest it is
the every-stage level exactly; a large undamped heave decay and a run in a wave converge to the
every-stage run at third order in the sampling interval (the error of a quadratic
extrapolation, O(h³) per interval: ×8 for each doubling of k; > 5 asserted, the first doubling
leaving the asymptotic range least); its config and its dt are checked."""
from __future__ import annotations

import copy
import tomllib

import jax.numpy as jnp
import numpy as np
import pytest
from conftest import CONFIGS

import hydro
import mfm
from mfm.errors import ConfigError

pytestmark = pytest.mark.filterwarnings("ignore::hydro.database.HydroDatabaseWarning")

SPHERE = tomllib.loads((CONFIGS / "sphere.toml").read_text())


def _sphere(**hydro_keys):
    """The floating sphere (surge, heave, pitch) at the nonlinear level, its hull's panels 0.25 m
    (the runs here compare the level with itself: a coarse hull is as good a reference)."""
    cfg = copy.deepcopy(SPHERE)
    cfg["hydro"].update({"hydrostatics": "nonlinear", **hydro_keys})
    cfg["bodies"][0]["hull"] = {"shape": "sphere", "radius": 1.0, "panel_size": 0.25}
    return mfm.load(cfg, base=CONFIGS)


@pytest.mark.filterwarnings("ignore:dropped 1 wave component:UserWarning")   # beyond the database
def test_its_linear_part_is_the_linear_level():
    """HeldHulls.linear at a pitched, heaved, surged pose and times on and after the ramp: its
    Froude–Krylov force is the tables' (froude_krylov_series, build_water's numpy sum) and its
    hydrostatics the linear water's buoyancy and −C_wp ξ, each to 1e-12 of its scale."""
    from mfm.loads.water import build_water, froude_krylov_series
    from mfm.mechanics.kinematics import kinematics

    model = _sphere(nonlinear_dt=0.1)
    sea = hydro.Jonswap(hs=0.5, tp=4.5, n_components=4, seed=3)
    spec = model.hydro
    held = build_water(model, spec, sea, dt=0.05, duration=2.0, ramp=1.0, radiation="none")
    lin = build_water(mfm.load(CONFIGS / "sphere.toml"), mfm.load(CONFIGS / "sphere.toml").hydro,
                      sea, dt=0.05, duration=2.0, ramp=1.0, radiation="none")
    assert held.hulls.hold.every == 2
    kin = kinematics(model, jnp.asarray([0.3, 0.2, 0.15]), jnp.zeros(3))
    hulls, geo = held.hulls, held.geometry
    comps = sea.components(water_depth=spec.water_depth, g=spec.g)
    ts = np.array([0.3, 0.8, 1.7])
    table = froude_krylov_series(spec, comps, ts, 1.0)
    from hydro.wetted import ramped
    for t, row in zip(ts, table):
        hs, fk = hulls.hold.linear(geo, kin, ramped(hulls.wave, hulls.ramp, t), t)
        np.testing.assert_allclose(np.asarray(fk), row, rtol=0, atol=1e-12 * np.abs(table).max())
        comps_lin = lin._forces(t, kin, jnp.zeros(0), (), np.arange(6))[0]
        ref = np.asarray(comps_lin["buoyancy"] + comps_lin["hydrostatic"])
        np.testing.assert_allclose(np.asarray(hs), ref, rtol=0, atol=1e-12 * np.abs(ref).max())


def test_linearised_at_rest_it_is_the_every_stage_level():
    """The linearisation at rest drops the samples (static_load: the pressure at every call):
    the held model's M, C and K are the every-stage model's, to the bit."""
    a = mfm.frequency.linearise(_sphere())
    b = mfm.frequency.linearise(_sphere(nonlinear_dt=0.2))
    for x, y in zip(a, b):
        np.testing.assert_array_equal(np.asarray(x), np.asarray(y))


def _errors(run, outputs, ks, coords):
    """The largest difference of each coordinate's series from the every-stage run, as a
    fraction of its range, for the held level at each k (nonlinear_dt = k dt)."""
    ref = mfm.simulate(_sphere(), **run)
    out = []
    for k in ks:
        d = mfm.simulate(_sphere(nonlinear_dt=k * run["dt"]), **run)
        assert d.attrs["hull_pressure"].startswith(f"sampled every {k} steps")
        out.append([float(np.abs(d.q.sel(coordinate=c).values - ref.q.sel(coordinate=c).values)
                          .max() / np.ptp(ref.q.sel(coordinate=c).values)) for c in coords])
    return np.array(out), ref


def test_a_large_heave_decay_converges_at_third_order():
    """Released 0.4 m above rest, no radiation, no drag (test_nonlinear_hydrostatics' decay):
    sampled every 1, 2, 4 steps of 0.02 s (ω h = 0.05–0.2), the heave's difference from the
    every-stage run falls ×8 per halving of the interval (third order; > 5 asserted), and at
    every step it is below 1e-3 of the swing (measured 2–3e-4 over 12 s: the extrapolation's
    error acts as a small negative damping, O((ω h)³) per cycle, docs/nonlinear.md)."""
    run = dict(duration=12.0, dt=0.02, radiation="none", q0={"sphere.heave": 0.4},
               check_stability=False)
    err, _ = _errors(run, None, (1, 2, 4), ("sphere.heave",))
    e = err[:, 0]
    assert e[0] < 1e-3, e
    assert e[1] / e[0] > 5 and e[2] / e[1] > 5, e


def test_in_a_wave_it_converges_to_the_every_stage_run():
    """A regular wave H 0.3 m T 4 s (H/λ 0.012), surge, heave and pitch free, 24 s at dt 0.05 s:
    sampled every 2 and 4 steps (ω h = 0.16, 0.31), each coordinate's difference from the
    every-stage run falls by more than 5 (third order: 8) and at k = 2 is below 1e-3 of its
    range. (At k = 1 the surge's, 1.3e-5 of its range, is near the level of what the two runs'
    other differences leave: its ratio to k = 2 was 3.9, heave's and pitch's 6.7.)"""
    run = dict(sea=hydro.Regular(height=0.3, period=4.0), duration=24.0, dt=0.05, ramp=8.0,
               radiation="state_space", check_stability=False)
    err, _ = _errors(run, None, (2, 4), ("sphere.surge", "sphere.heave", "sphere.pitch"))
    assert (err[0] < 1e-3).all(), err
    assert (err[1] / err[0] > 5).all(), err


def test_its_config_and_dt_are_checked():
    with pytest.raises(ConfigError, match=r"hydro.nonlinear_dt: -0.1 is not a positive number"):
        _sphere(nonlinear_dt=-0.1)
    with pytest.raises(ConfigError, match=r"hydro.nonlinear_dt: 0.1 is given but "
                                          r"hydro.hydrostatics is 'linear'"):
        _sphere(nonlinear_dt=0.1, hydrostatics="linear")
    model = _sphere(nonlinear_dt=0.1)
    with pytest.raises(ValueError, match=r"hydro.nonlinear_dt: 0.1 s is not a whole multiple "
                                         r"of the run's dt 0.03 s.*0.09 or 0.12 s \(3 or 4 steps\)"):
        mfm.simulate(model, duration=0.3, dt=0.03, check_stability=False)


def test_reduce_takes_the_sampled_level_where_it_holds():
    """mfm.reduce on the sphere at the nonlinear level in a moderate wave (H 0.3 m, T 4 s, H/λ
    0.012; 50 steps a period: the sampled level every step, ω h = 0.13): its reference is the
    pressure at every stage (a nonlinear_dt of the model left out), the linear "full" level is
    off by more than the 1 % asked (the heave: the hull against the database's and the
    second-order terms), and the "sampled" level, within 1e-3 (third order in ω h), is taken;
    its run samples the pressure as the reduction says."""
    from mfm.studies.fidelity import sampled_steps

    model = _sphere(nonlinear_dt=0.32)          # left out of the reference
    sea = hydro.Regular(height=0.3, period=4.0)
    r = mfm.reduce(model, sea, tolerance=0.01, coordinates=("sphere.heave", "sphere.pitch"),
                   pilot_periods=12.0, settle_periods=6.0, steps_per_period=50,
                   levels=("full", "sampled", "nonlinear"), timing=False)
    assert sampled_steps(50) == 1 and sampled_steps(200) == 4
    assert max(r.errors["full"].values()) > 0.01, r.errors
    assert r.level == "sampled", r.reason
    assert max(r.errors["sampled"].values()) < 1e-3, r.errors
    assert r.variant == {"nonlinear_dt": pytest.approx(0.08)}
    ds = r.run(model, sea, duration=1.6)
    assert ds.attrs["hull_pressure"].startswith("sampled every 1 steps")


def test_a_run_s_gradient_goes_through_the_samples():
    """jax.grad of the heave after 40 steps (the samples taken every 2 steps, lax.cond on the
    step counter) with respect to the initial heave, against a central difference (ε 1e-5:
    truncation ~ε² f''' ≈ 1e-10, round-off ~1e-16/ε ≈ 1e-11; 1e-7 asserted)."""
    import jax

    from mfm.timedomain.setup import model_loads

    model = _sphere(nonlinear_dt=0.1)
    loads = model_loads(model, hydro.Regular(height=0.3, period=4.0), dt=0.05, duration=2.0,
                        radiation="state_space", integrator="rk4")

    def heave(h0):
        out = mfm.rollout(model, jnp.array([0.0, h0, 0.0]), jnp.zeros(3), dt=0.05, n_steps=40,
                          loads=loads)
        return out[1][-1, 1]

    g = float(jax.grad(heave)(0.1))
    eps = 1e-5
    fd = float((heave(0.1 + eps) - heave(0.1 - eps)) / (2 * eps))
    assert g == pytest.approx(fd, rel=1e-7, abs=1e-9)
