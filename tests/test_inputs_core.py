"""What a new user meets in the core: bad arguments name themselves, a failed run keeps its data,
results say how they were made (issue 9, the parts in simulate / build / frequency)."""
from __future__ import annotations

import hashlib
import math

import numpy as np
import pytest
from conftest import CONFIGS

import hydro
import mfm

pytestmark = pytest.mark.filterwarnings("ignore::hydro.database.HydroDatabaseWarning")


@pytest.fixture(scope="module")
def rm3():
    return mfm.load(CONFIGS / "rm3.toml")


@pytest.fixture(scope="module")
def pendulum():
    return mfm.load(CONFIGS / "double_pendulum.toml")


SEA = hydro.Regular(height=1.0, period=8.0)


@pytest.mark.parametrize("kwargs, match", [
    ({"memory": 0.0}, r"memory: 0\.0 must be > 0"),
    ({"t0": math.nan}, r"t0: nan is not a finite number"),
    ({"dt": "0.1"}, r"dt: '0\.1' is not a finite number"),
    ({"dt": -0.1}, r"dt: -0\.1 must be > 0"),
    ({"ramp": -1.0}, r"ramp: -1\.0 must be ≥ 0"),
    ({"q0": [np.nan, 0, 0, 0]}, r"q0: not finite for \['spar\.surge'\]"),
    ({"q0": {"spar.heave": "up"}}, r"q0\['spar\.heave'\]: 'up' is not a number"),
    ({"radiation": "ss"}, r"radiation='ss'; accepted: 'auto', 'convolution', 'state_space', 'state_space_exact', 'none', 'database' or a strategy of mfm.radiation"),
    ({"radiation": "state_space", "state_space_options": {"orders": 4}},
     r"unknown option\(s\) \['orders'\]; accepted: \[.*'order'"),
    ({"save_every": 0}, r"save_every: 0 must be a positive divisor"),
])
def test_simulate_bad_arguments_name_themselves(rm3, kwargs, match):
    args = dict(duration=1.0, dt=0.1)
    args.update(kwargs)
    with pytest.raises(ValueError, match=match):
        mfm.simulate(rm3, SEA, **args)


def test_sea_must_be_a_sea_state(rm3):
    with pytest.raises(TypeError, match=r"sea: 'regular' is not a sea state; give one of hydro\.Regular"):
        mfm.simulate(rm3, "regular", duration=1.0, dt=0.1)


def test_load_flags_are_checked():
    with pytest.raises(ValueError, match=r"body_coupling: 'no'; accepted: True, False or None"):
        mfm.load(CONFIGS / "rm3.toml", body_coupling="no")
    with pytest.raises(ValueError, match=r"hydro: 'yes'; accepted"):
        mfm.load(CONFIGS / "rm3.toml", hydro="yes")


def test_rollout_refuses_negative_dt_and_steps(pendulum):
    q0 = np.zeros(pendulum.n_coordinates)
    with pytest.raises(ValueError, match=r"dt: -0\.01; give a positive, finite number"):
        mfm.rollout(pendulum, q0, q0, dt=-0.01, n_steps=10)
    with pytest.raises(ValueError, match=r"n_steps: -5; give a positive whole number"):
        mfm.rollout(pendulum, q0, q0, dt=0.01, n_steps=-5)


def test_failed_run_keeps_its_data(rm3):
    # RM3 at dt = 3 s goes non-finite (the float's heave–stroke mode is far beyond RK4's limit):
    # the error says when and why, and carries the run up to the last finite sample
    with pytest.warns(mfm.StabilityWarning):
        with pytest.raises(mfm.SimulationError) as info:
            mfm.simulate(rm3, SEA, duration=600.0, dt=3.0, radiation="none")
    err = info.value
    assert "went non-finite at t =" in str(err) and "Reduce dt below" in str(err)
    ds = err.dataset
    assert ds is not None and ds.attrs["complete"] == "false"
    assert np.isfinite(ds.q.values).all() and ds.time.size >= 2
    assert f"t = {ds.time.values[-1]:.6g} s" in str(err)


def test_coarse_dt_for_the_sea_warns_with_the_expected_error(rm3):
    # RK4 at ω dt = 2π·2/8: period error (ω dt)⁴/120 ≈ 5 % per wave period
    with pytest.warns(mfm.AccuracyWarning, match=r"about 5\.1 % per wave period.*Use dt ≤ 1\.\d+ s"):
        mfm.simulate(rm3, SEA, duration=40.0, dt=2.0, radiation="none", check_stability=False)


def test_results_carry_their_provenance(rm3):
    ds = mfm.simulate(rm3, SEA, duration=2.0, dt=0.1, ramp=1.0, radiation="state_space")
    cfg = CONFIGS / "rm3.toml"
    assert ds.attrs["config_sha256"] == hashlib.sha256(cfg.read_bytes()).hexdigest()
    assert ds.attrs["config"].endswith("rm3.toml")
    assert "Regular" in ds.attrs["sea"] and ds.attrs["ramp_s"] == 1.0
    assert ds.attrs["radiation"] == "state_space" and ds.attrs["state_space_states"] > 0
    assert ds.attrs["radiation_choice"] == "given"
    assert len(ds.attrs["database_sha256"]) == 64
    for key in ("mfm_version", "jax_version", "git_commit", "integrator", "dt", "created"):
        assert key in ds.attrs
    assert ds.q.attrs["units"].startswith("m or rad")
    assert list(ds.coordinate_unit.values) == ["m", "m", "rad", "m"]   # surge, heave, pitch, stroke
    fr = mfm.frequency_response(rm3, [0.8], heading=0.0)
    assert fr.attrs["heading"] == 0.0 and fr.attrs["heading_units"] == "rad"
    assert fr.attrs["config_sha256"] == ds.attrs["config_sha256"]
    nat = mfm.natural_frequencies(rm3)
    assert nat.eigen.attrs["units"] == "rad/s" and "config_sha256" in nat.attrs

    # every result saves to NetCDF with its attributes
    import tempfile
    from hydro.database import split_complex

    with tempfile.TemporaryDirectory() as tmp:
        for i, d in enumerate((ds, split_complex(fr), nat)):
            d.to_netcdf(f"{tmp}/r{i}.nc")


def test_batch_cases_are_labelled(rm3):
    seas = [hydro.Regular(height=1.0, period=T) for T in (7.0, 9.0)]
    ds = mfm.simulate_batch(rm3, seas, dt=0.2, n_steps=20, radiation="none")
    assert list(ds.sea_period.values) == [7.0, 9.0] and ds.sea_period.attrs["units"] == "s"
    assert "config_sha256" in ds.attrs


def test_a_run_that_cannot_fit_is_refused_before_any_work(rm3, monkeypatch):
    # duration = 1e15 s at dt = 0.1 s used to allocate until the machine gave up; now the memory
    # the run would hold before its first step (saved samples, wave tables) is estimated from the
    # model and refused at once, with the estimate and the ways out
    import time

    from mfm.runner import checks

    start = time.perf_counter()
    with pytest.raises(ValueError, match=r"duration: 1e\+16 steps would hold about .* GB before "
                                         r"the first step .*save_every=k"):
        mfm.simulate(rm3, SEA, duration=1e15, dt=0.1)
    with pytest.raises(ValueError, match=r"n_steps: 1e\+13 steps × 4 cases"):
        mfm.simulate_batch(rm3, [SEA] * 4, dt=0.1, n_steps=10**13)
    assert time.perf_counter() - start < 5.0          # before the water, the fit, any compile
    # the estimate is the dataset's size to a few per cent (here the run's own: coordinates and
    # attributes aside, 2 % on RM3), the wave tables on top
    ds = mfm.simulate(rm3, SEA, duration=20.0, dt=0.1, check_stability=False)
    n, dofs = 200, 6 * len(rm3.hydro.body_index)
    est = checks.run_bytes(rm3, rm3.loads, n, 1) - 8 * (2 * n + 1) * (dofs + 1)
    assert abs(est / ds.nbytes - 1) < 0.05
    # and the limit is the machine's memory: a machine of 100 kB refuses that run (~0.25 MB) too
    monkeypatch.setattr(checks, "machine_memory", lambda: 100_000)
    with pytest.raises(ValueError, match=r"more than the 0.0001 GB this process may use "
                                         r"\(this machine's memory\)"):
        mfm.simulate(rm3, SEA, duration=20.0, dt=0.1)


def test_the_memory_check_meets_a_container_s_limit(tmp_path, monkeypatch):
    """Issue 54 item 17: the limit is what the process may use, not the machine's memory: a
    control group's memory.max less its memory.current (cgroup v2; v1's files likewise), read
    under a root the test lays out. A 1.5 GB limit with 0.3 GB in use leaves 1.2 GB."""
    from mfm.runner import checks

    cg = tmp_path / "sys/fs/cgroup"
    cg.mkdir(parents=True)
    (cg / "memory.max").write_text("1500000000\n")
    (cg / "memory.current").write_text("300000000\n")
    have, what = checks.usable_memory(str(tmp_path))
    assert have == 1_200_000_000 and "control group's limit (1.5 GB" in what, (have, what)
    (cg / "memory.max").write_text("max\n")             # no limit: the others decide
    have, what = checks.usable_memory(str(tmp_path))
    assert "control group" not in what and have > 0
    v1 = tmp_path / "v1"
    (v1 / "sys/fs/cgroup/memory").mkdir(parents=True)
    (v1 / "sys/fs/cgroup/memory/memory.limit_in_bytes").write_text("2000000000")
    (v1 / "sys/fs/cgroup/memory/memory.usage_in_bytes").write_text("500000000")
    assert checks.usable_memory(str(v1)) [0] == 1_500_000_000
    # and the run's refusal names it: a run needing more than the group leaves is refused
    monkeypatch.setattr(checks, "usable_memory",
                        lambda root="/": (100_000, "its control group's limit (test)"))
    rm3 = mfm.load(CONFIGS / "rm3.toml")
    with pytest.raises(ValueError, match=r"may use \(its control group's limit \(test\)\)"):
        mfm.simulate(rm3, SEA, duration=20.0, dt=0.1)


@pytest.mark.parametrize("front", ["simulate", "simulate_batch", "frequency_response",
                                   "natural_frequencies", "equilibrium", "spectral_response",
                                   "sweep"])
def test_a_path_where_a_model_is_meant_is_refused_with_the_fix(front):
    """Every front door that takes a model refuses a config path (a TypeError naming the call that
    makes the model), and anything else that is not a Model, before any work."""
    path = str(CONFIGS / "rm3.toml")
    calls = {
        "simulate": lambda m: mfm.simulate(m, SEA, duration=10.0, dt=0.1),
        "simulate_batch": lambda m: mfm.simulate_batch(m, [SEA], dt=0.1, n_steps=10),
        "frequency_response": lambda m: mfm.frequency_response(m, [0.8]),
        "natural_frequencies": lambda m: mfm.natural_frequencies(m),
        "equilibrium": lambda m: mfm.equilibrium(m),
        "spectral_response": lambda m: mfm.spectral_response(m, SEA),
        "sweep": lambda m: mfm.sweep(m, [SEA], dt=0.1, n_steps=10),
    }
    with pytest.raises(TypeError, match=r"is a path, not a model; load it first: model = "
                                        r"mfm.load\("):
        calls[front](path)
    with pytest.raises(TypeError, match="give an mfm.Model"):
        calls[front]({"model": path})


def test_load_refuses_what_is_not_a_path(rm3):
    with pytest.raises(TypeError, match=r"path: 123 \(int\); give the path of a config TOML"):
        mfm.load(123)
    with pytest.raises(TypeError, match="already loaded"):
        mfm.load(rm3)


def test_waves_past_breaking_are_refused():
    """Miche's limit H_b = 0.142 L tanh(kh), against its two ends: Stokes' H/L = 1/7 (0.142) in
    deep water, 0.142 · 2π h = 0.89 h in shallow water (kh → 0, tanh kh ≈ kh); a regular wave or
    a sea (its Hs at Tp) past it is refused by every front door, one just below runs."""
    from hydro.waves import breaking_height

    g = 9.81
    assert breaking_height(8.0, g=g) == pytest.approx(0.142 * g * 8.0**2 / (2 * np.pi), rel=1e-12)
    # T = 200 s in 10 m: kh = 0.05, tanh kh / kh = 1 − (kh)²/3: 0.1 % from the shallow limit
    assert breaking_height(200.0, 10.0, g=g) == pytest.approx(0.142 * 2 * np.pi * 10.0, rel=2e-3)
    Hb = breaking_height(8.0, g=9.81)
    with pytest.raises(ValueError, match=r"height 15 m at a period of 8 s is past breaking.*"
                                         r"below 14\.2 m"):
        hydro.Regular(height=15.0, period=8.0).components(g=9.81)
    hydro.Regular(height=0.99 * Hb, period=8.0).components(g=9.81)
    with pytest.raises(ValueError, match="hs 15 m at a period of 4 s is past breaking"):
        hydro.Jonswap(hs=15.0, tp=4.0).components()
    rm3 = mfm.load(CONFIGS / "rm3.toml")
    with pytest.raises(ValueError, match="past breaking"):
        mfm.simulate(rm3, hydro.Regular(height=20.0, period=3.0), duration=1.0, dt=0.1)
    with pytest.raises(ValueError, match="past breaking"):
        mfm.simulate_batch(rm3, [SEA, hydro.Regular(height=20.0, period=3.0)], dt=0.1,
                           n_steps=10)


def _movable_config(name, database):
    """A shipped config's text with its relative database path made absolute, so that an edited
    copy loads from another folder."""
    db = str((CONFIGS / database).resolve())
    return (CONFIGS / name).read_text().replace(f'"{database}"', repr(db).replace("'", '"'))


def test_a_body_without_its_parent_beside_a_floating_root_is_refused(tmp_path):
    """RM3 with the float's ``parent`` left out: its slider would hang from the earth, not from the
    spar (two roots where one was meant); refused naming the body and both fixes. Said on
    purpose (parent = "earth"), it loads, and the float no longer follows the spar."""
    text = _movable_config("rm3.toml", "../hydro/data/rm3/rm3.out")
    orphan = tmp_path / "orphan.toml"
    orphan.write_text(text.replace('parent = "spar"\n', "", 1))
    with pytest.raises(mfm.ConfigError, match=r"'float'.*prismatic joint hangs from the inertial "
                                              r"frame.*parent = \"spar\".*parent = \"earth\""):
        mfm.load(orphan)
    earthed = tmp_path / "earthed.toml"
    earthed.write_text(text.replace('parent = "spar"\n', 'parent = "earth"\n', 1))
    model = mfm.load(earthed, hydro=False)
    assert model.coordinates == ("spar.surge", "spar.heave", "spar.pitch", "float.stroke")
    q = np.array([0.0, 0.3, 0.0, 0.0])            # the spar heaves 0.3 m; the float stays put
    com, _ = mfm.body_poses(model, q)
    assert abs(float(com[model.body_index("float"), 2]) - (-0.72)) < 1e-12
    assert abs(float(com[model.body_index("spar"), 2]) - (-21.29 + 0.3)) < 1e-12
    two = tmp_path / "two.toml"
    two.write_text(text.replace('body = "float"', 'body = "spar"'))
    with pytest.raises(mfm.ConfigError, match="bodies 'spar' and 'float' both name the database "
                                              "body 'spar'"):
        mfm.load(two)


def test_a_body_renamed_against_its_database_is_refused(tmp_path):
    """M4 134 matches its bodies to the database by name: float8 renamed in the config would run
    dry (no buoyancy, no waves) beside a database body no one uses; refused naming both, with
    the fix."""
    text = _movable_config("m4_134.toml", "../hydro/data/m4_134.nc")
    renamed = tmp_path / "renamed.toml"
    renamed.write_text(text.replace('name = "float8"', 'name = "float8b"', 1))
    with pytest.raises(mfm.ConfigError, match=r"database bodies \['float8'\] are used by no config "
                                              r"body.*\['float8b'\].*renamed.*\[bodies.hydro\]"):
        mfm.load(renamed)


# ---- a frequency grid that makes no sense for the question (issue 35 item 6) -------------------


def test_a_sea_outside_the_database_is_refused_naming_the_sea(rm3):
    """The frequency domain needs a RAO at each component: a sea with components beyond the
    database's grid (RM3: 0.02–5.2 rad/s) is refused by spectral_response and spectral_sweep,
    naming the sea (not an ``omega`` the caller never passed), the share of its energy outside and
    the fix; the same sea cut to the grid runs."""
    from mfm.runner.spectral import spectral_sweep

    wide = hydro.Jonswap(hs=2.0, tp=8.0, omega_range=(0.3, 8.0))
    with pytest.raises(ValueError, match=r"^sea: JONSWAP Hs 2 m, Tp 8 s.* of its 200 wave "
                                         r"components .* outside the database's frequency grid "
                                         r"\[0\.02, 5\.2\] rad/s.*omega_range"):
        mfm.spectral_response(rm3, wide)
    with pytest.raises(ValueError, match=r"^seas\[1\]: JONSWAP Hs 2 m, Tp 8 s"):
        spectral_sweep(rm3, [SEA, wide])
    ok = spectral_sweep(rm3, [SEA, hydro.Jonswap(hs=2.0, tp=8.0, omega_range=(0.3, 5.0))])
    assert np.all(np.isfinite(ok["q_rms"].values))


def test_a_sea_band_that_drops_most_of_the_spectrum_warns():
    """omega_range cutting most of a spectrum's energy leaves a sea far below the stated Hs:
    a SeaStateWarning with the fraction kept. The fraction against scipy's adaptive quadrature
    (an independent route); the default band and the cut bands the shipped studies use do not
    warn (they keep >= 0.94)."""
    import warnings

    from scipy import integrate

    cut = hydro.Jonswap(hs=2.0, tp=8.0, omega_range=(2.0, 3.0))
    wp = 2 * np.pi / 8.0
    ref = (integrate.quad(cut.spectrum, 2.0, 3.0, epsrel=1e-12)[0]
           / sum(integrate.quad(cut.spectrum, a, b, epsrel=1e-12, limit=400)[0]
                 for a, b in ((1e-3, wp), (wp, np.inf))))
    # the trapezoid rule on 4001 geometric points against quad: measured 5e-7 relative; 1e-5
    assert cut.band_energy_fraction() == pytest.approx(ref, rel=1e-5)
    with pytest.warns(hydro.SeaStateWarning, match=r"omega_range=\(2, 3\) rad/s keeps a fraction "
                                                   r"0\.0154 .*Hs = 0\.124 × the stated"):
        c = cut.components()
    # the discretised sea holds that fraction (200 bins over a smooth band: 1e-3)
    assert np.sum(c.amplitude**2) / 2 == pytest.approx(ref * 2.0**2 / 16, rel=1e-3)
    # a table cut to half its triangle keeps 0.5 exactly
    tri = hydro.UserSpectrum(omega=[0.5, 1.0, 1.5], S=[0.0, 1.0, 0.0], omega_range=(1.0, 1.5))
    assert tri.band_energy_fraction() == pytest.approx(0.5, rel=1e-12)
    with pytest.warns(hydro.SeaStateWarning, match="keeps a fraction 0.5 "):
        tri.components()
    with warnings.catch_warnings():
        warnings.simplefilter("error", hydro.SeaStateWarning)
        for sea in (hydro.Jonswap(hs=2.0, tp=8.0), hydro.PiersonMoskowitz(hs=2.0, tp=8.0),
                    *(hydro.Jonswap(hs=0.04, tp=tp, omega_range=(1.0, 25.0)) for tp in (0.8, 1.8)),
                    *(hydro.Jonswap(hs=2.0, tp=tp, omega_range=(0.2, 2.0)) for tp in (8.0, 16.0)),
                    hydro.Jonswap(hs=2.0, tp=7.0, omega_range=(0.35, 2.0))):
            sea.components()


@pytest.mark.parametrize("bem, match", [
    ({"omega": [0.5, 1.0, 1.0, 2.0]}, r"hydro\.bem\.omega\[2\]: 1 rad/s repeats omega\[1\] = 1"),
    ({"omega": [0.5, 2.0, 1.0]}, r"hydro\.bem\.omega\[2\]: 1 rad/s is below omega\[1\] = 2.*"
                                 r"increasing order"),
    ({"omega": [0.5, float("nan")]}, r"hydro\.bem\.omega\[1\]: nan is not a finite number"),
    ({"omega": [0.0, 1.0]}, r"hydro\.bem\.omega\[0\]: 0\.0 must be > 0"),
    ({"omega_min": 0.5, "omega_max": 2.0, "n_omega": 1},
     r"hydro\.bem\.n_omega: 1 with omega_min = 0\.5 and omega_max = 2 rad/s solves omega_min only"),
    ({"omega_min": 2.0, "omega_max": 0.5, "n_omega": 10}, r"hydro\.bem\.omega_max: 0\.5 must be > omega_min"),
    ({"omega_min": 1.0, "omega_max": 1.0, "n_omega": 10}, r"hydro\.bem\.omega_max: 1\.0 must be > omega_min"),
])
def test_a_bem_frequency_list_that_is_a_typo_is_refused(bem, match):
    """[hydro.bem] for `mfm hydro`: hydro.bem.solve sorts and de-duplicates its ω, so a repeat or a
    step back in a hand-typed list, or n_omega = 1 under a band, would solve other frequencies than
    the config shows; each is refused naming the key, the value and the fix."""
    from mfm.io.bemgen import bem_settings

    with pytest.raises(mfm.ConfigError, match=match):
        bem_settings({"dx": 0.1, **bem})


def test_a_one_frequency_bem_grid_stated_as_such_is_accepted():
    from mfm.io.bemgen import bem_settings

    one = bem_settings({"dx": 0.1, "omega_min": 0.8, "omega_max": 0.8, "n_omega": 1})
    assert one["kwargs"]["omega"].tolist() == [0.8]
    assert bem_settings({"dx": 0.1, "omega": [0.8]})["kwargs"]["omega"].tolist() == [0.8]
