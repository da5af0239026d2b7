"""Model no more than a scene needs: the fidelity ladder and :func:`reduce`, which picks its
cheapest level whose answer stays within a tolerance of the full model on the scene.

The levels, cheapest first:

- ``"spectral"``: the linear frequency-domain response summed over the sea's components
  (:func:`mfm.runner.spectral.spectral_response`), no time stepping. Linear about the equilibrium:
  quadratic drag linearised stochastically for the sea, no large rotations, no stops.
- ``"linear"``: the same linear model in the time domain (:func:`mfm.runner.linear.linear_response`):
  radiation by the state-space fit, the modes stepped exactly, the drag linearised as the spectral
  level's; it has the start-up transient and ramp that the spectral level's steady state has not.
- ``"fast"``: the full nonlinear model stepped once per step (``integrator="verlet"``) with the
  radiation states advanced exactly (``radiation="state_space_exact"``): second order in dt.
- ``"full"``: the full nonlinear model with RK4 and the engine's default radiation
  (``radiation="auto"``), linear potential flow: the reference of a model given with it.
- ``"sampled"``: for a model with ``[hydro] hydrostatics = "nonlinear"``, that level with its
  hull pressure sampled every few steps (ω h ≈ :data:`SAMPLED_OMEGA_H`; ``nonlinear_dt``,
  :class:`mfm.loads.water.HeldHulls`: the linear level's loads at every stage plus the pressure's
  excess over them, extrapolated between samples); 4–10× the linear step on M4 134 where the
  pressure at every stage is 85× (docs/nonlinear.md).
- ``"nonlinear"``: above linear potential flow, for a model loaded with ``[hydro] hydrostatics =
  "nonlinear"`` (its hulls) and/or ``drag_flow = "relative"`` (docs/nonlinear.md): "full" with the
  pressure on the instantaneous wetted hull (at every stage: a ``nonlinear_dt`` of the model is
  left out of the reference) and drag on the relative flow. Given such a model,
  :func:`reduce` takes it as the reference and runs the levels below on the same model with the
  linear water (the database's buoyancy, C_wp and excitation, drag on the body's velocity):
  whether linear potential flow is enough for the scene is measured, not assumed.

Within a level, ``options`` of :func:`reduce` pilots run-time simplifications of the model the
same way (:data:`OPTIONS`): ``"body_coupling"``, the model without the hydrodynamic interaction
between its bodies (the cross-body blocks of A∞, A(ω), B(ω) and K dropped, as
``mfm.load(path, body_coupling=False)``), at the chosen level; it is taken when the scene's outputs
stay within the tolerance of the full model with the model as given. What the options buy and cost
on M4 134 and the Stansby & Li semi-sub: docs/fidelity.md.

Whether a level holds is measured, not guessed: :func:`reduce` runs the full model and each cheaper
level on a pilot window of the scene (the same sea, the same components and phases, so the time
series agree sample by sample where the model is linear) and compares the scene's outputs — the
mean power of each PTO, the standard deviation of named coordinates, and the mean and standard
deviation of each catenary line's fairlead tension (every level reports it: the linear levels to
first order about the equilibrium, :meth:`mfm.loads.base.Load.linear_outputs`) — over the pilot's
settled part. A level is chosen when every output is within ``tolerance``; the cost is a pilot of the full
model, paid once for a scene that is then run long or swept.
"""
from __future__ import annotations

import dataclasses
import numbers
import time as _time
from dataclasses import dataclass, field

import numpy as np

from ..runner.linear import linear_response
from ..runner.spectral import spectral_response
from ..mechanics.model import Model
from ..runner.simulation import simulate
from ..validation import check_model, check_sea, finite_number

LEVELS = ("spectral", "linear", "fast", "full", "sampled", "nonlinear")
# the run options each time-domain level gives mfm.simulate
LEVEL_OPTIONS = {"fast": {"integrator": "verlet", "radiation": "state_space_exact"},
                 "full": {"integrator": "rk4", "radiation": "auto"},
                 "sampled": {"integrator": "rk4", "radiation": "auto"},
                 "nonlinear": {"integrator": "rk4", "radiation": "auto"}}
# the "sampled" level's interval between two samples of the hull pressure, as ω h at the scene's
# period (the nearest whole number of steps, at least 1): 4 steps at reduce's default 200 steps a
# period, where the extrapolation's error on M4 134 and the sphere in moderate seas is
# 1e-4–1e-3 of the every-stage run's range (docs/nonlinear.md)
SAMPLED_OMEGA_H = 0.125


def sampled_steps(steps_per_period: int) -> int:
    """The "sampled" level's steps between two samples: ω h ≈ :data:`SAMPLED_OMEGA_H`."""
    return max(1, int(round(SAMPLED_OMEGA_H * steps_per_period / (2 * np.pi))))


# the levels of linear potential flow: run on the model's linear water (linear_water)
LINEAR_LEVELS = ("spectral", "linear", "fast", "full")


def above_linear(model: Model) -> bool:
    """Whether ``model``'s water is above linear potential flow (nonlinear hydrostatics and
    Froude–Krylov, drag on the relative flow, or the second-order wave drift force)."""
    from ..loads.water import nonlinear, relative_drag, wave_drift

    return model.hydro is not None and (nonlinear(model.hydro) or relative_drag(model.hydro)
                                        or wave_drift(model.hydro))


def linear_water(model: Model) -> Model:
    """``model`` with the linear water: its spec without the nonlinear level's hulls and the wave
    drift, with drag on the body's velocity (the same database, bodies and options; the radiation's fits and
    kernels shared, as they do not depend on either)."""
    from ..loads.water import linear_spec

    if not above_linear(model):
        return model
    return dataclasses.replace(model, hydro=linear_spec(model.hydro))


# the within-level options reduce can pilot: name -> the HydroSpec options of the variant
OPTIONS = {"body_coupling": {"body_coupling": False}}


def variant_model(model: Model, variant: dict) -> Model:
    """``model`` with the hydro options of ``variant`` (values of :data:`OPTIONS`, merged; e.g.
    ``{"body_coupling": False}``) by :meth:`hydro.prepare.HydroSpec.replace`, and with
    ``"linear_water": True`` its linear water (:func:`linear_water`); the model itself when
    ``variant`` is empty; ``"nonlinear_dt"``: s, the hull pressure sampled that often, or None:
    at every stage (:func:`mfm.loads.water.sampled_spec`)."""
    variant = dict(variant)
    if variant.pop("linear_water", False):
        model = linear_water(model)
    if "nonlinear_dt" in variant:
        from ..loads.water import sampled_spec

        model = dataclasses.replace(model, hydro=sampled_spec(model.hydro,
                                                              variant.pop("nonlinear_dt")))
    if not variant:
        return model
    return dataclasses.replace(model, hydro=model.hydro.replace(**variant))


def _sea_period(sea, period):
    if period is not None:
        return period
    for name in ("tp", "period"):
        v = getattr(sea, name, None)
        if isinstance(v, numbers.Real):
            return float(v)
    raise ValueError(f"sea: {sea!r} has no peak period (tp) or period; give period= (s), the "
                     "period that sets the pilot's length and time step")


@dataclass(frozen=True)
class Reduction:
    """The answer of :func:`reduce`.

    level: the chosen level (one of :data:`LEVELS`). options: what :func:`mfm.simulate` is given
    for it (empty for "spectral" and "linear"). errors: {level: {output: relative error against
    the reference ("full", or "nonlinear" for a model given above linear)}} on the pilot. wall_s: {level: s} the warm wall time of each level on the pilot.
    reason: why this level, in words. tolerance, dt, pilot: the settings of the measurement.
    variant: the hydro options of the within-level variant taken (``{"body_coupling": False}``;
    empty when none was asked for or none held; ``{"linear_water": True}`` where a linear level
    was chosen for a model given above linear); :meth:`run` applies it (:func:`variant_model`).
    variant_errors, variant_wall_s: {option: {output: error}} and {option: s} of each option
    piloted at the chosen level, against the same full model.
    """
    level: str
    options: dict
    errors: dict
    wall_s: dict
    reason: str
    tolerance: float
    dt: float
    pilot: tuple = field(default=())
    variant: dict = field(default_factory=dict)
    variant_errors: dict = field(default_factory=dict)
    variant_wall_s: dict = field(default_factory=dict)

    def run(self, model: Model, sea, *, duration: float, ramp: float | None = None):
        """Run the scene at the chosen level: a dataset with ``time``, ``q``, ``qd`` and
        ``pto_power`` whichever the level (spectral: synthesised on the same time grid; no ramp,
        its response is the steady state; linear: from rest at the equilibrium, with the ramp)."""
        duration = finite_number(duration, "duration", positive=True)
        model = variant_model(model, self.variant)
        if self.level == "spectral":
            t = self.dt * np.arange(int(round(duration / self.dt)) + 1)
            return spectral_response(model, sea, t=t)
        ramp = self.pilot[1] if ramp is None else ramp
        if self.level == "linear":
            return linear_response(model, sea, duration=duration, dt=self.dt, ramp=ramp)
        return simulate(model, sea, duration=duration, dt=self.dt, ramp=ramp, **self.options)


# what the loads record that every level reports (mfm.loads.base.Load.linear_outputs): each
# one's mean and standard deviation over the window, per element (a catenary line's fairlead
# tension)
LOAD_OUTPUTS = ("fairlead_tension",)


def _measures(ds, window, coordinates):
    """Mean power per PTO (W), the standard deviation of named coordinates, and each element's
    mean and standard deviation of the loads' outputs (:data:`LOAD_OUTPUTS`) over the window."""
    sel = ds.sel(time=window)
    out = {f"pto_power[{p}]": float(sel.pto_power.sel(pto=p).mean()) for p in
           ds.pto.values} if "pto_power" in ds else {}
    for c in coordinates:
        out[f"std[{c}]"] = float(sel.q.sel(coordinate=c).std())
    for name in LOAD_OUTPUTS:
        if name in ds:
            y = sel[name]
            (dim,) = (d for d in y.dims if d != "time")
            for k in y[dim].values:
                out[f"mean[{name}[{k}]]"] = float(y.sel({dim: k}).mean())
                out[f"std[{name}[{k}]]"] = float(y.sel({dim: k}).std())
    return out


def _errors(measured, reference):
    """Relative errors: each PTO against the total mean power (a PTO that absorbs little does not
    inflate the error), each coordinate's standard deviation and each load output's mean against
    its own, each load output's standard deviation against the largest of that output's (a line
    the sea hardly moves does not inflate it). A measure the reference has and the level lacks
    is an error: the level does not report it."""
    total = sum(abs(v) for k, v in reference.items() if k.startswith("pto_power")) or 1.0
    spread = {}
    for k, v in reference.items():
        for name in LOAD_OUTPUTS:
            if k.startswith(f"std[{name}["):
                spread[name] = max(spread.get(name, 0.0), abs(v))
    out = {}
    for k, ref in reference.items():
        if k not in measured:
            raise ValueError(f"reduce: the level's answer has no {k!r}, which the reference has")
        scale = abs(ref) or 1.0
        if k.startswith("pto_power"):
            scale = total
        for name in LOAD_OUTPUTS:
            if k.startswith(f"std[{name}["):
                scale = spread[name] or 1.0
        out[k] = abs(measured[k] - ref) / scale
    return out


def reduce(model: Model, sea, *, tolerance: float = 0.02, coordinates=(), period=None,
           pilot_periods: float = 40.0, settle_periods: float = 15.0,
           steps_per_period: int = 200, levels=LEVELS, timing: bool = True,
           options=()) -> Reduction:
    """The cheapest level of the fidelity ladder (module docstring) whose mean PTO powers,
    coordinate standard deviations and catenary lines' fairlead tensions (mean and standard
    deviation of each) stay within ``tolerance`` of the full model on a pilot run of the scene.

    model: a Model with hydrodynamics; sea: its sea state (:mod:`hydro.waves`).
    tolerance: the largest relative error accepted (0.02 = 2 %): each PTO's mean power against the
    total mean power, each named coordinate's standard deviation against its own, each line's
    mean tension against its own and its standard deviation against the largest line's.
    coordinates: coordinate names whose standard deviation counts too (free coordinates without
    restoring drift in the time domain and should not be named).
    period: s, the scene's period (default the sea's ``tp`` or ``period``); the pilot runs
    ``pilot_periods`` periods at dt = period / ``steps_per_period`` with a ramp of 5 periods, and
    compares the part after ``settle_periods`` periods.
    levels: the levels to consider (the reference is always run: "nonlinear" for a model given
    above linear potential flow, whose other levels run on its linear water; else "full").
    timing: run each level a second time for its warm wall time (compiled, fitted: what a long
    run or a sweep pays per run), reported in ``wall_s`` and the reason; False runs each once and
    reports no times.
    options: names of :data:`OPTIONS` to pilot at the chosen level, each on its own: an option is
    taken when its outputs stay within ``tolerance`` of the full model (the errors are those of
    the level and the option together; with ``timing``, also only when it is faster than the
    level without it); the variant taken is ``reduction.variant``, each option's errors and time
    in ``variant_errors`` and ``variant_wall_s``, why in the reason. ``"body_coupling"`` needs a
    model whose bodies are coupled (more than one hydro body, ``body_coupling`` on).

    Returns a :class:`Reduction`; ``reduction.run(model, sea, duration=...)`` runs the scene at the
    chosen level. Refuses a cheaper level (returns "full", saying why) when none is within the
    tolerance, e.g. large motions where the linear answer is wrong.
    """
    model = check_model(model)
    tolerance = finite_number(tolerance, "tolerance", positive=True)
    if model.hydro is None:
        raise ValueError(f"model {model.name!r} has no hydrodynamics: the fidelity ladder is that "
                         "of a floating model in a sea")
    check_sea(sea, still_water=False)
    levels = tuple(levels)
    bad = [lv for lv in levels if lv not in LEVELS]
    if bad or not levels:
        raise ValueError(f"levels: {levels!r}; accepted: a non-empty subset of {LEVELS}")
    # the reference: the model as given, "nonlinear" when its water is above linear potential
    # flow (the levels below then run on its linear water), else "full"
    top = "nonlinear" if above_linear(model) else "full"
    if top == "full":
        levels = tuple(lv for lv in levels if lv != "nonlinear")
    from ..loads.water import nonlinear as _has_hulls

    hulls = _has_hulls(model.hydro)
    if not hulls:       # the sampled level samples the hulls' pressure
        levels = tuple(lv for lv in levels if lv != "sampled")
    names = list(model.coordinates)
    bad = [c for c in coordinates if c not in names]
    if bad:
        raise ValueError(f"coordinates: {bad} are not coordinates of {model.name!r}; accepted: "
                         f"{names}")
    if isinstance(options, str):
        options = (options,)
    options = tuple(options)
    bad = [o for o in options if o not in OPTIONS]
    if bad or len(set(options)) != len(options):
        raise ValueError(f"options: {options!r}; accepted: distinct names of {tuple(OPTIONS)}")
    if "body_coupling" in options and (not model.hydro.body_coupling
                                       or len(model.hydro.db_names) < 2):
        raise ValueError(f"options: 'body_coupling': model {model.name!r} has no coupling between "
                         f"hydro bodies to drop ({len(model.hydro.db_names)} hydro bodies, "
                         f"body_coupling={model.hydro.body_coupling})")
    T = finite_number(_sea_period(sea, period), "period", positive=True)
    pilot_periods = finite_number(pilot_periods, "pilot_periods", positive=True)
    settle_periods = finite_number(settle_periods, "settle_periods", positive=True)
    if settle_periods >= pilot_periods:
        raise ValueError(f"settle_periods: {settle_periods} must be less than pilot_periods "
                         f"({pilot_periods}): nothing would be compared")
    if isinstance(steps_per_period, bool) or not isinstance(steps_per_period, numbers.Integral) \
            or steps_per_period < 10:
        raise ValueError(f"steps_per_period: {steps_per_period!r}; give a whole number ≥ 10")
    dt = T / int(steps_per_period)
    duration, ramp = pilot_periods * T, 5.0 * T
    window = slice(settle_periods * T, None)

    def with_water(level, variant=None):
        # the linear levels of a model given above linear run on its linear water
        out = dict(variant or {})
        if top == "nonlinear" and level in LINEAR_LEVELS:
            out["linear_water"] = True
        elif level == "sampled":
            out["nonlinear_dt"] = sampled_steps(steps_per_period) * dt
        elif level == "nonlinear" and hulls:
            out["nonlinear_dt"] = None      # the reference: the pressure at every stage
        return out

    def timed(level, variant=None):
        fn = lambda: Reduction(level, LEVEL_OPTIONS.get(level, {}), {}, {}, "", tolerance, dt,  # noqa: E731
                               (duration, ramp), with_water(level, variant)).run(
                                   model, sea, duration=duration)
        ds = fn()
        if not timing:
            return ds, None
        start = _time.perf_counter()
        fn()
        return ds, _time.perf_counter() - start

    ref, wall_full = timed(top)
    reference = _measures(ref, window, coordinates)
    errors, wall = {top: {k: 0.0 for k in reference}}, {top: wall_full}
    for level in [lv for lv in LEVELS if lv in levels and lv != top]:
        ds, wall[level] = timed(level)
        errors[level] = _errors(_measures(ds, window, coordinates), reference)
    within = [lv for lv in LEVELS if lv in errors and max(errors[lv].values(), default=0.0) <= tolerance]
    level = within[0]
    worst = {lv: max(errors[lv].values(), default=0.0) for lv in errors}
    if level == top:
        reason = ("no cheaper level within the tolerance: " + ", ".join(
            f"{lv} {worst[lv]:.3g}" for lv in errors if lv != top) + f" > {tolerance:g}")
        if top == "nonlinear":
            reason += " (linear potential flow is not enough for this scene)"
    else:
        reason = (f"{level}: largest error {worst[level]:.3g} ≤ {tolerance:g} on a pilot of "
                  f"{pilot_periods:g} periods")
        if timing:
            reason += f", {wall_full / wall[level]:.3g}× faster than {top}"
        refused = [lv for lv in LEVELS[:LEVELS.index(level)] if lv in errors]
        if refused:
            reason += "; refused: " + ", ".join(f"{lv} {worst[lv]:.3g} > {tolerance:g}"
                                                for lv in refused)
    variant, v_errors, v_wall, notes = {}, {}, {}, []
    for name in options:
        ds, v_wall[name] = timed(level, OPTIONS[name])
        v_errors[name] = _errors(_measures(ds, window, coordinates), reference)
        worst_v = max(v_errors[name].values(), default=0.0)
        text = f"{name} off at {level}: largest error {worst_v:.3g}"
        if timing:
            text += f", {v_wall[name]:.3g} s against {wall[level]:.3g} s"
        if worst_v > tolerance:
            notes.append(f"{text} > {tolerance:g}: refused")
        elif timing and v_wall[name] >= wall[level]:
            notes.append(f"{text}: within {tolerance:g} but no faster: refused")
        else:
            variant.update(OPTIONS[name])
            notes.append(f"{text} ≤ {tolerance:g}: taken")
    if notes:
        reason += "; options: " + "; ".join(notes)
    if not timing:
        wall, v_wall = {}, {}
    return Reduction(level, LEVEL_OPTIONS.get(level, {}), errors, wall, reason, tolerance, dt,
                     (duration, ramp), with_water(level, variant), v_errors, v_wall)
