"""Sea states, spectra, dispersion, spreading and elevation (hydro.waves) against independent checks."""
import dataclasses
import math

import numpy as np
import pytest
from scipy import integrate, optimize, signal, stats

from hydro.waves import (
    Jonswap,
    MeasuredElevation,
    PiersonMoskowitz,
    Regular,
    Spreading,
    UserSpectrum,
    WaveComponents,
    elevation,
    jonswap_normalisation,
    ramp,
    wavenumber,
)

G = 9.81


def _m0_fine(spectrum, wp):
    """∫₀^∞ S dω by the trapezoid rule on a fine grid to 60 ωp plus the analytic ω⁻⁵ tail beyond."""
    w = np.linspace(1e-3 * wp, 60.0 * wp, 400_001)
    S = spectrum(w)
    tail = S[-1] * w[-1] / 4.0  # ∫_W^∞ S(W)(W/ω)⁵ dω = S(W) W / 4
    return np.trapezoid(S, w) + tail


# ---------------------------------------------------------------------------- spectra


@pytest.mark.parametrize("gamma", [1.0, 2.0, 3.3, 7.0])
def test_jonswap_continuous_m0_gives_hs(gamma):
    sea = Jonswap(hs=2.5, tp=9.0, gamma=gamma)
    m0 = _m0_fine(sea.spectrum, sea.omega_peak)
    # 1e-6: trapezoid on 4e5 points resolves the σ = 0.07 ωp peak to ~1e-9; the exact
    # normalisation comes from scipy quad to 1e-12.
    assert 4.0 * math.sqrt(m0) == pytest.approx(2.5, rel=1e-6)


def test_jonswap_dnv_normalisation_is_close_to_exact():
    for gamma in [1.0, 2.0, 3.3, 5.0]:
        # DNV-RP-C205 states 1 − 0.287 ln γ as an approximation; measured within 0.3 % here.
        assert jonswap_normalisation(gamma, "dnv") == pytest.approx(jonswap_normalisation(gamma), rel=5e-3)
    sea = Jonswap(hs=1.0, tp=5.0, gamma=3.3, normalisation="dnv")
    assert 4.0 * math.sqrt(_m0_fine(sea.spectrum, sea.omega_peak)) == pytest.approx(1.0, rel=2e-3)


def test_discretised_spectrum_m0():
    sea = Jonswap(hs=2.0, tp=8.0, repeat_period=1800.0)
    c = sea.components()
    lo, hi = sea.band
    w = np.linspace(lo, hi, 200_001)
    m0_band = np.trapezoid(sea.spectrum(w), w)
    # the Σ a²/2 rectangle rule on Δω = 2π/1800 = 0.0035 rad/s (16 points per peak width σωp)
    # integrates the band to 1e-3 (measured 2e-6 off)
    assert c.m0 == pytest.approx(m0_band, rel=1e-3)
    # the band (0.5, 5) ωp holds all but the ω⁻⁵ tail: 4√m0 within 0.2 % of Hs (measured 0.07 %)
    assert c.hs == pytest.approx(2.0, rel=2e-3)
    # jittered bins: a randomised midpoint rule, 200 bins of 0.0177 rad/s (3 per peak width)
    cj = Jonswap(hs=2.0, tp=8.0, n_components=200).components()
    assert cj.hs == pytest.approx(2.0, rel=1e-2)


def test_jonswap_peak_at_tp():
    for tp in [5.0, 8.0, 14.0]:
        sea = Jonswap(hs=1.0, tp=tp)
        w = np.linspace(0.2, 3.0, 280_001)
        dw = w[1] - w[0]
        assert abs(w[np.argmax(sea.spectrum(w))] - 2 * math.pi / tp) <= dw


def test_gamma_one_equals_pierson_moskowitz():
    jon = Jonswap(hs=3.0, tp=10.0, gamma=1.0)
    pm = PiersonMoskowitz(hs=3.0, tp=10.0)
    w = np.linspace(0.05, 5.0, 2000)
    np.testing.assert_allclose(jon.spectrum(w), pm.spectrum(w), rtol=1e-12, atol=0.0)
    # PM in Hs–Tp form integrates to Hs²/16 (analytic); the fine trapezoid agrees to 1e-6
    assert 4.0 * math.sqrt(_m0_fine(pm.spectrum, pm.omega_peak)) == pytest.approx(3.0, rel=1e-6)
    # the same seed discretises both identically
    np.testing.assert_allclose(jon.components().amplitude, pm.components().amplitude, rtol=1e-12)


def test_welch_estimate_and_hs_of_long_record():
    sea = Jonswap(hs=2.0, tp=8.0, gamma=3.3, n_components=600, seed=3)
    c = sea.components()
    dt = 0.5  # Nyquist 2π rad/s, above the 5 ωp = 3.9 rad/s band edge
    t = np.arange(2**15) * dt  # 4.55 h
    eta = elevation(c, t)
    # variance of a sum of sinusoids over T >> 2π/min spacing equals Σa²/2 up to cross terms
    # ~1/(T δω): 2 % covers them (measured 0.2 %)
    assert 4.0 * eta.std() == pytest.approx(2.0, rel=2e-2)
    f, P = signal.welch(eta, fs=1.0 / dt, nperseg=1024)
    w, S_est = 2 * np.pi * f, P / (2 * np.pi)  # one-sided density per rad/s
    S = sea.spectrum(w)
    wp = sea.omega_peak
    # bands of >= 6 Welch bins with ~63 half-overlapping segments: ~5 % statistical scatter;
    # 15 % is 3σ (measured worst 3 %)
    for a, b in [(0.7, 0.9), (0.9, 1.0), (1.0, 1.1), (1.1, 1.3), (1.3, 1.6), (1.6, 2.2), (2.2, 3.5)]:
        m = (w >= a * wp) & (w < b * wp)
        assert S_est[m].sum() / S[m].sum() == pytest.approx(1.0, abs=0.15), (a, b)
    assert abs(w[np.argmax(S_est)] - wp) <= 2 * (w[1] - w[0])


def test_user_spectrum_matches_parametric():
    jon = Jonswap(hs=2.0, tp=8.0, n_components=150, seed=5)
    w = np.linspace(0.2, 5.0, 20_000)
    user = UserSpectrum(w, jon.spectrum(w), n_components=150, seed=5, omega_range=jon.band)
    cu, cj = user.components(), jon.components()
    np.testing.assert_allclose(cu.omega, cj.omega, rtol=1e-14)
    np.testing.assert_allclose(cu.phase, cj.phase, rtol=1e-14)
    # linear interpolation of a table with 2.4e-4 rad/s spacing: 1e-3 relative near the peak
    np.testing.assert_allclose(cu.amplitude, cj.amplitude, rtol=1e-3, atol=1e-6)
    assert user.hs == pytest.approx(2.0, rel=2e-3)  # table covers all but the tail beyond 5 rad/s


# ---------------------------------------------------------------------------- seeds, repeat period


def test_seed_reproducible_and_independent_streams():
    a = Jonswap(hs=1.0, tp=6.0, seed=11).components()
    b = Jonswap(hs=1.0, tp=6.0, seed=11).components()
    c = Jonswap(hs=1.0, tp=6.0, seed=12).components()
    np.testing.assert_array_equal(a.phase, b.phase)
    np.testing.assert_array_equal(a.omega, b.omega)
    assert np.mean(np.abs(a.phase - c.phase)) > 0.5
    assert np.all((a.phase >= 0.0) & (a.phase < 2 * math.pi))
    # spreading draws from its own stream: phases and frequencies do not change
    d = Jonswap(hs=1.0, tp=6.0, seed=11, spreading=Spreading(8.0)).components()
    np.testing.assert_array_equal(a.phase, d.phase)
    np.testing.assert_array_equal(a.omega, d.omega)
    assert np.std(d.heading) > 0.1


def test_repeat_period_makes_elevation_periodic():
    TR = 512.0
    sea = Jonswap(hs=1.5, tp=7.0, repeat_period=TR, seed=2)
    c = sea.components(water_depth=30.0)
    np.testing.assert_allclose(c.omega / (2 * math.pi / TR), np.round(c.omega / (2 * math.pi / TR)), rtol=0, atol=1e-9)
    t = np.linspace(0.0, 300.0, 1001)
    x, y = np.array([0.0, 12.0, -40.0]), np.array([0.0, 5.0, 3.0])
    e0 = elevation(c, t, x, y)
    e1 = elevation(c, t + TR, x, y)
    e3 = elevation(c, t + 3 * TR, x, y)
    # rounding only: ω T_R ≈ 2e3 rad, relative 1e-16 → 1e-12 m
    np.testing.assert_allclose(e1, e0, rtol=0, atol=1e-10)
    np.testing.assert_allclose(e3, e0, rtol=0, atol=1e-10)
    # the subset form (fewer components) stays on the grid and periodic
    cs = Jonswap(hs=1.5, tp=7.0, repeat_period=TR, n_components=60).components()
    assert len(cs) == 60
    np.testing.assert_allclose(elevation(cs, t + TR), elevation(cs, t), atol=1e-10)
    assert cs.hs == pytest.approx(1.5, rel=2e-2)
    # jittered frequencies are not periodic with 2π/Δω (the equal-spacing period)
    cj = Jonswap(hs=1.5, tp=7.0, n_components=100).components()
    Tc = 2 * math.pi / ((sea.band[1] - sea.band[0]) / 100)
    assert np.max(np.abs(elevation(cj, t + Tc) - elevation(cj, t))) > 0.1


# ---------------------------------------------------------------------------- dispersion


def test_dispersion_deep_and_finite():
    w = np.linspace(0.05, 6.0, 120)
    np.testing.assert_allclose(wavenumber(w), w**2 / G, rtol=1e-15)
    # classic value: x tanh x = 1 at x = kh = 1.19967864025773 (ω²h/g = 1)
    h = 20.0
    assert wavenumber(math.sqrt(G / h), h) * h == pytest.approx(1.19967864025773, rel=1e-13)
    # constructed: ω²h/g = tanh(1) ↔ kh = 1
    assert wavenumber(math.sqrt(G * math.tanh(1.0) / h), h) * h == pytest.approx(1.0, rel=1e-14)
    for h in [0.5, 3.0, 50.0, 400.0]:
        k = wavenumber(w, h)
        kb = np.array([optimize.brentq(lambda kk: G * kk * np.tanh(kk * h) - ww**2, 1e-12, 1e3, xtol=1e-300, rtol=1e-15)
                       for ww in w])
        # both solve to ~1e-15; 1e-13 leaves room for the rounding of tanh near the root
        np.testing.assert_allclose(k, kb, rtol=1e-13)
    # shallow limit k ≈ ω/√(gh): kh = 0.01 makes the tanh correction (kh)²/6 ≈ 2e-5
    h, ww = 1.0, 0.01 * math.sqrt(G / 1.0)
    assert wavenumber(ww, h) == pytest.approx(ww / math.sqrt(G * h), rel=5e-5)
    assert wavenumber(np.array([[0.0, 1.0]]), 10.0).shape == (1, 2)
    assert wavenumber(0.0, 10.0) == 0.0


# ---------------------------------------------------------------------------- spreading


@pytest.mark.parametrize("s", [0.0, 1.0, 6.0, 40.0])
def test_spreading_density_and_samples(s):
    sp = Spreading(s)
    norm, _ = integrate.quad(sp.density, -math.pi, math.pi, epsabs=1e-13)
    assert norm == pytest.approx(1.0, abs=1e-10)
    beta = sp.sample(np.random.default_rng(7), 20_000)
    assert np.all(np.abs(beta) <= math.pi)

    # independent CDF: cumulative trapezoid of the density on a fine grid (not the Beta sampler)
    grid = np.linspace(-math.pi, math.pi, 20_001)
    cgrid = integrate.cumulative_trapezoid(sp.density(grid), grid, initial=0.0)
    # fixed seed: the exact sampler passes at p > 1e-3; a wrong s is rejected (power of the test)
    assert stats.kstest(beta, lambda b: np.interp(b, grid, cgrid)).pvalue > 1e-3
    wrong = Spreading(2 * s + 2)
    wgrid = integrate.cumulative_trapezoid(wrong.density(grid), grid, initial=0.0)
    assert stats.kstest(beta, lambda b: np.interp(b, grid, wgrid)).pvalue < 1e-6
    # first circular moment s/(s+1) ⇒ σ² = 2(1 − E cos β) = 2/(1+s); sample SE of E cos β ≤ 0.005
    assert 2.0 * (1.0 - np.mean(np.cos(beta))) == pytest.approx(sp.sigma**2, abs=0.02)
    assert sp.sigma**2 == pytest.approx(2.0 / (1.0 + s))


def test_spreading_normal_method_and_components():
    sp = Spreading(10.0, method="normal")
    beta = sp.sample(np.random.default_rng(1), 20_000)
    # seed 003: β = σ N(0,1), σ² = 2/(1+s) = 0.1818; SE of the sample std ~ 0.5 %
    assert np.std(beta) == pytest.approx(math.sqrt(2.0 / 11.0), rel=0.03)
    assert stats.kstest(beta / sp.sigma, "norm").pvalue > 1e-3
    # one direction per component, about the mean heading, with the cos2s distribution
    mean = 0.6
    c = Jonswap(hs=1.0, tp=6.0, heading=mean, spreading=Spreading(4.0), repeat_period=4000.0).components()
    assert len(np.unique(c.omega)) == len(c)
    dev = np.angle(np.exp(1j * (c.heading - mean)))
    grid = np.linspace(-math.pi, math.pi, 20_001)
    cg = integrate.cumulative_trapezoid(Spreading(4.0).density(grid), grid, initial=0.0)
    assert stats.kstest(dev, lambda b: np.interp(b, grid, cg)).pvalue > 1e-3


# ---------------------------------------------------------------------------- measured record


@pytest.mark.parametrize("n", [1000, 999])
def test_measured_elevation_reproduces_record(n):
    rng = np.random.default_rng(4)
    t = 37.0 + 0.2 * np.arange(n)
    eta = np.convolve(rng.standard_normal(n + 20), np.ones(20) / 20, mode="valid")[:n]
    eta -= eta.mean()
    c = MeasuredElevation(t, eta, heading=0.3).components(water_depth=25.0)
    assert c.repeat_period == pytest.approx(n * 0.2)
    # FFT round trip: rounding only
    np.testing.assert_allclose(elevation(c, t), eta, rtol=0, atol=1e-12 * n)
    np.testing.assert_allclose(c.heading, 0.3)
    # a pure sinusoid on the FFT grid is one component with its amplitude and phase
    w5 = 2 * math.pi * 5 / (n * 0.2)
    c1 = MeasuredElevation(t, 0.7 * np.cos(w5 * t - 0.3)).components()
    j = int(np.argmax(c1.amplitude))
    assert c1.omega[j] == pytest.approx(w5, rel=1e-12)
    assert c1.amplitude[j] == pytest.approx(0.7, rel=1e-12)
    assert np.angle(np.exp(1j * (c1.phase[j] - 0.3))) == pytest.approx(0.0, abs=1e-10)
    assert np.sum(np.delete(c1.amplitude, j)) < 1e-10


def test_measured_elevation_mean_warning_and_band():
    t = np.arange(512) * 0.25
    eta = 1.0 + np.cos(2 * math.pi * 8 / 128.0 * t)
    with pytest.warns(UserWarning, match="mean"):
        c = MeasuredElevation(t, eta, omega_range=(0.1, 1.0)).components()
    assert np.all((c.omega >= 0.1) & (c.omega <= 1.0))
    with pytest.raises(ValueError, match="uniformly"):
        MeasuredElevation(np.array([0.0, 1.0, 3.0]), np.zeros(3))


# ---------------------------------------------------------------------------- elevation, ramp


def test_regular_wave_elevation_hand_formula():
    H, T, beta, phi, h = 2.5, 8.0, math.radians(30.0), 0.4, 40.0
    c = Regular(H, T, heading=beta, phase=phi).components(water_depth=h)
    w = 2 * math.pi / T
    k = optimize.brentq(lambda kk: G * kk * math.tanh(kk * h) - w * w, 1e-6, 10.0, xtol=1e-15)
    t = np.linspace(0.0, 20.0, 41)
    x = np.array([[0.0, 10.0, -3.0], [7.0, 2.0, 1.0]])
    y = np.array([[0.0, -4.0, 8.0], [1.0, 2.0, 3.0]])
    eta = elevation(c, t, x, y)
    assert eta.shape == (41, 2, 3)
    hand = 0.5 * H * np.cos(k * (x * math.cos(beta) + y * math.sin(beta))[None] - w * t[:, None, None] + phi)
    np.testing.assert_allclose(eta, hand, rtol=0, atol=1e-12)
    assert np.ndim(elevation(c, 1.0)) == 0
    # crest at the origin at t = 0 when φ = 0 (the convention of the brief)
    assert elevation(Regular(2.0, 6.0).components(), 0.0) == pytest.approx(1.0)


def test_uniform_grid_elevation_equals_the_direct_sum():
    """A long uniform time grid takes the block-phase path of the harmonic sum (the phase table
    e^{−iωkh} made once, each block's start folded into the coefficients); it must equal the
    component-by-component sum Σ a_j cos(k_j x − ω_j t + φ_j) written out here. Tolerance 1e-11 of
    the amplitude sum: phases reach ω t ≈ 2.5e3 rad, whose round-off is ~1e-13 rad."""
    c = Jonswap(hs=2.0, tp=9.0, seed=4, n_components=60).components(water_depth=30.0)
    dt = 0.05
    t = 3.7 + dt * np.arange(5003)           # 19 blocks and a part one; starts off zero
    x = np.array([0.0, 25.0])
    eta = elevation(c, t, x, 0.0)
    phase = np.multiply.outer(c.wavenumber * np.cos(c.heading), x)[None] \
        - c.omega[None, :, None] * t[:, None, None] + c.phase[None, :, None]
    hand = np.einsum("j,tjp->tp", c.amplitude, np.cos(phase))
    scale = c.amplitude.sum()
    np.testing.assert_allclose(eta, hand, rtol=0, atol=1e-11 * scale)
    # a grid that is not uniform (one time moved by 1 ms) takes the direct path: same formula
    t2 = t.copy()
    t2[100] += 1e-3
    phase2 = -c.omega[None, :] * t2[:, None] + c.phase[None, :]
    np.testing.assert_allclose(elevation(c, t2), np.cos(phase2) @ c.amplitude, rtol=0,
                               atol=1e-11 * scale)


def test_ramp_shape_and_use():
    T = 20.0
    assert ramp(-1.0, T) == 0.0 and ramp(0.0, T) == 0.0
    assert ramp(T / 2, T) == pytest.approx(0.5) and ramp(T, T) == 1.0 and ramp(3 * T, T) == 1.0
    # slope continuous: zero at both ends (finite difference, step 1e-6 s → slope ≈ π²ε/(2T²))
    eps = 1e-6
    assert (ramp(eps, T) - ramp(0.0, T)) / eps < 1e-6
    assert (ramp(T, T) - ramp(T - eps, T)) / eps < 1e-6
    np.testing.assert_array_equal(ramp(np.array([-1.0, 0.0, 5.0]), 0.0), [0.0, 1.0, 1.0])
    c = Jonswap(hs=1.0, tp=6.0, n_components=50).components()
    t = np.linspace(0.0, 40.0, 201)
    np.testing.assert_allclose(elevation(c, t, ramp_duration=T), ramp(t, T) * elevation(c, t), atol=1e-14)


# ---------------------------------------------------------------------------- validation, immutability


def test_validation_errors_name_the_argument():
    with pytest.raises(ValueError, match="hs"):
        Jonswap(hs=0.0, tp=8.0)
    with pytest.raises(ValueError, match="tp"):
        Jonswap(hs=1.0, tp=-1.0)
    with pytest.raises(ValueError, match="gamma"):
        Jonswap(hs=1.0, tp=8.0, gamma=0.9)
    with pytest.raises(ValueError, match="n_components"):
        Jonswap(hs=1.0, tp=8.0, n_components=0)
    with pytest.raises(ValueError, match="omega_range"):
        PiersonMoskowitz(hs=1.0, tp=8.0, omega_range=(2.0, 1.0))
    with pytest.raises(ValueError, match="repeat_period"):
        Jonswap(hs=1.0, tp=8.0, repeat_period=0.0)
    with pytest.raises(ValueError, match="repeat_period"):  # grid 2π/T_R has no point in the band
        Jonswap(hs=1.0, tp=8.0, repeat_period=1.0, omega_range=(0.5, 2.0)).components()
    with pytest.raises(ValueError, match="n_components"):
        Jonswap(hs=1.0, tp=8.0, repeat_period=100.0, n_components=500).components()
    with pytest.raises(ValueError, match="seed"):
        Jonswap(hs=1.0, tp=8.0, seed=-1)
    with pytest.raises(ValueError, match="period"):
        Regular(1.0, 0.0)
    with pytest.raises(ValueError, match="height"):
        Regular(-1.0, 5.0)
    with pytest.raises(ValueError, match="spreading parameter"):
        Spreading(-0.5)
    with pytest.raises(ValueError, match="water_depth"):
        Regular(1.0, 5.0).components(water_depth=0.0)
    with pytest.raises(ValueError, match="S must be >= 0"):
        UserSpectrum([0.5, 1.0], [1.0, -1.0])
    with pytest.raises(TypeError, match="components"):
        elevation(Regular(1.0, 5.0), 0.0)


def test_immutable():
    sea = Jonswap(hs=1.0, tp=8.0)
    with pytest.raises(dataclasses.FrozenInstanceError):
        sea.hs = 2.0
    c = sea.components()
    assert isinstance(c, WaveComponents)
    with pytest.raises(ValueError):
        c.amplitude[0] = 1.0
    with pytest.raises(dataclasses.FrozenInstanceError):
        c.omega = c.omega
    w = np.linspace(0.5, 2.0, 5)
    u = UserSpectrum(w, np.ones(5))
    w[0] = 99.0  # the caller's array is copied
    assert u.omega[0] == 0.5
