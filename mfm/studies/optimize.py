"""Design by gradient: the PTO, mooring and ballast values that maximise an objective of a model's
response, with exact derivatives of the very linearisation the engine simulates.

The spectral responses as a pure jax function of named parameters are :mod:`mfm.studies.design`;
the objective J(θ) = Σ_s w_s P_s / Σ_s w_s (mean absorbed power, a scatter diagram's weights
w_s) or a user's function of those responses. An optimisation, a grid over parameters
(:func:`evaluate`) and another model with the same structure reuse one compilation.

Derivatives come from jax: forward mode when the parameters are no more than the outputs
(objective and constraint values) or no more than :data:`FORWARD_UP_TO`, reverse mode otherwise,
for the cost of a jacobian is one pass per parameter (forward) or per output (reverse), and a
forward program of a few parameters compiled lighter where measured. The optimiser is SLSQP (scipy) on the
parameters scaled to [0, 1] by their bounds, with the constraints as inequalities in every sea.
The time domain confirms an optimum (``confirm=``): the optimised model stepped in the same seas
(:func:`mfm.simulate_batch`; :func:`mfm.simulate` per sea for hydraulic pistons), its mean power
against the spectral prediction. The equilibrium q₀(θ) of every evaluated point must balance the
loads to EQUILIBRIUM_TOL (1e-6) of the largest weight (:func:`mfm.studies.design._newton`, damped):
a point without one raises :class:`~mfm.errors.OptimizeError` (``evaluate``: NaN there). From the
command line: ``mfm optimize`` (:func:`mfm.io.cli.cmd_optimize`).
"""
from __future__ import annotations

import functools
import math
import time as _time
from types import SimpleNamespace
from typing import Callable

import jax
import jax.numpy as jnp
import numpy as np
import xarray as xr
from hydro.seabatch import components_many

from .. import host, results
from ..backend import device_array
from ..errors import OptimizeError
from ..frequency.rest import (_equilibrium, _static_functions, linear_hydro, linear_hydro_index,
                              system_loads)
from ..runner.spectral import component_union
from ..loads.base import Load
from ..loads.catenary import CatenaryLines
from ..loads.hydraulic_pto import HydraulicPTO
from ..mechanics.kinematics import kinematics
from ..mechanics.model import Model
from ..validation import check_model, check_seas
from .design import (EQUILIBRIUM_TOL, KINDS, Limit, Problem, Response,  # noqa: F401
                     _constraint_values, _limits, _targets, _unknown, _value_of, apply, mean_power,
                     responses, tunable_parameters)

TRACES = {"outputs": 0}      # how often the objective was traced (tests: one per structure)


def _outputs(pb, u, lower, upper, limits, scale, objective, spec):
    """[J(θ)/scale, 1 − value/limit for each limit and sea] at θ = lower + u (upper − lower), and
    the responses there."""
    r = responses(pb, lower + u * (upper - lower))
    g = 1.0 - _constraint_values(r, spec) / limits[:, None]
    out = jnp.concatenate([jnp.atleast_1d(objective(r)) / scale, g.reshape(-1)])
    return out, (out, r)


# "auto" derivatives are forward mode up to this many parameters, whatever the outputs
FORWARD_UP_TO = 4


@functools.partial(jax.jit, static_argnames=("objective", "spec", "forward"))
def _evaluate(pb, u, lower, upper, limits, scale, objective, spec, forward):
    """(outputs, their jacobian in u (n_out, n_par), the responses): one compilation per
    structure of the problem, objective and limits (their numbers are arguments). Forward mode
    costs one pass per parameter, reverse one per output."""
    TRACES["outputs"] += 1
    jac = jax.jacfwd if forward else jax.jacrev
    J, (out, r) = jac(_outputs, argnums=1, has_aux=True)(pb, u, lower, upper, limits, scale,
                                                         objective, spec)
    return out, J, r


# ------------------------------------------------------------------------------- the front door
def _parameters(model, parameters, table):
    """[(label, (Target, …), lower, upper)] from the user's dict name or tuple of names → (lower,
    upper); a tuple of names is one design value shared by them (e.g. one damping for all WECs)."""
    if not isinstance(parameters, dict) or not parameters:
        raise TypeError(f"parameters: {parameters!r}; give a dict name → (lower, upper), names "
                        "from mfm.studies.optimize.tunable_parameters(model), e.g. "
                        "{'float3.angle.damping': (0.0, 50.0)}")
    out, seen = [], set()
    for key, bounds in parameters.items():
        names = (key,) if isinstance(key, str) else tuple(key)
        for n in names:
            if not isinstance(n, str) or n not in table:
                raise KeyError(_unknown(n, table))
            if n in seen:
                raise ValueError(f"parameters: {n!r} is given twice; each parameter once")
            seen.add(n)
        try:
            lo, hi = (float(b) for b in bounds)
        except (TypeError, ValueError):
            raise ValueError(f"parameters[{key!r}]: {bounds!r}; give bounds (lower, upper)") from None
        if not (math.isfinite(lo) and math.isfinite(hi)) or not lo < hi:
            raise ValueError(f"parameters[{key!r}]: bounds ({lo!r}, {hi!r}); give finite bounds "
                             "with lower < upper (the optimiser works on [0, 1] between them)")
        out.append((" + ".join(names), tuple(table[n][0] for n in names), lo, hi,
                    tuple(table[n][2] for n in names)[0]))
    return out


@jax.jit
def _kinematics_at_rest(model):
    """The kinematics at q = q̇ = 0."""
    zero = jnp.zeros(model.n_coordinates)
    return kinematics(model, zero, zero)


def _sea_union(model, seas, lds, radiation, state_space_options):
    """ω (U,), a² (S, U), Zb (U, 6K, 6K), X (U, 6K) on the union of the seas' (β, ω) pairs."""
    comps = components_many(seas, water_depth=model.hydro.water_depth, g=model.hydro.g)
    union, inverse, bounds = component_union(comps)
    a2 = np.zeros((len(seas), len(union)))
    for s, c in enumerate(comps):
        np.add.at(a2[s], inverse[bounds[s]:bounds[s + 1]], c.amplitude ** 2)
    water = linear_hydro(lds)
    args = (model.keyed(),)
    # compiled, once per structure (op by op, the tree walk was ~190 small compilations: ~3 s of
    # CPU of every first optimum, cached or not)
    kin = host.current().program(_kinematics_at_rest, "kinematics_at_rest", args, once=True)(*args)
    options = {"radiation": radiation, "state_space_options": state_space_options}
    nd = 6 * len(water.geometry.body_index)
    Zb = np.zeros((len(union), nd, nd), complex)
    X = np.zeros((len(union), nd), complex)
    for beta in np.unique(union[:, 0]):
        sel = union[:, 0] == beta
        om = union[sel, 1]
        A_rel, B, Xb, _ = water.coefficients(kin, om, float(beta), options)
        Zb[sel] = -om[:, None, None] ** 2 * A_rel - 1j * om[:, None, None] * B
        X[sel] = Xb
    return union[:, 1].copy(), a2, Zb, X, water


def _setup(model, seas, parameters, objective, constraints, weights, loads, radiation,
           state_space_options, drag_iterations, derivatives):
    """The checked request as the compiled objective takes it (a namespace: the Problem ``pb``,
    the parameters' labels, bounds and baseline, the limits, the objective function, …)."""
    model = check_model(model)
    if model.hydro is None:
        raise ValueError(f"model {model.name!r} has no hydrodynamics: optimize works on the sea's "
                         "response; give a config with a [hydro] table")
    seas = check_seas(seas)
    S = len(seas)
    w = np.ones(S) if weights is None else np.asarray(weights, dtype=float).reshape(-1)
    if w.shape != (S,) or not np.all(np.isfinite(w)) or np.any(w < 0) or w.sum() <= 0:
        raise ValueError(f"weights: {weights!r}; give {S} finite weights ≥ 0, not all 0 (one per sea)")
    if derivatives not in ("auto", "forward", "reverse"):
        raise ValueError(f"derivatives: {derivatives!r}; give 'auto', 'forward' or 'reverse'")
    if isinstance(objective, str):
        if objective != "power":
            raise ValueError(f"objective: {objective!r}; give 'power' or a function of a Response")
        objective_fn = mean_power
    elif callable(objective):
        objective_fn = objective
    else:
        raise TypeError(f"objective: {objective!r}; give 'power' or a function of a Response")

    lds = system_loads(model, loads)
    table, _ = _targets(model, lds)
    params = _parameters(model, parameters, table)
    kmodel, static, mems = _static_functions(model, lds)
    hydraulic = [i for i, ld in enumerate(static) if isinstance(ld, HydraulicPTO)]
    if len(hydraulic) > 1:
        raise NotImplementedError("optimize: more than one hydraulic PTO load; put the pistons "
                                  "in one [[hydraulic_ptos]] table")
    others = [type(ld).__name__ for ld in static if not isinstance(ld, HydraulicPTO)
              and type(ld).linear_dampers is not Load.linear_dampers]
    if others:
        raise NotImplementedError(f"optimize: loads {others} add PTOs the spectral objective does "
                                  "not know yet")
    water_index = linear_hydro_index(static)
    # the joint PTOs: the coordinates damped now, and those whose damping is tuned
    tuned = {t.index for _, grp, *_ in params for t in grp if t.where == "model" and t.field == "damping"}
    joint = tuple(sorted({int(k) for k in np.flatnonzero(np.asarray(model.damping) > 0)} | tuned))
    pto_names = [model.coordinates[k] for k in joint]
    if hydraulic:
        pto_names += list(static[hydraulic[0]].names)
    lines = tuple(i for i, ld in enumerate(static) if isinstance(ld, CatenaryLines))
    line_names = [n for i in lines for n in static[i].names]
    limits = _limits(constraints, model.coordinates, pto_names, line_names)

    def where(lm):
        if lm.quantity in model.coordinates:
            return ("q", model.coordinates.index(lm.quantity), KINDS[lm.kind], False)
        if lm.quantity in pto_names:
            return ("pto", pto_names.index(lm.quantity), KINDS[lm.kind], False)
        return ("tension", line_names.index(lm.quantity[:-len(".tension")]), KINDS[lm.kind],
                lm.kind == "peak")
    spec = tuple(where(lm) for lm in limits)
    q0, _ = _equilibrium(model, lds)
    omega, a2, Zb, X, water = _sea_union(model, seas, lds, radiation, state_space_options)
    drag = np.zeros(Zb.shape[1])
    D = np.asarray(water.drag)                           # (K, 3) on the translations
    drag.reshape(-1, 6)[:, :3] = D
    dev = device_array          # numpy onto the device without a compiled conversion each
    pb = Problem(kmodel, static, mems, dev(q0), dev(omega), dev(a2), dev(Zb), dev(X), dev(drag),
                 dev(w),
                 tuple(grp for _, grp, *_ in params), joint,
                 hydraulic[0] if hydraulic else -1, water_index,
                 int(drag_iterations) if np.any(drag > 0) else 0, lines,
                 control=dev(np.zeros(model.n_coordinates)))

    labels = [p[0] for p in params]
    lower = np.array([p[2] for p in params])
    upper = np.array([p[3] for p in params])
    baseline = np.array([_value_of(kmodel, static, p[1][0]) for p in params])
    n_out = 1 + len(limits) * S
    # forward also for a few parameters whatever the outputs: its program compiled lighter where
    # measured, for the same optimum (2 parameters, 1 output: Hallak's β, κ 46 against 60 s of
    # CPU, Stansby & Li's two dampings 23 against 27 s)
    forward = derivatives == "forward" or (derivatives == "auto"
                                           and len(params) <= max(n_out, FORWARD_UP_TO))
    lo_j, hi_j = device_array(lower), device_array(upper)
    lim_j = device_array(np.asarray([lm.limit for lm in limits], float).reshape(-1))
    return SimpleNamespace(model=model, seas=seas, S=S, w=w, objective_fn=objective_fn, lds=lds,
                           params=params, pb=pb, pto_names=pto_names, limits=limits, spec=spec,
                           labels=labels, lower=lower, upper=upper, baseline=baseline,
                           forward=forward, lo_j=lo_j, hi_j=hi_j, lim_j=lim_j)


def _check_equilibrium(P, r, values, last_good):
    """Raise :class:`OptimizeError` when the equilibrium Newton of :func:`mfm.studies.design.
    responses` stopped with max|Q(q₀)| above EQUILIBRIUM_TOL of the force scale: the response
    there would be the linearisation about a point that is no equilibrium."""
    res = float(r.equilibrium_residual)
    if res <= EQUILIBRIUM_TOL:        # NaN fails this too
        return
    q0 = dict(zip(P.model.coordinates, np.round(np.asarray(r.q0, dtype=float), 6).tolist()))
    raise OptimizeError(
        f"optimize: no static equilibrium at {values}: the damped Newton stopped at max|Q(q0)| = "
        f"{res:.3g} of the largest weight (accepted: <= {EQUILIBRIUM_TOL:g}), at q0 = {q0}. A mass "
        "its buoyancy cannot carry sinks, a centre of mass too high or a negative stiffness past "
        "the restoring capsizes, a mooring or joint stiffness out of range leaves no balance: "
        "narrow the bounds of the parameters that move the equilibrium (stiffness, mass, kappa, "
        f"mooring k). The last point with an equilibrium was {last_good}.", last_good=last_good)


def _run(P, u, scale):
    """(outputs, jacobian, responses) of the request at scaled parameters u, as numpy. The
    compiled objective is the host's program (:meth:`mfm.host.Host.program`; the runner's: from
    disk where an earlier process traced it, so that a later process neither traces nor lowers
    it: Stansby & Li's two dampings, ~4 s of CPU of a cached first optimum). Its arguments are
    put on the device as numpy (:func:`mfm.backend.device_array`): ``jnp.asarray`` of a new
    shape compiles a small program of its own."""
    args = (P.pb, device_array(u, np.float64), P.lo_j, P.hi_j, P.lim_j,
            device_array(scale, np.float64))
    static = dict(objective=P.objective_fn, spec=P.spec, forward=P.forward)
    out, J, r = host.current().program(_evaluate, "optimize_evaluate", args, static)(*args)
    return np.asarray(out), np.asarray(J), jax.tree_util.tree_map(np.asarray, r)


def optimize(model: Model, seas, parameters: dict, *, objective: Callable | str = "power",
             constraints: dict | None = None, weights=None, x0: dict | None = None,
             loads=None, radiation: str = "database", state_space_options: dict | None = None,
             drag_iterations: int = 40, derivatives: str = "auto", max_iter: int = 100,
             tol: float = 1e-9, confirm: dict | None = None) -> xr.Dataset:
    """Tune ``parameters`` of ``model`` to maximise ``objective`` over ``seas`` at the spectral
    level (the equations of :mod:`mfm.studies.design`), optionally confirmed in the time domain.

    parameters: dict name → (lower, upper), names of :func:`tunable_parameters` (e.g.
        ``"float3.angle.damping"``, ``"float.stroke.control_stiffness"`` (a controller's spring
        about the equilibrium; negative: reactive control), ``"float.stroke.stiffness"`` (the
        joint spring about the config's rest: it moves the equilibrium),
        ``"pto.beta"``, ``"platform.mass"``, ``"mooring0.kx"``); a tuple of names as the key is
        one value shared by them (one damping for every WEC).
    seas: a sea state of :mod:`hydro.waves` or a sequence; ``weights`` (S,) ≥ 0 their weights
        (a scatter diagram's probabilities or hours; default equal).
    objective: "power" (Σ_s w_s P_s, W, the weighted mean absorbed power of every PTO) or a
        function of a :class:`Response` returning a scalar to maximise, written with jax.numpy
        (e.g. ``lambda r: mean_power(r) - 1e6 * jnp.max(r.q_rms[:, 4])``).
    constraints: dict quantity → {"rms": limit} or {"significant": limit} (m or rad) for a
        coordinate (``"platform.pitch"``) or a PTO's stroke (its name), to hold in every sea.
    x0: starting values by name (default: the model's own, clipped to the bounds).
    loads, radiation, state_space_options: as :func:`mfm.frequency_response`.
    drag_iterations: fixed-point iterations of the stochastic drag linearisation (when the water
        has drag). derivatives: "auto" (forward when parameters ≤ outputs or ≤ 4, else reverse),
        "forward" or "reverse". max_iter, tol: SLSQP's.
    confirm: None, or options of :func:`mfm.simulate_batch` (``dt``, ``n_steps`` required;
        ``integrator``, ``radiation``, ``ramp``, …; ``settle`` s discarded before averaging,
        default half the run): the optimised model in the same seas, its mean power against the
        spectral prediction (``time_domain_*`` variables, the relative difference printed).

    Returns an xarray.Dataset: over ``parameter`` ``optimum``, ``baseline`` (the model's values),
    ``lower``, ``upper``, ``at_bound`` ("lower", "upper" or ""), ``gradient`` (dJ/dθ at the optimum,
    objective units per parameter unit); ``objective``, ``objective_baseline``, ``gain`` (relative);
    over ``constraint`` ``constraint_value`` (the largest over the seas), ``constraint_value_baseline``,
    ``constraint_limit``, ``constraint_active``; over (case, pto) ``pto_power_mean`` and
    ``pto_power_mean_baseline`` (W), over (case, coordinate) ``q_rms``; ``iterations``,
    ``evaluations``, ``gradient_norm`` (of the projected gradient, scaled units); provenance.
    Raises KeyError naming an unknown parameter (with the tunable ones), ValueError for bounds,
    and :class:`~mfm.errors.OptimizeError` (with ``last_good``) when the objective goes
    non-finite or the constraints cannot be met.
    """
    start = _time.perf_counter()
    P = _setup(model, seas, parameters, objective, constraints, weights, loads, radiation,
               state_space_options, drag_iterations, derivatives)
    model, seas, S, w, objective_fn, lds, params = (P.model, P.seas, P.S, P.w, P.objective_fn,
                                                    P.lds, P.params)
    pb, pto_names, limits, spec, labels = P.pb, P.pto_names, P.limits, P.spec, P.labels
    lower, upper, baseline, forward = P.lower, P.upper, P.baseline, P.forward
    start_values = np.clip(baseline, lower, upper)
    if x0 is not None:
        for k, v in x0.items():
            if k not in labels:
                raise KeyError(f"x0: {k!r} is not one of the parameters {labels}")
            start_values[labels.index(k)] = float(v)
        if np.any(start_values < lower) or np.any(start_values > upper):
            raise ValueError(f"x0: {x0!r} lies outside the bounds {dict(zip(labels, zip(lower, upper)))}")

    def to_u(theta):
        return (np.asarray(theta) - lower) / (upper - lower)

    def point(u):
        return dict(zip(labels, (lower + np.asarray(u) * (upper - lower)).tolist()))

    def run(u, scale):
        return _run(P, u, scale)

    u_base = to_u(baseline)
    base_out, _, r_base = run(u_base, 1.0)
    _check_equilibrium(P, r_base, point(u_base), None)
    if not np.all(np.isfinite(base_out)):
        raise OptimizeError(f"optimize: the objective or constraints are not finite at the model's "
                            f"own values {point(u_base)}: {base_out.tolist()}", last_good=None)
    # the objective is scaled by its size for SLSQP (its tolerances are absolute); a model with
    # no damping absorbs nothing at its own values, so then the size at the middle of the bounds
    scale = abs(float(base_out[0]))
    if not scale > 0:
        mid = run(np.full(len(params), 0.5), 1.0)[0][0]
        scale = abs(float(mid)) if np.isfinite(mid) and mid != 0 else 1.0
    cache = {}
    last_good = {"u": u_base}      # finite: checked above

    def evaluate(u):
        """(outputs, jacobian, responses) at u, computed once per point (SLSQP asks for the
        value and the jacobian at the same points)."""
        key = np.asarray(u).tobytes()
        if key not in cache:
            out, J, r = run(u, scale)
            _check_equilibrium(P, r, point(u), point(last_good["u"]))
            if not (np.all(np.isfinite(out)) and np.all(np.isfinite(J))):
                good = point(last_good["u"])
                raise OptimizeError(
                    f"optimize: the objective, a constraint or a derivative went non-finite at "
                    f"{point(u)}: outputs {out.tolist()}; the last good point was {good}. A "
                    "parameter that removes all damping of a resonance, or a negative stiffness "
                    "past the restoring, makes the response unbounded: narrow the bounds.",
                    last_good=good)
            last_good["u"] = np.array(u)
            cache.clear()
            cache[key] = (out, J, r)
        return cache[key]

    from scipy.optimize import minimize

    cons = ([{"type": "ineq", "fun": lambda u: evaluate(u)[0][1:], "jac": lambda u: evaluate(u)[1][1:]}]
            if limits else [])
    res = minimize(lambda u: -evaluate(u)[0][0], to_u(start_values),
                   jac=lambda u: -evaluate(u)[1][0], method="SLSQP",
                   bounds=[(0.0, 1.0)] * len(params), constraints=cons,
                   options={"maxiter": int(max_iter), "ftol": float(tol)})
    u_opt = np.clip(res.x, 0.0, 1.0)
    out, J, r_opt = evaluate(u_opt)
    theta = lower + u_opt * (upper - lower)
    if limits and -out[1:].min() > 1e-6:
        values = np.asarray(_constraint_values(r_opt, spec)).max(axis=1)
        raise OptimizeError(
            "optimize: the constraints cannot be met within the bounds: at the end "
            + ", ".join(f"{lm.kind}({lm.quantity}) = {float(v):.4g} > {lm.limit:.4g}"
                        for lm, v in zip(limits, values) if v > lm.limit * (1 + 1e-6))
            + f" ({res.message}); widen the bounds or relax the limits. Last point: "
            + repr(point(u_opt)), last_good=point(u_opt))
    if pb.drag_iterations and float(r_opt.drag_change) > 1e-6:
        raise OptimizeError(f"optimize: the drag linearisation did not settle in {drag_iterations} "
                            f"iterations (last relative change {float(r_opt.drag_change):.2e}); "
                            "give more drag_iterations", last_good=point(u_opt))
    # the projected gradient: zero where a bound holds the parameter against its pull
    g = J[0].copy()
    g[(u_opt <= 1e-9) & (g < 0)] = 0.0
    g[(u_opt >= 1 - 1e-9) & (g > 0)] = 0.0
    at_bound = np.where(u_opt <= 1e-6, "lower", np.where(u_opt >= 1 - 1e-6, "upper", ""))
    con_opt = np.asarray(_constraint_values(r_opt, spec)).reshape(len(limits), S)
    con_base = np.asarray(_constraint_values(r_base, spec)).reshape(len(limits), S)
    obj = float(out[0] * scale)
    obj_base = float(base_out[0])
    confirm_out = None
    if confirm is not None:
        confirm_out = _confirm(model, seas, dict(zip(labels, theta)), params, w, r_opt, confirm)
    from ..radiation import label as radiation_label

    settings = dict(level="spectral", seas=repr(seas), radiation=radiation_label(radiation),
                    method="SLSQP",
                    derivatives="forward" if forward else "reverse", max_iter=int(max_iter),
                    tol=float(tol), message=str(res.message), success=bool(res.success),
                    objective=("mean absorbed power" if objective_fn is mean_power
                               else getattr(objective_fn, "__name__", repr(objective_fn))),
                    drag_linearisation=("stochastic (Borgman), c_eq = D sqrt(8/pi) sigma_v"
                                        if pb.drag_iterations else "none (no drag)"))
    return results.optimum(
        model, lds, seas, labels=labels, units=[p[4] for p in params], optimum=theta,
        baseline=baseline, lower=lower, upper=upper, at_bound=at_bound,
        gradient=J[0] * scale / (upper - lower), objective=obj, objective_baseline=obj_base,
        limits=limits, con_opt=con_opt, con_base=con_base, pto_names=pto_names,
        power=r_opt.power, power_base=r_base.power, q_rms=r_opt.q_rms,
        iterations=int(res.nit), evaluations=int(res.nfev), gradient_norm=float(np.linalg.norm(g)),
        confirm=confirm_out, settings=settings, start=start)


def evaluate(model: Model, seas, points: dict, *, objective: Callable | str = "power",
             constraints: dict | None = None, weights=None, loads=None,
             radiation: str = "database", state_space_options: dict | None = None,
             drag_iterations: int = 40) -> dict:
    """The objective and the constraint values of :func:`optimize` at given parameter values,
    through the same compiled function (a grid over parameters, a landscape to chart, the check
    of an optimum): ``points`` name (or tuple of names) → values (N,) (all of one length N).

    Returns dict: ``objective`` (N,), ``constraints`` (N, n_limits) their largest value over the
    seas (m or rad), ``power`` (N, S, P) W, ``q_rms`` (N, S, n_q), ``equilibrium_residual`` (N,)
    (max|Q(q₀)| over the force scale); at a point whose residual exceeds EQUILIBRIUM_TOL (no
    equilibrium reached) every value is NaN, not the linearisation about a point that is none."""
    if not isinstance(points, dict) or not points:
        raise TypeError(f"points: {points!r}; give a dict name → values (N,)")
    arrays = {k: np.atleast_1d(np.asarray(v, dtype=float)) for k, v in points.items()}
    N = {a.shape for a in arrays.values()}
    if len(N) != 1 or len(next(iter(N))) != 1:
        raise ValueError(f"points: shapes {[a.shape for a in arrays.values()]}; give 1-D arrays "
                         "of one length")
    # bounds only scale the parameters; any span holding the points does
    bounds = {k: (float(a.min()) - 1.0, float(a.max()) + 1.0) for k, a in arrays.items()}
    P = _setup(model, seas, bounds, objective, constraints, weights, loads, radiation,
               state_space_options, drag_iterations, "auto")
    theta = np.stack([arrays[k] for k in points], axis=1)
    objective_v, cons, power, q_rms, residual = [], [], [], [], []
    for row in theta:
        out, _, r = _run(P, (row - P.lower) / (P.upper - P.lower), 1.0)
        res = float(r.equilibrium_residual)
        bad = np.nan if not res <= EQUILIBRIUM_TOL else 1.0      # NaN × a value: no equilibrium
        objective_v.append(out[0] * bad)
        cons.append(np.asarray(_constraint_values(r, P.spec)).reshape(len(P.limits), P.S).max(axis=1)
                    * bad)
        power.append(r.power * bad)
        q_rms.append(r.q_rms * bad)
        residual.append(res)
    return {"objective": np.array(objective_v), "constraints": np.array(cons),
            "power": np.array(power), "q_rms": np.array(q_rms),
            "equilibrium_residual": np.array(residual)}


def _confirm(model, seas, values, params, weights, r_opt, options):
    """The optimised model stepped in the same seas (Verlet with exact radiation unless
    ``options`` say otherwise): every PTO's mean power after ``settle`` against the spectral
    prediction. One :func:`mfm.simulate_batch` call for the seas; a model with hydraulic pistons
    runs :func:`mfm.simulate` per sea (a batch records joint dampers only)."""
    from ..runner.batch import simulate_batch
    from ..runner.simulation import simulate

    options = dict(options)
    if "dt" not in options or "n_steps" not in options:
        raise ValueError(f"confirm: {options!r}; give at least dt (s) and n_steps (the options of "
                         "mfm.simulate_batch), and settle (s) if not half the run")
    settle = options.pop("settle", None)
    opt_model = apply(model, {n: v for (label, grp, *_), v in zip(params, values.values())
                              for n in label.split(" + ")})
    options.setdefault("integrator", "verlet")
    options.setdefault("radiation", "state_space_exact")
    if any(isinstance(ld, HydraulicPTO) for ld in opt_model.loads):
        one = dict(options)
        n_steps = int(one.pop("n_steps"))
        runs = [simulate(opt_model, sea, duration=n_steps * float(one["dt"]), **one) for sea in seas]
        times = [np.asarray(ds.time.values) for ds in runs]
        powers = [np.asarray(ds.pto_power.values) for ds in runs]
    else:
        ds = simulate_batch(opt_model, seas, **options)
        times = list(np.asarray(ds.time.values))
        powers = list(np.asarray(ds.pto_power.values)) if "pto_power" in ds else \
            [np.zeros((len(t), 0)) for t in times]
    settle = 0.5 * float(times[0][-1] - times[0][0]) if settle is None else float(settle)
    power = np.stack([p[t >= t[0] + settle].mean(axis=0).sum() for t, p in zip(times, powers)])
    wn = weights / weights.sum()
    td = float(np.sum(wn * power))
    spectral = float(np.sum(wn * r_opt.power.sum(axis=1)))
    rel = (td - spectral) / abs(spectral) if spectral else math.nan
    print(f"optimize: time-domain mean power at the optimum {td:.6g} W against the spectral "
          f"{spectral:.6g} W: relative difference {rel:+.3%}")
    return {"power": power, "objective": td, "relative_difference": rel, "settle_s": settle,
            "options": repr(options)}
