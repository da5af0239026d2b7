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
small rotations, no hinge at a stop. :func:`mfm.reduce` measures when that holds.

Quadratic drag — the water's (−D_a |v_a − u_a| (v_a − u_a) per inertial axis at each reference
point on the relative flow with ``[hydro] drag_flow = "relative"``, −D_a |v_a| v_a on the body's
own velocity with ``"body"``) and every ``[[morison]]``
point's (½ ρ C_D A |w_n| w_n on the normal flow w_n = (I − e eᵀ)(u − v)) — is linearised
stochastically for each sea (:mod:`mfm.frequency.drag`): the force of least mean-square error for a
Gaussian relative flow w, C w with C = E[∂f/∂w] (per axis Borgman's c_eq = D √(8/π) σ_w), so that

    [Z(ω_j) − iω_j Σ_p R_pᵀ C_p R_p] x̂_j = F(ω_j, β_j) + Σ_p R_pᵀ C_p P_p û_p(ω_j, β_j),
    σ_w,p² from Σ_j ½ a_j² |P_p û_pj + iω_j R_p x̂_j|²,

(R_p the point's projected velocity rows, û_p the linear particle velocity per unit amplitude at
its rest position, every component of the sea with its heading) iterated from C = 0 to a fixed
point: damping C on the body's velocity and the excitation C û of the flow. Each sea gets its own
C (``drag_damping``, ``relative_flow_rms``). The drag on the body's own velocity (``[hydro]
drag_flow = "body"``, the default) is linearised the same way with u = 0: a damping C alone, the
fixed point :func:`mfm.optimize` reaches in jax (:mod:`mfm.studies.design`). The
linearisation's known error: a Gaussian response assumed (the drag's own non-Gaussian, odd
harmonics are dropped), typically 5–15 % on the standard deviation where drag dominates the
damping, less where radiation and PTO damping do.
"""
from __future__ import annotations

import time as _time
import warnings

import numpy as np
import xarray as xr
from hydro.seabatch import components_many

from ..radiation import label as radiation_label
from .. import results
from ..loads.pto import linear_ptos, mean_absorbed_power
from ..mechanics.model import Model
from ..validation import check_model, check_sea, check_sea_in_grid, check_seas
from ..frequency.response import _amplitudes
from ..frequency.rest import linear_system

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
    (time, pto) = c (G q̇)² (W) and ``eta`` (time) the elevation at the origin (m). With
    quadratic drag (the water's, on the relative flow or the body's own velocity, and
    ``[[morison]]`` elements: module docstring) also ``drag_damping`` (drag_point, flow_axis, flow_axis_col) each point's
    equivalent damping C (N s/m) and ``relative_flow_rms`` (drag_point, flow_axis) the standard
    deviation of its relative flow (m/s), and the attributes ``drag_iterations``, ``drag_change``
    (the fixed point's). With loads that record outputs linear about q₀
    (:meth:`~mfm.loads.base.Load.linear_outputs`: a catenary line's ``fairlead_tension``) also
    ``<name>_equilibrium`` (its value at the equilibrium), ``<name>_rms`` its standard deviation
    sqrt(Σ ½ a² |L x̂|²) and, with ``t``, ``<name>`` (time, …) = y₀ + L (q − q₀). Attributes: provenance, the sea, ``level = "spectral"``,
    ``n_components`` and the wall time. The one-sea case of :func:`spectral_sweep`.
    """
    model = check_model(model)
    if model.hydro is None:
        raise ValueError(f"model {model.name!r} has no hydrodynamics: spectral_response needs a "
                         "config with a [hydro] table")
    check_sea(sea, still_water=False)
    if t is not None:
        try:
            t = np.asarray(t, dtype=float)
        except (TypeError, ValueError):
            raise ValueError(f"t: {t!r}; give a 1-D array of times in seconds") from None
        if t.ndim != 1 or t.size == 0 or not np.all(np.isfinite(t)):
            raise ValueError(f"t: shape {t.shape}; give a non-empty 1-D array of finite times (s)")
    # one sea is the one-case sweep (one place for the synthesis), relabelled over time
    return results.spectral_one(_sweep(model, [sea], ["sea"], t=t, q0=q0, loads=loads,
                                       radiation=radiation,
                                       state_space_options=state_space_options), sea, t)


def _check_in_grid(model, seas, labels):
    """The seas' components (one WaveComponents each), each checked to lie inside the model's
    database grid (:func:`mfm.validation.check_sea_in_grid`, naming the sea by its label)."""
    from hydro.excitation import GRID_RTOL

    grid = np.asarray(model.hydro.database()["omega"].values, dtype=float)
    grid = np.sort(grid[np.isfinite(grid)])
    comps = components_many(seas, water_depth=model.hydro.water_depth, g=model.hydro.g)
    for c, s, what in zip(comps, seas, labels):
        check_sea_in_grid(c, s, grid, what, rtol=GRID_RTOL)
    return comps


def component_union(comps_list):
    """The distinct (β, ω) pairs (U, 2) of several seas' components (sorted by heading, then
    frequency), the index in them of every component of the seas in turn, and where each sea's
    components start in that index ((len + 1,), cumulative): one linear solve per pair serves
    every sea that has it."""
    pairs = np.concatenate([np.stack([c.heading, c.omega], axis=1) for c in comps_list])
    union, inverse = np.unique(pairs, axis=0, return_inverse=True)
    return union, np.asarray(inverse).reshape(-1), np.cumsum([0] + [len(c.omega) for c in comps_list])


def _union_raos(model, sys, comps_list, options):
    """The RAOs x̂ (n_j, n_q) of every sea's components from ONE linear solve per distinct heading
    over the union of their (β, ω) pairs (seas of one seed share their frequencies: the M4 134
    power matrix's 120 seas are 200 pairs, not 24,000). Returns (one array per sea, the number of
    distinct pairs solved)."""
    if not comps_list:
        return [], 0
    union, inverse, bounds = component_union(comps_list)
    if union.size == 0:
        return [np.zeros((0, model.n_coordinates), dtype=complex) for _ in comps_list], 0
    x = np.zeros((len(union), model.n_coordinates), dtype=complex)
    for beta in np.unique(union[:, 0]):
        sel = union[:, 0] == beta
        x[sel] = _amplitudes(model, sys, union[sel, 1], float(beta), options)
    return [x[inverse[bounds[i]:bounds[i + 1]]] for i in range(len(comps_list))], len(union)


def _times(t, B):
    """t as (B, n_t): one grid for every case (1-D) or one per case (2-D)."""
    if t is None:
        return None
    try:
        arr = np.asarray(t, dtype=float)
    except (TypeError, ValueError):
        raise ValueError(f"t: {t!r}; give times in seconds, 1-D (every case) or 2-D "
                         f"(case, time) with {B} rows") from None
    if arr.ndim == 1:
        arr = np.broadcast_to(arr, (B, arr.size))
    if arr.ndim != 2 or arr.shape[0] != B or arr.shape[1] == 0 or not np.all(np.isfinite(arr)):
        raise ValueError(f"t: shape {np.shape(t)}; give non-empty finite times (s), 1-D (every "
                         f"case) or 2-D (case, time) with {B} rows")
    return arr


def _synthesise(comps, xs, times, q0):
    """q, q̇ (B, n_t, n_q) and η (B, n_t) at the origin of every case: Re Σ_j c_j e^{−iω_j t} with
    c_j = a_j e^{iφ_j} (x̂_j, −iω_j x̂_j, 1) (the elevation of :func:`hydro.waves.elevation` at
    x = y = 0). The phases e^{−iω_j t} are most of the cost: cases with the same time grid and
    frequencies (a power matrix's seas of one T_p and one seed) share one harmonic sum."""
    from hydro.waves import _harmonic_sum

    B, n_t = times.shape
    n = q0.shape[0]
    q, qd, eta = np.empty((B, n_t, n)), np.empty((B, n_t, n)), np.empty((B, n_t))
    groups: dict = {}
    for i, cm in enumerate(comps):
        groups.setdefault((times[i].tobytes(), cm.omega.tobytes()), []).append(i)
    for members in groups.values():
        omega = comps[members[0]].omega
        cols = []
        for i in members:
            a = comps[i].complex_amplitude[:, None]
            coef = a * xs[i]
            cols += [coef, -1j * omega[:, None] * coef, a]
        out = _harmonic_sum(omega, np.concatenate(cols, axis=1), times[members[0]])
        for k, i in enumerate(members):
            block = out[:, k * (2 * n + 1):(k + 1) * (2 * n + 1)]
            q[i], qd[i], eta[i] = q0[None] + block[:, :n], block[:, n:2 * n], block[:, 2 * n]
    return q, qd, eta


def spectral_sweep(model: Model, seas, *, t=None, q0=None, loads=None,
                   radiation: str = "database", state_space_options: dict | None = None
                   ) -> xr.Dataset:
    """:func:`spectral_response` of many sea states in one call, with the model linearised once
    and its RAOs solved once on the union of the seas' component frequencies and headings (module
    docstring: per case i, σ_q² = Σ_j ½ a_ij² |x̂(ω_ij, β_ij)|², P̄ = Σ_j a_ij² ½ c ω_ij² |G x̂|²).
    Its front door is ``mfm.sweep(model, seas, level="spectral")``; a power matrix of a model
    linear over its sea states needs no time stepping.

    model: a Model with hydrodynamics (one: the linearisation is shared by every case).
    seas: a sequence of sea states of :mod:`hydro.waves` (or one).
    t: None (the statistics only), times (s) 1-D for every case or 2-D (case, time): the time
    series too (memory B × n_t × n_q).
    q0, loads, radiation, state_space_options: as :func:`mfm.frequency_response`.

    Returns an xarray.Dataset over ``case`` with the sea labels of :func:`mfm.simulate_batch`
    (``sea_hs``, ``sea_tp``, ``sea_gamma``, ``sea_heading``, …): ``q_rms`` (case, coordinate),
    ``pto_power_mean`` (case, pto) the expected mean power of each joint damper and hydraulic
    piston (W; as :func:`spectral_response`),
    ``n_components`` (case), ``equilibrium`` (coordinate); with ``t`` also ``time`` (case, step),
    ``q``, ``qd`` (case, step, coordinate), ``pto_power`` (case, step, pto) and ``eta`` (case,
    step); with drag on the relative flow ``drag_damping`` (case, drag_point, flow_axis,
    flow_axis_col) and ``relative_flow_rms`` (case, drag_point, flow_axis), each sea linearised on
    its own (module docstring); the loads' linear outputs as :func:`spectral_response` (``<name>_rms``
    over case, ``<name>`` over case and step). Attributes: provenance, ``level = "spectral"``, the seas,
    ``n_frequencies_solved`` (the union), the wall times of the RAO solve and of the whole call.
    """
    start = _time.perf_counter()
    if model.hydro is None:
        raise ValueError(f"model {model.name!r} has no hydrodynamics: the spectral level needs a "
                         "config with a [hydro] table")
    seas = check_seas(seas)
    return _sweep(model, seas, [f"seas[{i}]" for i in range(len(seas))], t=t, q0=q0, loads=loads,
                  radiation=radiation, state_space_options=state_space_options, start=start)


def _sweep(model, seas, labels, *, t, q0, loads, radiation, state_space_options, start=None):
    """:func:`spectral_sweep` of checked ``seas``, each named by its label in errors."""
    start = _time.perf_counter() if start is None else start
    B = len(seas)
    times = _times(t, B)
    comps = _check_in_grid(model, seas, labels)
    options = {"radiation": radiation, "state_space_options": state_space_options}
    sys = linear_system(model, q0, loads=loads)
    # quadratic drag (the water's, on the relative flow or the body's own velocity, and Morison
    # elements'): linearised stochastically per sea (its damping depends on the sea)
    groups = [g for ld in sys.loads if (g := ld.quadratic_drag(model, sys.kin0)) is not None]
    solve_start = _time.perf_counter()
    if groups:
        xs, n_union, drag = drag_raos(model, sys, comps, options, groups)
    else:
        xs, n_union = _union_raos(model, sys, comps, options)
    solve_s = _time.perf_counter() - solve_start
    n = model.n_coordinates
    # every PTO as a damping c on a rate G q̇: the joint dampers (rows of the identity), then the
    # loads' pistons linearised at q₀ (the time domain's pto order)
    ptos = linear_ptos(model, sys.loads, sys.kin0)
    G, c = ptos.rows, ptos.damping
    q_rms = np.empty((B, n))
    power = np.empty((B, len(c)))
    for i, (cm, x) in enumerate(zip(comps, xs)):
        a2 = cm.amplitude[:, None] ** 2
        power[i] = np.sum(a2 * mean_absorbed_power(c, cm.omega[:, None], x @ G.T), axis=0)
        q_rms[i] = np.sqrt(np.sum(0.5 * a2 * np.abs(x) ** 2, axis=0))
    series = None if times is None else (np.array(times),) + _synthesise(comps, xs, times, sys.q0)
    settings = dict(level="spectral", seas=repr(seas), n_frequencies_solved=n_union,
                    radiation=radiation_label(radiation), convention="exp(-i omega t)", rao_solve_s=solve_s)
    if groups:
        settings.update(results.drag_settings(groups, drag))
    ds = results.spectral(model, sys.loads, sys.q0, q_rms, power, ptos, comps, seas, settings,
                          series, start)
    # what the loads record in the time domain, to first order (a catenary's fairlead tension):
    # its standard deviation from the RAOs, its series from the synthesised q
    outs, coords = results.linear_outputs(model, sys.loads, sys.kin0)
    if outs:
        rms = {name: np.stack([np.sqrt(np.sum(0.5 * cm.amplitude[:, None] ** 2
                                              * np.abs(x @ np.asarray(L).T) ** 2, axis=0))
                               for cm, x in zip(comps, xs)])
               for name, (_, _, L, _) in outs.items()}
        ds = results.add_linear_outputs(ds, outs, coords, sys.q0,
                                        None if series is None else series[1],
                                        lead=("case", "step"), rms=rms)
    if groups:
        ds = results.drag_linearisation(ds, groups, drag["C"], drag["sigma"])
    return ds


def drag_raos(model, sys, comps_list, options, groups):
    """The RAOs x̂ (n_j, n_q) of every sea's components with the loads' quadratic drag on the
    relative flow linearised stochastically for that sea (:func:`mfm.frequency.drag.linearise`):
    Z(ω) and F(ω, β) made once per distinct (β, ω) pair of the seas (one per heading), the fixed
    point per sea. Returns (one array per sea, the number of distinct pairs, {"C" (B, P, 3, 3),
    "sigma" (B, P, 3), "iterations" (B,), "change" (B,)})."""
    from hydro.wetted import velocity_transfer

    from ..frequency.drag import TOL, linearise
    from ..frequency.response import _system

    n = model.n_coordinates
    union, inverse, bounds = component_union(comps_list)
    Zu = np.zeros((len(union), n, n), dtype=complex)
    Fu = np.zeros((len(union), n), dtype=complex)
    for beta in np.unique(union[:, 0]):
        sel = union[:, 0] == beta
        Zu[sel], Fu[sel] = _system(model, sys, union[sel, 1], float(beta), options)
    depth = float(model.hydro.water_depth)
    xs, C, sigma, its, change = [], [], [], [], []
    for i, cm in enumerate(comps_list):
        idx = inverse[bounds[i]:bounds[i + 1]]
        U = [velocity_transfer(g.positions, cm.omega, cm.wavenumber, cm.heading, depth)
             if g.flow else np.zeros((len(cm.omega), len(g.positions), 3), dtype=complex)
             for g in groups]
        lin = linearise(groups, Zu[idx], Fu[idx], cm.omega, cm.amplitude, U)
        if lin.change > TOL:
            warnings.warn(f"case {i}: the stochastic drag linearisation's fixed point did not "
                          f"converge in {lin.iterations} iterations (last relative change of C "
                          f"{lin.change:.3g} > {TOL:g}); its answer is the last iterate",
                          RuntimeWarning, stacklevel=3)
        xs.append(lin.x)
        C.append(lin.C)
        sigma.append(lin.sigma)
        its.append(lin.iterations)
        change.append(lin.change)
    return xs, len(union), {"C": np.array(C), "sigma": np.array(sigma),
                            "iterations": np.array(its), "change": np.array(change)}
