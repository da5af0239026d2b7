"""The linear frequency-domain level of the fidelity ladder: a sea state's response as the sum of
its wave components, each the model's RAO times the component's complex amplitude, with no time
stepping.

For a sea discretised as a_j e^{iφ_j} at ω_j, β_j (:meth:`hydro.waves.Jonswap.components`) and the
model linearised about its equilibrium q₀ (:func:`mfm.frequency_response`, RAOs x̂(ω, β) per metre of
wave amplitude, x(t) = Re[x̂ e^{−iωt}]):

    q(t) = q₀ + Re Σ_j a_j e^{iφ_j} x̂(ω_j, β_j) e^{−iω_j t}                 (the time series)
    σ_q² = Σ_j ½ a_j² |x̂(ω_j, β_j)|²                                       (its variance)
    P̄ = Σ_j a_j² · ½ c ω_j² |G x̂(ω_j, β_j)|²                              (mean damper power)

(G the rows that give each PTO's rate from q̇: a joint damper's coordinate, a piston's stroke rate
linearised at q₀.)

— the same components and phases as :func:`mfm.simulate` excites the time domain with (the
excitation is ``hydro.excitation.excitation_time_series`` of the same components), so the two can be
compared sample by sample. Valid where the model is linear about q₀ over the motions the sea makes:
small rotations, drag and other quadratic loads negligible (they are absent here), no hinge at a
stop. :func:`mfm.reduce` measures when that holds.
"""
from __future__ import annotations

import time as _time

import numpy as np
import xarray as xr

from . import frequency as _fd
from . import results
from .model import Model

def _check_sea(sea):
    if sea is None or not hasattr(sea, "components"):
        raise ValueError(f"sea: {sea!r}; give a sea state of hydro.waves (Regular, Jonswap, "
                         "PiersonMoskowitz, UserSpectrum, ...)")


def spectral_response(model: Model, sea, *, t=None, q0=None, loads=None,
                      radiation: str = "database", state_space_options: dict | None = None
                      ) -> xr.Dataset:
    """The model's linear response to ``sea`` by spectral synthesis (module docstring).

    model: a Model with hydrodynamics. sea: a sea state of :mod:`hydro.waves` (its components must
    lie inside the database's frequency range, as for :func:`mfm.simulate`); components are grouped
    by heading, so a spread sea costs one linear solve per distinct heading.
    t: times (s) at which to synthesise the time series (1-D, finite); None gives the statistics
    only. q0, loads, radiation, state_space_options: as :func:`mfm.frequency_response`.

    Returns an xarray.Dataset: ``q_rms`` (coordinate) the standard deviation about the equilibrium,
    ``pto_power_mean`` (pto) the expected mean power of each joint damper and hydraulic piston
    (W; a piston's rate ẇ = G q̇ linearised at q₀, :meth:`~mfm.loads.base.Load.linear_dampers`),
    ``equilibrium`` (coordinate); with ``t`` also ``q``, ``qd`` (time, coordinate), ``pto_power``
    (time, pto) = c (G q̇)² (W) and ``eta`` (time) the elevation at the origin (m). Attributes: provenance, the
    sea, ``level = "spectral"``, ``n_components`` and the wall time of the synthesis.
    """
    # the harmonic sum of the time-domain excitation and elevation (hydro.waves), chunked over t
    from hydro.waves import _harmonic_sum, elevation

    if model.hydro is None:
        raise ValueError(f"model {model.name!r} has no hydrodynamics: spectral_response needs a "
                         "config with a [hydro] table")
    _check_sea(sea)
    if t is not None:
        try:
            t = np.asarray(t, dtype=float)
        except (TypeError, ValueError):
            raise ValueError(f"t: {t!r}; give a 1-D array of times in seconds") from None
        if t.ndim != 1 or t.size == 0 or not np.all(np.isfinite(t)):
            raise ValueError(f"t: shape {t.shape}; give a non-empty 1-D array of finite times (s)")
    start = _time.perf_counter()
    comps = sea.components(water_depth=model.hydro.water_depth, g=model.hydro.g)
    options = {"radiation": radiation, "state_space_options": state_space_options}
    sys = _fd.linear_system(model, q0, loads=loads)
    n = model.n_coordinates
    x = np.zeros((len(comps), n), dtype=complex)
    for beta in np.unique(comps.heading):
        sel = comps.heading == beta
        x[sel] = _fd._amplitudes(model, sys, comps.omega[sel], float(beta), options)
    a = comps.complex_amplitude
    damped = [k for k in range(n) if float(model.damping[k]) > 0]
    c = np.asarray(model.damping, dtype=float)[damped]
    # every PTO as a damping c on a rate G q̇: the joint dampers (G rows of the identity), then the
    # loads' pistons linearised at q₀ (the time domain's pto order)
    dampers = results.linear_dampers(sys.loads, sys.kin0)
    G = np.concatenate([np.eye(n)[damped]] + [np.asarray(d.rows) for d in dampers])
    c_all = np.concatenate([c] + [np.asarray(d.damping, dtype=float) for d in dampers])
    mean_power = np.sum(comps.amplitude[:, None] ** 2
                        * results.mean_absorbed_power(c_all, comps.omega[:, None], x @ G.T), axis=0)
    q_rms = np.sqrt(np.sum(0.5 * comps.amplitude[:, None] ** 2 * np.abs(x) ** 2, axis=0))
    data = {
        "q_rms": (("coordinate",), q_rms, {"long_name": "standard deviation about the equilibrium",
                                           "units": "m or rad (per coordinate: coordinate_unit)"}),
        "pto_power_mean": (("pto",), mean_power, {"long_name": "expected mean power of each joint "
                                                  "damper and piston, Σ a² ½ c ω² |G x|²",
                                                  "units": "W"}),
        "equilibrium": (("coordinate",), sys.q0, {"units": "m or rad"}),
    }
    coords = {**results._coordinate_coords(model),
              "pto": [model.coordinates[k] for k in damped] + [p for d in dampers for p in d.names]}
    if t is not None:
        coef = a[:, None] * x
        # q and q̇ in one harmonic sum (the exponentials are most of the cost)
        both = _harmonic_sum(comps.omega, np.concatenate([coef, -1j * comps.omega[:, None] * coef], 1), t)
        q, qd = sys.q0[None] + both[:, :n], both[:, n:]
        data.update(
            q=(("time", "coordinate"), q, {"long_name": "generalised coordinates",
                                           "units": "m or rad (per coordinate: coordinate_unit)"}),
            qd=(("time", "coordinate"), qd, {"long_name": "generalised velocities",
                                             "units": "m/s or rad/s"}),
            pto_power=(("time", "pto"), results.absorbed_power(c_all, qd @ G.T),
                       {"long_name": "power absorbed by each joint damper and piston, c (G q̇)²",
                        "units": "W"}),
            eta=(("time",), np.asarray(elevation(comps, t)).reshape(-1),
                 {"long_name": "undisturbed wave elevation at the origin", "units": "m"}))
        coords["time"] = ("time", t, {"units": "s"})
    wall = _time.perf_counter() - start
    ds = xr.Dataset(data, coords=coords, attrs={
        "title": f"mfm spectral response of {model.name}",
        **results.provenance(model, sys.loads, level="spectral", sea=repr(sea),
                             n_components=len(comps), radiation=radiation,
                             convention="exp(-i omega t)", wall_time_s=wall),
        "source": model.hydro.source})
    return ds
