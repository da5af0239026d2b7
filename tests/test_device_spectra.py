"""Wave spectra against the closed forms of DNV-RP-C205 (2010) §3.5.5, written out here, at points
on both sides of the peak (where σ_a = 0.07 and σ_b = 0.09 act), and the discretised amplitudes
a_j = √(2 S(ω_j) Δω_j) against the same closed forms."""
import math

import numpy as np
import pytest
from scipy import integrate

import hydro

HS, TP = 2.5, 9.0
WP = 2 * math.pi / TP
# both sides of ω_p: below (σ_a = 0.07 acts), at, and above (σ_b = 0.09 acts), near and far
X = np.array([0.6, 0.85, 0.93, 0.97, 1.0, 1.03, 1.07, 1.15, 1.4, 2.5])


def s_pm(w, hs, tp):
    """DNV-RP-C205 eq. 3.5.5.1: S_PM(ω) = 5/16 Hs² ω_p⁴ ω⁻⁵ exp(−5/4 (ω/ω_p)⁻⁴)."""
    wp = 2 * math.pi / tp
    return 5.0 / 16.0 * hs**2 * wp**4 * w**-5 * np.exp(-1.25 * (w / wp) ** -4)


def s_jonswap(w, hs, tp, gamma, a_gamma):
    """DNV-RP-C205 eq. 3.5.5.2: S_J = A_γ S_PM γ^exp(−½((ω − ω_p)/(σ ω_p))²), σ = σ_a = 0.07 for
    ω ≤ ω_p and σ_b = 0.09 for ω > ω_p."""
    wp = 2 * math.pi / tp
    sigma = np.where(w <= wp, 0.07, 0.09)
    return a_gamma * s_pm(w, hs, tp) * gamma ** np.exp(-0.5 * ((w - wp) / (sigma * wp)) ** 2)


def test_pierson_moskowitz_closed_form():
    w = X * WP
    # 1e-12: the same closed form in another arrangement, float64 rounding only
    np.testing.assert_allclose(hydro.PiersonMoskowitz(hs=HS, tp=TP).spectrum(w), s_pm(w, HS, TP),
                               rtol=1e-12)


@pytest.mark.parametrize("gamma", [2.0, 3.3, 7.0])
def test_jonswap_closed_form_dnv_normalisation(gamma):
    w = X * WP
    sea = hydro.Jonswap(hs=HS, tp=TP, gamma=gamma, normalisation="dnv")
    # A_γ = 1 − 0.287 ln γ (DNV-RP-C205 eq. 3.5.5.3); 1e-12: rounding only. Swapping σ_a and σ_b
    # changes S by γ^(Δ of the exponent): 10 % at ω = 0.97 ω_p for γ = 3.3.
    np.testing.assert_allclose(sea.spectrum(w), s_jonswap(w, HS, TP, gamma, 1 - 0.287 * math.log(gamma)),
                               rtol=1e-12)


def test_jonswap_exact_normalisation_is_hs():
    # "exact": A_γ makes 4 √m0 = Hs for the closed form above (integrated here by scipy, split at
    # the kink of σ at ω_p); 1e-8: quadrature tolerance
    gamma = 3.3
    m0_unit, _ = integrate.quad(lambda w: s_jonswap(w, HS, TP, gamma, 1.0), 0.05 * WP, WP, limit=200)
    above, _ = integrate.quad(lambda w: s_jonswap(w, HS, TP, gamma, 1.0), WP, 50 * WP, limit=200)
    a_gamma = HS**2 / 16 / (m0_unit + above)
    w = X * WP
    sea = hydro.Jonswap(hs=HS, tp=TP, gamma=gamma)
    np.testing.assert_allclose(sea.spectrum(w), s_jonswap(w, HS, TP, gamma, a_gamma), rtol=1e-6)
    # and the DNV approximation of A_γ is within its stated ~1 % of the exact one
    assert abs(a_gamma / (1 - 0.287 * math.log(gamma)) - 1) < 0.015


def test_discretised_amplitudes_follow_the_closed_form():
    # repeat_period: ω_j = multiples of 2π/T_R, Δω_j = 2π/T_R exactly; a_j = √(2 S(ω_j) Δω_j)
    T_R = 200.0
    sea = hydro.Jonswap(hs=HS, tp=TP, gamma=3.3, normalisation="dnv", repeat_period=T_R,
                        omega_range=(0.5 * WP, 3 * WP))
    c = sea.components()
    dw = 2 * math.pi / T_R
    np.testing.assert_allclose(np.diff(c.omega), dw, rtol=1e-12)
    np.testing.assert_allclose(c.amplitude, np.sqrt(2 * s_jonswap(c.omega, HS, TP, 3.3, 1 - 0.287 * math.log(3.3)) * dw),
                               rtol=1e-12)
    # deep-water dispersion k = ω²/g (1e-12: rounding)
    np.testing.assert_allclose(c.wavenumber, c.omega**2 / 9.81, rtol=1e-12)
