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
    ({"radiation": "ss"}, r"radiation='ss'; accepted: 'convolution', 'state_space', 'state_space_exact', 'none'"),
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

    from mfm.timedomain import checks

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
    with pytest.raises(ValueError, match="more than this machine's 0.0001 GB"):
        mfm.simulate(rm3, SEA, duration=20.0, dt=0.1)
