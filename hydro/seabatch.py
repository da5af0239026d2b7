"""Many sea states discretised at once (a study's hundreds or thousands of seas).

:func:`components_many` gives, for each sea, the :class:`~hydro.waves.WaveComponents` that its own
``components(water_depth, g)`` gives, to round-off, with the same warnings and errors. Each sea's
random streams (its frequency jitter, phases and directions) are drawn from its own seed as there;
what is arithmetic on every sea's numbers is done on all of them together:

- the breaking check, H_s against Miche's height at the peak period (one Newton iteration of the
  dispersion relation for every sea);
- the band check, the fraction of the spectrum's variance that the band keeps. For the peaked
  spectra it is a function of the band in x = ω/ω_p alone, for a given γ:
  S(ω) dω = (H_s²/16) A_γ f_γ(x) dx, f_γ(x) = 5 x⁻⁵ e^{−5/4 x⁻⁴} γ^{r(x)}. So one table of
  F_γ(x) = ∫_{0.2}^{x} f_γ per distinct γ serves every sea (cumulative trapezoid on 20,001
  points geometric over [0.2, 200], as each sea's own 4,001-point quadrature over its band;
  the two agree within 1e-6, far inside what decides the warning);
- the spectrum at every component, and the wavenumbers (one Newton iteration over all).

On 960 JONSWAP seas of 200 components (M4 134's study): 1.0 ms a sea one by one, ~0.2 ms
together (cProfile of ``simulate_batch``, 960 and 480 cases, 2 cores).
"""
from __future__ import annotations

import functools
import math

import numpy as np

from hydro import waves as _w

__all__ = ["components_many"]

# the band table: x = ω/ω_p from 0.2 to 200 (below 0.2 ω_p, S < e^{−780} of its peak; above
# 200 ω_p the tail holds 4e-10 of the variance: as _SpectralSea._variance)
_X_RANGE = (0.2, 200.0)
_X_POINTS = 20001


@functools.lru_cache(maxsize=32)
def _band_table(gamma: float):
    """(ln x (N,), F_γ(x) (N,)): the cumulative trapezoid of f_γ(x) = 5 x⁻⁵ e^{−5/4 x⁻⁴} γ^{r(x)},
    the peaked spectrum in units of H_s²/16 per unit x, before A_γ."""
    x = np.geomspace(*_X_RANGE, _X_POINTS)
    f = _w.jonswap_spectrum(x, 4.0, 2.0 * math.pi, gamma, 1.0)     # H_s = 4, ω_p = 1: f_γ(x)
    F = np.concatenate([[0.0], np.cumsum(0.5 * (f[1:] + f[:-1]) * np.diff(x))])
    return np.log(x), F


def _band_fractions(seas):
    """Each peaked sea's :meth:`band_energy_fraction`, from :func:`_band_table`."""
    out = np.empty(len(seas))
    gammas = np.array([getattr(s, "gamma", 1.0) for s in seas])
    for gamma in np.unique(gammas):
        idx = np.flatnonzero(gammas == gamma)
        lnx, F = _band_table(float(gamma))
        wp = np.array([seas[i].omega_peak for i in idx])
        band = np.array([seas[i].band for i in idx])
        lo = np.clip(band[:, 0] / wp, *_X_RANGE)
        hi = np.clip(band[:, 1] / wp, *_X_RANGE)
        kept = np.interp(np.log(hi), lnx, F) - np.interp(np.log(lo), lnx, F)
        # a JONSWAP of the exact normalisation (and a PM) has ∫S = H_s²/16, so A_γ F is the
        # fraction; the DNV normalisation's total is the table's whole integral
        for j, i in enumerate(idx):
            sea = seas[i]
            exact = getattr(sea, "normalisation", "exact") == "exact"
            out[i] = kept[j] * getattr(sea, "_a_gamma", 1.0) if exact else kept[j] / F[-1]
    return out


def _vectorised(sea) -> bool:
    return type(sea) in (_w.Jonswap, _w.PiersonMoskowitz)


def components_many(seas, water_depth: float = math.inf, g: float = _w.G_STANDARD):
    """``[sea.components(water_depth=water_depth, g=g) for sea in seas]``, the same components to
    round-off, the JONSWAP and Pierson–Moskowitz seas together (the module docstring); any other
    sea (regular, user spectrum, measured) by its own call. None stays None."""
    seas = list(seas)
    out = [None] * len(seas)
    group = [i for i, s in enumerate(seas) if s is not None and _vectorised(s)]
    for i, s in enumerate(seas):
        if s is not None and not _vectorised(s):
            out[i] = s.components(water_depth=water_depth, g=g)
    if not group:
        return out
    h, g = _w._water_depth(water_depth), _w._positive("g", g)
    peaked = [seas[i] for i in group]
    hs = np.array([s.hs for s in peaked])
    tp = np.array([s.tp for s in peaked])

    # breaking, as _PeakSea.components: H_s against Miche's height at the peak period
    broken = np.flatnonzero(hs > _w.breaking_height(tp, h, g))
    if broken.size:             # that sea's own check gives the error
        peaked[broken[0]]._refuse_breaking(h, g)

    for j in np.flatnonzero(_band_fractions(peaked) < _w.BAND_ENERGY_MIN):
        # the sea's own quadrature decides and words it, as in its own call (the tables are
        # within 1e-6 of it)
        peaked[j]._warn_band(peaked[j].band_energy_fraction(), stacklevel=3)

    # each sea's draws from its own seed, as _SpectralSea.components
    omega, dw, phase, heading = zip(*(s._draws() for s in peaked))
    counts = np.array([len(w) for w in omega])
    each = lambda a: np.repeat(a, counts)  # noqa: E731
    w_all = np.concatenate(omega)
    gamma = np.array([getattr(s, "gamma", 1.0) for s in peaked])
    a_gamma = np.array([getattr(s, "_a_gamma", 1.0) for s in peaked])
    S = _w.jonswap_spectrum(w_all, each(hs), each(tp), each(gamma), each(a_gamma))
    amplitude = np.sqrt(2.0 * np.maximum(S, 0.0) * np.concatenate(dw))
    wavenumbers = _w.wavenumber(w_all, h, g)
    cut = np.cumsum(counts)[:-1]
    for i, s, a, kk, w, ph, beta in zip(group, peaked, np.split(amplitude, cut),
                                        np.split(wavenumbers, cut), omega, phase, heading):
        out[i] = _w.WaveComponents._made(omega=w, amplitude=a, phase=ph, heading=beta,
                                         wavenumber=kk, water_depth=h, g=g,
                                         repeat_period=s.repeat_period)
    return out
