"""The radiation fit judged on the model's own modes (mfm.frequency.fitcheck): the pieces against
independent routes, and radiation="auto" taking the convolution where a fit fails."""
import math
from pathlib import Path

import numpy as np
import pytest

import hydro
import mfm
from mfm.frequency import fitcheck
from mfm.frequency.modes import _eig_pair
from mfm.frequency.rest import linear_system
from mfm.frequency.response import _mass_and_damping_at

CONFIGS = Path(__file__).resolve().parents[1] / "configs"


@pytest.fixture(scope="module")
def rm3():
    model = mfm.load(CONFIGS / "rm3.toml")
    return model, linear_system(model)


@pytest.mark.parametrize("s, ds", [(-0.02 + 0.5j, 0.001 + 0.002j), (-0.3 + 1.0j, -0.01 + 0.0j),
                                   (-1e-4 + 0.4j, 2e-5 - 1e-4j)])
@pytest.mark.parametrize("horizon", [50.0, 1e4])
def test_mode_error_is_the_largest_change_of_the_free_response(s, ds, horizon):
    """e_mode against max over 0 ≤ t ≤ D of |e^{(s+δs)t} − e^{st}| sampled densely: the first-order
    formula within 5 % where it is below 0.2 (its second-order term, |δs t|²/2, is then small);
    where it is larger, the exact change is far past the tolerance too."""
    t = np.linspace(0.0, horizon, 400_001)
    exact = float(np.max(np.abs(np.exp((s + ds) * t) - np.exp(s * t))))
    est = fitcheck.mode_error(s, s + ds, horizon)
    if est < 0.2:                          # first order holds while the change is small
        assert est == pytest.approx(exact, rel=0.05)
    else:                                  # else both far past any tolerance (0.05)
        assert exact > 0.15


def test_damped_modes_are_roots_of_the_frequency_dependent_system(rm3):
    """Each root s that damped_modes returns (coefficients interpolated on its grid) makes
    det[s² M(ω) + s C(ω) + K], ω = Im s, with the database's coefficients evaluated directly at
    that ω, vanish: its smallest singular value is < 1e-4 of the largest."""
    model, sys = rm3
    roots = fitcheck.damped_modes(model, sys, {"radiation": "database"})
    assert roots.size == 3 and (roots.real < 0).all() and (roots.imag > 0).all()
    for s in roots:
        Mw, Cr = _mass_and_damping_at(model, sys, np.array([s.imag]), {"radiation": "database"})
        Z = s**2 * Mw[0] + s * (sys.C + Cr[0]) + sys.K
        sv = np.linalg.svd(Z, compute_uv=False)
        assert sv[-1] < 1e-4 * sv[0], (s, sv)


def test_a_good_fit_passes_and_a_poor_one_fails(rm3):
    """RM3's default fit (1 % from its database over the band) keeps every mode within the
    tolerance; a two-pole fit (order 2) puts the spar's lightly damped 15.6 s mode's damping
    60× too high, which over 100 s changes its free response by ~30 %."""
    model, sys = rm3
    good = fitcheck.judge_fit(model, sys, horizon=100.0)
    assert good.ok and good.mode_error < fitcheck.MODE_TOLERANCE / 2, good.summary
    poor = fitcheck.judge_fit(model, sys, state_space_options={"order": 2}, horizon=100.0)
    assert not poor.ok and poor.mode_error > 3 * fitcheck.MODE_TOLERANCE, poor.summary
    worst = poor.modes[0]
    assert worst.period_db == pytest.approx(15.59, abs=0.01)
    assert worst.zeta_fit > 10 * worst.zeta_db
    assert "does not match" in poor.summary and "15.59" in poor.summary


def test_auto_takes_the_convolution_where_the_fit_fails(rm3, monkeypatch):
    """radiation="auto" with a fit that fails its judgement runs the convolution (the same bits as
    radiation="convolution") and says why in radiation_choice and the fit_* attributes; a fit
    that passes keeps the state space. The convolution's work limit is lowered so that this short
    run takes the state space first."""
    from mfm.runner import choices

    model, _ = rm3
    monkeypatch.setattr(choices, "AUTO_CONVOLUTION_LIMIT", 0.0)
    run = dict(duration=30.0, dt=0.1, q0={"spar.heave": 0.3}, check_stability=True)
    poor = mfm.simulate(model, state_space_options={"order": 2}, **run)
    assert poor.attrs["radiation_choice"].endswith("the convolution instead"), \
        poor.attrs["radiation_choice"]
    assert "radiation" in poor.attrs and poor.attrs["radiation"] == "convolution"
    assert poor.attrs["fit_judged_ok"] == "false" and poor.attrs["fit_mode_error"] > 0.05
    conv = mfm.simulate(model, radiation="convolution", **run)
    np.testing.assert_array_equal(poor.q.values, conv.q.values)
    # the default fit passes: choose_radiation makes the same judgement without running
    name, why = choices.choose_radiation(model, dt=0.1, n_steps=300)
    assert name == "state_space" and "the fit matches the database" in why, why


def test_in_a_sea_only_the_modes_near_its_band_are_judged(rm3):
    """A regular wave of 2.5 s (2.5 rad/s) is more than an octave above RM3's 15.6 s and 39 s
    modes: they are listed as not judged, and the response to the wave is."""
    model, sys = rm3
    spec = model.hydro
    sea = hydro.Regular(height=0.5, period=4.0).components(spec.water_depth, spec.g)
    v = fitcheck.judge_fit(model, sys, state_space_options={"order": 2}, components=sea,
                           horizon=100.0)
    periods = sorted(2 * math.pi / s.imag for s, why in v.unjudged if "sea" in why)
    assert periods and periods[0] > 15.0, v.summary
    assert v.sea_error is not None and "sea response" in v.summary


def test_eig_pair_with_an_indefinite_mass_does_not_raise():
    """natural_frequencies' eigensolve where a strategy's M(ω) is indefinite at the frequency the
    iteration starts from (LinAlgError "not positive definite" before): the general
    eigenproblem's real roots, the same as eigh's where M is positive definite."""
    K = np.diag([4.0, 9.0])
    M_pd = np.array([[1.0, 0.2], [0.2, 1.0]])
    lam, _ = _eig_pair(K, M_pd)
    import scipy.linalg
    np.testing.assert_allclose(lam, scipy.linalg.eigh(K, M_pd, eigvals_only=True))
    M_bad = np.array([[1.0, 0.0], [0.0, -0.5]])
    lam, vec = _eig_pair(K, M_bad)
    np.testing.assert_allclose(sorted(lam), [-18.0, 4.0])
    assert vec.shape == (2, 2)


def test_natural_frequencies_with_every_radiation_strategy(rm3):
    """natural_frequencies works with each strategy; the database, the fit and the convolution
    give RM3's periods within 0.1 % (the fit and the convolution are 1 % from the database's
    impedance in the band), "none" (A∞ only) moves the float's 5 s mode by 5 %."""
    model, _ = rm3
    T = {r: mfm.natural_frequencies(model, radiation=r).period.values
         for r in ("database", "state_space", "convolution", "state_space_exact", "none")}
    for r in ("state_space", "convolution", "state_space_exact"):
        np.testing.assert_allclose(T[r], T["database"], rtol=1e-3, err_msg=r)
    assert abs(T["none"][-1] / T["database"][-1] - 1) > 0.03


# ----------------------------------------------------------------- a device where the fit fails
# configs/two_flap.toml (hydro/data/README.md: made by `mfm hydro`): a floating hub with two
# buoyant flaps on pitch hinges 28 m apart and light PTOs, two closely spaced coupled flap modes
# (13.90 s in phase, 14.44 s anti-phase). Its default state-space fit (band error 0.4 %) gives
# them 54-66x the database's radiation damping: 3-5x their total damping.

@pytest.fixture(scope="module")
def two_flap():
    return mfm.load(CONFIGS / "two_flap.toml")


def test_two_flap_decay_with_the_defaults_is_the_convolution(two_flap):
    """A 6,000 s decay of the fore flap from 0.1 rad at dt 0.05 (long enough that auto takes a
    state space: 2.2e10 convolution multiply-adds): the defaults give the convolution's run to
    the bit (its judgement refuses the fit: e_mode > 1), where before they ran the fit, whose
    hinge angles differ from the convolution's by 43-46 % of their largest value. The state space
    run itself is shown off here by more than 20 %, so the comparison can tell them apart."""
    run = dict(duration=6000.0, dt=0.05, q0={"fore.angle": 0.1}, save_every=20)
    default = mfm.simulate(two_flap, **run)
    assert default.attrs["radiation_choice"].endswith("the convolution instead"), \
        default.attrs["radiation_choice"]
    conv = mfm.simulate(two_flap, radiation="convolution", **run)
    angles = ["fore.angle", "aft.angle"]
    np.testing.assert_array_equal(default.q.sel(coordinate=angles).values,
                                  conv.q.sel(coordinate=angles).values)
    fit = mfm.simulate(two_flap, radiation="state_space", **run)
    c, f = (d.q.sel(coordinate=angles).values for d in (conv, fit))
    assert np.abs(f - c).max() > 0.2 * np.abs(c).max()


def test_two_flap_modes_and_raos_judge_the_fit_not_the_convolution(two_flap):
    """The judgement on the flap modes: the fit fails (the in-phase and anti-phase modes' total
    damping 3-5x the database's), the convolution passes (its A, B are the Ogilvie transforms of
    the same K(t): within 15 % of the database's damping, 0.1 % of its periods). The hinge RAO
    peaks: the fit's a fifth of the database's, the convolution's within 2 % (0.5 % measured)."""
    sys = linear_system(two_flap)
    fit = fitcheck.judge_fit(two_flap, sys)
    assert not fit.ok and fit.mode_error > 10 * fitcheck.MODE_TOLERANCE, fit.summary
    flaps = [m for m in fit.modes if 13.5 < m.period_db < 15.0]
    assert len(flaps) == 2 and all(m.zeta_fit > 2.5 * m.zeta_db for m in flaps), fit.summary
    conv = fitcheck.judge_fit(two_flap, sys, radiation="convolution")
    flaps_c = [m for m in conv.modes if 13.5 < m.period_db < 15.0]
    for m in flaps_c:
        assert m.period_fit == pytest.approx(m.period_db, rel=1e-3)
        assert m.zeta_fit == pytest.approx(m.zeta_db, rel=0.15)
    omega = np.linspace(0.40, 0.48, 801)
    k = two_flap.coordinate_index("fore.angle")
    peak = {r: np.abs(mfm.frequency_response(two_flap, omega, radiation=r,
                                             joint_reactions=False).rao.values[:, k]).max()
            for r in ("database", "state_space", "convolution")}
    assert peak["state_space"] < 0.5 * peak["database"], peak
    assert peak["convolution"] == pytest.approx(peak["database"], rel=0.02), peak
