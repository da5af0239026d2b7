"""The nonlinear level of the water ([hydro] hydrostatics = "nonlinear"): the pressure on the
instantaneous wetted hull in place of the constant buoyancy, the water-plane stiffness and the
Froude–Krylov part of the excitation. Linearised at rest it is the database's stiffness; in small
waves the linear run; with no damping a large heave decay keeps its amplitude; its config is
checked (a missing hull, a hull that is not the database body's)."""
from __future__ import annotations

import copy
import math
import tomllib

import numpy as np
import pytest
from conftest import CONFIGS

import hydro
import mfm
from mfm.errors import ConfigError
from mfm.studies.wec import harmonic_amplitude

pytestmark = pytest.mark.filterwarnings("ignore::hydro.database.HydroDatabaseWarning")

SPHERE = tomllib.loads((CONFIGS / "sphere.toml").read_text())


def _sphere(hull=None, **hydro_keys):
    cfg = copy.deepcopy(SPHERE)
    cfg["hydro"].update({"hydrostatics": "nonlinear", **hydro_keys})
    if hull is not False:
        cfg["bodies"][0]["hull"] = hull or {"shape": "sphere", "radius": 1.0}
    return mfm.load(cfg, base=CONFIGS)


@pytest.fixture(scope="module")
def models():
    return mfm.load(CONFIGS / "sphere.toml"), _sphere()


def test_linearised_at_rest_it_is_the_database_s_stiffness(models):
    """The stiffness of the nonlinear level at rest (jax's derivative of the pressure on the cut
    hull, through mfm.frequency.linearise) against the linear level's (the database's C_wp with
    the buoyancy's and the weight's terms) on heave and pitch: within 1.5 %, the two hulls' own
    difference (this sphere of 2,600 facets against the BEM's panels: volumes 0.6 % and 0.1 %
    under the sphere's; the water-plane area goes as the square of the radius)."""
    lin, nl = models
    K_lin = mfm.frequency.linearise(lin)[2]
    K_nl = mfm.frequency.linearise(nl)[2]
    for k in (1, 2):            # heave, pitch (surge has none)
        assert K_nl[k, k] == pytest.approx(K_lin[k, k], rel=1.5e-2), (k, K_nl[k, k], K_lin[k, k])
    assert np.abs(K_nl[1, 2]) < 1e-3 * K_nl[1, 1]


def test_in_a_small_wave_it_is_the_linear_run(models):
    """A 5 cm, 4 s regular wave (H/λ = 0.002): the nonlinear run's heave and pitch amplitudes at
    the wave's frequency are the linear run's within 2 %: the hulls' stiffness difference (above)
    moves the response by about as much, and the second-order terms are O(H/λ)."""
    lin, nl = models
    sea = hydro.Regular(height=0.05, period=4.0)
    run = dict(duration=48.0, dt=0.05, ramp=8.0, radiation="state_space", check_stability=False)
    a = mfm.simulate(lin, sea, **run)
    b = mfm.simulate(nl, sea, **run)
    assert b.attrs["hydrostatics"] == "nonlinear" and a.attrs["hydrostatics"] == "linear"
    w = 2 * np.pi / 4.0
    late = a.time.values >= 24.0
    for c in ("sphere.heave", "sphere.pitch"):
        ya = abs(harmonic_amplitude(a.time.values[late], a.q.sel(coordinate=c).values[late], w))
        yb = abs(harmonic_amplitude(b.time.values[late], b.q.sel(coordinate=c).values[late], w))
        assert yb == pytest.approx(ya, rel=2e-2), c


def test_a_large_undamped_heave_decay_keeps_its_amplitude(models):
    """Released 0.4 m above rest (40 % of the radius: the water-plane area changes by 16 % over
    the swing), no radiation memory, no drag: the nonlinear restoring is conservative, so the
    heave's last trough is its first within 1e-4 of the swing (RK4 at ω dt ≈ 0.1 loses
    ~(ω dt)⁶/144 per radian). Its period differs from the linear one (the cap's stiffness falls
    as it rises)."""
    _, nl = models
    run = dict(duration=30.0, dt=0.02, radiation="none", q0={"sphere.heave": 0.4},
               check_stability=False)
    out = mfm.simulate(nl, **run)
    z = out.q.sel(coordinate="sphere.heave").values
    t = out.time.values
    troughs, peaks = _extrema(t, -z), _extrema(t, z)
    assert len(troughs) >= 5
    # the extrema between the samples (a parabola through three: O(dt³), where the samples
    # themselves miss the extremum by ~ω² A dt²/8 ≈ 2e-4 m)
    assert abs(troughs[-1][1] - troughs[0][1]) < 1e-4 * 0.8
    assert abs(peaks[-1][1] - 0.4) < 1e-4 * 0.8
    lin = mfm.simulate(models[0], **run)
    tl = _extrema(t, -lin.q.sel(coordinate="sphere.heave").values)
    period_nl = np.diff([x for x, _ in troughs]).mean()
    assert abs(period_nl / np.diff([x for x, _ in tl]).mean() - 1) > 5e-3


def _extrema(t, y):
    """The maxima of y(t) between its samples: (time, value) of the parabola through each
    sampled maximum and its neighbours."""
    out = []
    for i in range(1, len(y) - 1):
        if y[i] > y[i - 1] and y[i] >= y[i + 1]:
            c = y[i + 1] - 2 * y[i] + y[i - 1]
            d = (y[i + 1] - y[i - 1]) / 2
            out.append((t[i] - d / c * (t[1] - t[0]), y[i] - d * d / (2 * c)))
    return out


def test_a_hull_from_the_body_s_geometry():
    """M4 134's eight floats, each hull its [bodies.geometry] (flat and hemispherical bases)
    under a 0.1 m freeboard (shape = "geometry"): every coordinate's stiffness at rest is the
    database's within 1 % (measured 0.2–0.4 %: the hulls are revolved from the meridian the BEM
    mesh was made from, at a finer panel size)."""
    cfg = tomllib.loads((CONFIGS / "m4_134.toml").read_text())
    cfg["hydro"]["hydrostatics"] = "nonlinear"
    for b in cfg["bodies"]:
        b["hull"] = {"shape": "geometry", "top": 0.1}
    nl = mfm.load(cfg, base=CONFIGS)
    lin = mfm.load(CONFIGS / "m4_134.toml")
    K_nl, K_lin = (np.diag(mfm.frequency.linearise(m)[2]) for m in (nl, lin))
    restoring = K_lin > 1e-9 * K_lin.max()
    np.testing.assert_allclose(K_nl[restoring], K_lin[restoring], rtol=1e-2)
    del cfg["bodies"][0]["geometry"]
    with pytest.raises(ConfigError, match=r"shape 'geometry' takes the body's \[bodies.geometry\]"):
        mfm.load(cfg, base=CONFIGS)


def test_its_config_is_checked():
    """A nonlinear level without a hull names the body and the table to add; a hull that is not
    the database body's (radius 1.3 m for the 1 m sphere) gives both volumes; a bad level and a
    bad hull key are refused. (simulate_batch takes the level: tests/test_batch_nonlinear.py.)"""
    with pytest.raises(ConfigError, match=r"bodies \('sphere'\).hull: missing; .*\[bodies.hull\]"):
        _sphere(hull=False)
    with pytest.raises(ConfigError, match=r"displaces 4\.\d+ m³ .* the database body 'sphere' 2\.09"):
        _sphere({"shape": "sphere", "radius": 1.3})
    with pytest.raises(ConfigError, match=r"hydro.hydrostatics: 'quadratic'; accepted"):
        _sphere(hydrostatics="quadratic")
    with pytest.raises(ConfigError, match=r"hull: unknown key\(s\) \['radious'\]"):
        _sphere({"shape": "sphere", "radious": 1.0})


def test_drag_on_the_relative_flow():
    """[hydro] drag_flow = "relative": a sphere at rest in a regular wave feels the drag of the
    flow past it, +½ ρ C_D A |u| u per axis with u = a ω e^{k z_s} (cos θ, 0, sin θ) at its
    reference point, the decay at the Wheeler-stretched z_r − η and none where the point is out of
    the water (deep water, heading 0: Morison's drag term at a point), to round-off, at times
    under a crest and under a trough; in
    still water the relative drag is the body drag to the bit."""
    import jax.numpy as jnp

    from mfm.loads.water import build_water
    from mfm.mechanics.kinematics import kinematics

    cfg = copy.deepcopy(SPHERE)
    cfg["hydro"]["drag_flow"] = "relative"
    cfg["bodies"][0]["hydro"] = {"drag_coefficient": [1.0, 1.0, 0.8], "drag_area": [3.1, 3.1, 3.1]}
    m = mfm.load(cfg, base=CONFIGS)
    sea = hydro.Regular(height=0.6, period=5.0, phase=0.4)
    water = build_water(m, m.hydro, sea, dt=0.05, duration=10.0)
    q = jnp.zeros(m.n_coordinates)
    kin = kinematics(m, q, q)
    c = sea.components(water_depth=m.hydro.water_depth, g=m.hydro.g)
    a, w, k, ph = (float(x[0]) for x in (c.amplitude, c.omega, c.wavenumber, c.phase))
    r = np.asarray(m.hydro.ref0[0])
    D = np.asarray(m.hydro.drag[0])
    for t in (0.7, 2.9, 4.1, 1.9):
        comps, *_ = water._forces(jnp.asarray(t), kin, jnp.zeros(water.n_states),
                                  water.init_memory(m, t, q, q, 0.05), np.arange(6))
        th = k * r[0] - w * t + ph
        # Wheeler-stretched: the decay at z − η (the reference point is on the mean surface),
        # and no flow where the point is above the surface (under a trough)
        eta = a * math.cos(th)
        decay = math.exp(k * (r[2] - eta)) if r[2] <= eta else 0.0
        u = a * w * decay * np.array([math.cos(th), 0.0, math.sin(th)])
        np.testing.assert_allclose(np.asarray(comps["drag"])[:3], D * np.abs(u) * u,
                                   rtol=1e-10, atol=1e-12 * float(np.abs(D * u * u).max()))
    body = copy.deepcopy(cfg)
    body["hydro"]["drag_flow"] = "body"
    run = dict(duration=5.0, dt=0.05, q0={"sphere.heave": 0.2}, radiation="none",
               check_stability=False)
    a1 = mfm.simulate(m, **run)
    a2 = mfm.simulate(mfm.load(body, base=CONFIGS), **run)
    np.testing.assert_array_equal(a1.q.values, a2.q.values)
    assert (a1.attrs["drag_flow"], a2.attrs["drag_flow"]) == ("relative", "body")


def test_reduce_says_when_linear_potential_flow_is_enough():
    """mfm.reduce on the sphere given with its nonlinear level: the reference is "nonlinear" and
    the linear levels run on its linear water. In a steep wave (H 1 m, T 4 s, H/λ = 0.04; the
    sphere is unmoored in surge, and the nonlinear level's mean wave force carries it downstream,
    docs/nonlinear.md) no linear level is within 2 %: it keeps "nonlinear" and says
    why; in a small one (H 0.05 m) the linear "full" is within 2 % (the hulls' own 1 %
    difference), and its run is the linear water's."""
    _, nl = _models_cached()
    kw = dict(tolerance=0.02, coordinates=("sphere.heave", "sphere.pitch"), pilot_periods=12.0,
              settle_periods=6.0, steps_per_period=50, levels=("full", "nonlinear"), timing=False)
    steep = mfm.reduce(nl, hydro.Regular(height=1.0, period=4.0), **kw)
    assert steep.level == "nonlinear", steep.reason
    assert "linear potential flow is not enough" in steep.reason
    assert max(steep.errors["full"].values()) > 0.03
    small = mfm.reduce(nl, hydro.Regular(height=0.05, period=4.0), **kw)
    assert small.level == "full", small.reason
    assert small.variant == {"linear_water": True}
    ds = small.run(nl, hydro.Regular(height=0.05, period=4.0), duration=4.0)
    assert ds.attrs["hydrostatics"] == "linear"
    with pytest.raises(ValueError, match="levels"):
        mfm.reduce(nl, hydro.Regular(height=0.05, period=4.0), levels=("huge",))


_CACHE = {}


def _models_cached():
    if not _CACHE:
        _CACHE["m"] = (mfm.load(CONFIGS / "sphere.toml"), _sphere())
    return _CACHE["m"]
