"""Wave energy measures: incident wave power, capture width ratio, response statistics and RAOs
from time series (Lande-Sudall et al. §6).

Conventions of Lande-Sudall et al., kept so that its figures can be reproduced:

- deep-water wave power per metre of crest, irregular sea  P_w = ρ g² H_s² T_e / (64 π),
  regular wave  P_w = ρ g² H² T / (32 π)  (the group velocity g T / 4π times the energy ρ g H² / 8);
- the device length  L_e = g T_e² / (2π), the deep-water wavelength at the energy period;
- T_e = 0.84 T_p for JONSWAP γ = 3.3 and 0.78 T_p for γ = 1 (Lande-Sudall et al. §6.3; the exact ratios
  m₋₁/m₀ of our spectra are :func:`energy_period`);
- the capture width ratio  CWR = P_av / (P_w L_e)  (Lande-Sudall et al. eq. 53);
- the RAO from an irregular run  √(S_θθ / S_ηη)  (Lande-Sudall et al. eq. 54).

The deep-water expressions are the seed's choice also where the basin is not deep (1 m water at
T_p = 1.8 s: k h ≈ 1.3); :func:`wave_power` takes ``water_depth`` for the finite-depth value.
"""
from __future__ import annotations

import math

import numpy as np

#: T_e / T_p used by Lande-Sudall et al. for its JONSWAP seas, by peak enhancement γ
SEED_TE_OVER_TP = {3.3: 0.84, 1.0: 0.78}


def deep_water_wavelength(period, g: float = 9.81):
    """L = g T² / (2π), m (period in s)."""
    return g * np.asarray(period, dtype=float) ** 2 / (2 * math.pi)


def wave_power(height, period, *, regular: bool = False, rho: float = 1000.0, g: float = 9.81,
               water_depth: float = math.inf):
    """Incident wave power per metre of crest, W/m.

    Irregular (default): ``height`` = H_s, ``period`` = T_e, P = ρ g² H_s² T_e / (64π) in deep
    water. Regular: ``height`` = H, ``period`` = T, P = ρ g² H² T / (32π). With a finite
    ``water_depth`` the energy ρ g H²/8 (H_s²/16) travels at the group velocity of depth h at
    that period instead of g T / 4π.
    """
    H = np.asarray(height, dtype=float)
    T = np.asarray(period, dtype=float)
    energy = rho * g * H ** 2 / (8.0 if regular else 16.0)
    if math.isinf(water_depth):
        return energy * g * T / (4 * math.pi)
    from hydro.waves import wavenumber

    w = 2 * math.pi / T
    k = np.asarray(wavenumber(np.atleast_1d(w).ravel(), water_depth, g)).reshape(np.shape(w))
    kh = k * water_depth
    cg = 0.5 * (w / k) * (1.0 + 2.0 * kh / np.sinh(2.0 * kh))
    return energy * cg


def capture_width_ratio(mean_power, wave_power_per_metre, length):
    """CWR = P_av / (P_w L): mean absorbed power (W) over the wave power per metre (W/m) times a
    length (m; Lande-Sudall et al.: L_e, the deep-water wavelength at T_e)."""
    return np.asarray(mean_power) / (np.asarray(wave_power_per_metre) * np.asarray(length))


def energy_period(sea, n: int = 4000) -> float:
    """T_e = m₋₁ / m₀ (s) of a sea's spectrum S(ω) (``hydro.waves`` Jonswap, PiersonMoskowitz,
    UserSpectrum), by the trapezoid rule over 0.2 ω_p … 8 ω_p."""
    wp = 2 * math.pi / sea.tp
    w = np.linspace(0.2 * wp, 8 * wp, n)
    S = np.asarray(sea.spectrum(w))
    return float(2 * math.pi * np.trapezoid(S / w, w) / np.trapezoid(S, w))


def harmonic_amplitude(t, y, omega: float, extra_omegas=()):
    """Complex amplitude x̂ of y(t) ≈ c + d t + Re[x̂ e^{−iωt}] by least squares (the convention
    of :func:`mfm.frequency_response`), with free cos/sin terms (and their growth t·cos, t·sin)
    at ``extra_omegas`` so that slowly decaying transients at other frequencies (natural
    modes) do not bias it."""
    t = np.asarray(t, dtype=float)
    cols = [np.ones_like(t), t, np.cos(omega * t), np.sin(omega * t)]
    for wn in np.asarray(extra_omegas, dtype=float).ravel():
        cols += [np.cos(wn * t), np.sin(wn * t), t * np.cos(wn * t), t * np.sin(wn * t)]
    c = np.linalg.lstsq(np.stack(cols, 1), np.asarray(y, dtype=float), rcond=None)[0]
    # y = a cos ωt + b sin ωt = Re[(a + i b) e^{−iωt}]
    return complex(c[2], c[3])


def spectral_rao(t, response, elevation, *, segment: float | None = None):
    """RAO = √(S_rr / S_ηη) (Lande-Sudall et al. eq. 54) from an irregular run: Welch spectra (Hann windows
    of ``segment`` seconds, default a quarter of the record, half overlap) of the response and of
    the undisturbed elevation. Returns (ω (rad/s), RAO, S_ηη (m² s/rad))."""
    from scipy.signal import welch

    t = np.asarray(t, dtype=float)
    dt = float(t[1] - t[0])
    nper = int(round((segment or (t[-1] - t[0]) / 4) / dt))
    f, S_rr = welch(np.asarray(response, float), fs=1.0 / dt, nperseg=nper)
    _, S_ee = welch(np.asarray(elevation, float), fs=1.0 / dt, nperseg=nper)
    with np.errstate(divide="ignore", invalid="ignore"):
        rao = np.sqrt(S_rr / S_ee)
    return 2 * math.pi * f, rao, S_ee / (2 * math.pi)
