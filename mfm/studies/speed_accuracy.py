"""The speed–accuracy chart of the engine (issue 14 item 1): for three systems, every integrator ×
time step, radiation models and fidelity levels, the error against a reference solution against
the warm wall time, with the Pareto front. The study (:func:`study`, a case at a time with
:func:`run_case`, :func:`spectral_case`, :func:`linear_case`, measured by :func:`measures` and
:func:`errors`), its figures and tables (:func:`figure`, :func:`table`, :func:`front_table`,
:func:`cheapest`). Needs a checkout (the configs in configs/). The command line is
tools/speed_accuracy.py (its docstring gives the commands and how long each takes).

Each system's cases go to notebooks/figures/speed_accuracy/<system>.json as they finish (a rerun
skips the cases already there: delete the file to start afresh), the figures to
notebooks/figures/speed_accuracy/<system>.png. notebooks/speed_accuracy.ipynb reads them and
reruns a small live slice through the same functions.

The grid (each distinct integrator, number of steps and radiation structure is a compilation of
10–60 s, so the grid is a sum of three slices rather than a product):

- ``integrators``: rk4, beeman, semi_implicit, newmark, verlet × dt = T/25, T/50, T/100, T/200,
  T/400 (fewer where the compilations did not fit the time: :data:`COARSE`), one radiation
  model for all: ``state_space_exact`` (the default fit, its states advanced exactly over a step:
  stable with every integrator, what verlet needs);
- ``radiation``: at RK4, dt = T/100: the convolution with memory windows of a few periods (T, 3T,
  10T) and the full T_K (from the decay of K), and the state space integrated by RK4
  (``state_space``) at two or three orders and the default (``order="auto"``);
- ``fidelity``: the levels of :mod:`mfm.studies.fidelity` at dt = T/200: spectral (no time
  stepping; statistics only, and the series on the run's grid), linear
  (:func:`mfm.linear_response`: the linearised model with the state-space fit, its modes stepped
  exactly), fast (verlet, ``state_space_exact``), full (rk4, ``radiation="auto"``). A level that
  refuses a system (an error naming why) is recorded as ``"refused"`` with the message.

The reference: RK4 at dt = T/800 with the state space integrated by RK4 (``state_space``, the
default fit). RK4 is the highest-order integrator; with the state space its radiation is
integrated at 4th order too (``state_space_exact`` advances it at 2nd order in the velocity's
interpolation, a floor of ≈ 1e-5 on M4, benchmarks/RESULTS.md), and the convolution with the full
memory at T/800 would cost hours on M4 (26,000 lags × 24² dofs per evaluation). Its own error is
checked by the same run at T/400 (``reference_check``: 4th order, so the reference's error is
≈ 1/16 of that). The fitted state space is itself an approximation of the Cummins integral (band
error 1 % on M4): the radiation slice is also compared with the full-memory convolution at its
own dt (``errors_vs_convolution``), which isolates the window and the fit.

The measures, over the settled part of the run (after ``settle`` periods), on the samples every
T/25 (every case saves there: the same estimator for all):

- ``std``: the largest relative error in the standard deviation of the named coordinates (the
  hinge angles' θ_rms for M4 and Stansby & Li; RM3's spar pitch and float stroke);
- ``power``: the relative error in the mean absorbed power Σ c_k q̇_k² of the joint dampers (the PTOs);
- ``series``: the relative L2 error of the time series of those coordinates,
  ‖x − x_ref‖ / ‖x_ref − mean x_ref‖.

Wall time: ``warm_s`` is the median of repeated warm calls (3 when a call is under 2 s, 2 under
5 s — RM3's rows: 10 s —, else 1; each row has its ``repeats``) of what a run costs once compiled: the loads for this sea and grid
(:func:`mfm.timedomain.setup.model_loads`: excitation tables, convolution weights, exact propagators) and
the compiled rollout (:func:`mfm.timedomain.rollout.rollout`, no per-sample outputs) to its last sample;
``compile_s`` is the first call's excess over it (tracing and XLA compilation; the state-space fit
is made before and cached). A run that goes non-finite is recorded as ``"non-finite"`` with the
time it stopped.
"""
from __future__ import annotations

import json
import math
import statistics
import time
import warnings
from pathlib import Path

import numpy as np

from .. import results
from ..runner import linear as _linear
from ..runner.spectral import spectral_response
from ..io.build import load
from ..timedomain.rollout import rollout
from ..runner.choices import choose_radiation
from ..timedomain.setup import model_loads

ROOT = Path(__file__).resolve().parents[2]      # the repository (configs/), in a checkout

INTEGRATORS = ("rk4", "beeman", "semi_implicit", "newmark", "verlet")
STEPS_PER_PERIOD = (25, 50, 100, 200, 400)
# the time steps per integrator where not all of STEPS_PER_PERIOD: on the shared machine (load
# 5–6) a compilation of M4 or Stansby & Li took ≈ 45 s and a warm M4 RK4 step 1.6 ms, so the
# schemes that are never on RM3's Pareto front (semi-implicit: first order; Newmark: implicit,
# 5–20× slower; Beeman: Verlet's error at Verlet's cost) run T/25, T/100, T/400 on M4, and on
# Stansby & Li (run last) every integrator does (Newmark T/25, T/100)
COARSE = {"m4_134": dict(beeman=(25, 100, 400), semi_implicit=(25, 100, 400),
                         newmark=(25, 100, 400)),
          "stansby_li": dict(rk4=(25, 100, 400), verlet=(25, 100, 400), beeman=(25, 100, 400),
                             semi_implicit=(25, 100, 400), newmark=(25, 100))}
SAVE_PER_PERIOD = 25           # every case saves at T/25: the measures use the same samples
REFERENCE = dict(integrator="rk4", n_per_T=800, radiation="state_space", option=None)
RADIATION_AT = dict(integrator="rk4", n_per_T=100)
FIDELITY_AT = 200              # mfm.reduce's pilot: dt = T/200


def _sea(system):
    import hydro

    if system == "m4_134":      # benchmarks/speed.py and tools/fidelity.py
        return hydro.Jonswap(hs=0.04, tp=1.2, gamma=3.3, seed=1, omega_range=(1.0, 25.0))
    if system == "rm3":         # the README's RM3 case
        return hydro.Regular(height=2.5, period=8.0)
    # Stansby & Li (notebooks/stansby_li.ipynb): JONSWAP γ 3.3 at the 12 s swell peak, 45° so
    # both hinged floats work
    return hydro.Jonswap(hs=2.0, tp=12.0, gamma=3.3, heading=math.radians(45.0), seed=0,
                         omega_range=(0.2, 2.0))


# period T (s), run length and settling time in periods (the ramp is 5 periods), the coordinates
# whose standard deviation and series are compared, the convolution windows (periods; the full
# T_K is always run) and state-space orders (beside "auto") tried. M4 and Stansby & Li run 20
# periods with two windows and two orders: their compilations are the study's cost (RM3 ran
# first with 30 periods, three windows and three orders)
SYSTEMS = {
    "m4_134": dict(config="m4_134.toml", T=1.2, periods=20, settle=8,
                   coordinates=("float3.angle", "float7.angle", "float6.angle", "float8.angle"),
                   windows=(1.0, 10.0), orders=(8, 16)),
    # RM3 ≤ 300 s: past ~600 s its parametric resonance grows (docs/stability.md)
    "rm3": dict(config="rm3.toml", T=8.0, periods=30, settle=15,
                coordinates=("spar.pitch", "float.stroke"), windows=(1.0, 3.0, 10.0),
                orders=(2, 4, 6)),
    "stansby_li": dict(config="stansby_li.toml", T=12.0, periods=20, settle=8,
                       coordinates=("floatB.angle", "floatC.angle"), windows=(1.0, 10.0),
                       orders=(8, 16)),
}


def load_system(system, **overrides):
    """(model, sea, settings) of a system; ``overrides`` change the settings (a short run)."""
    if system not in SYSTEMS:
        raise ValueError(f"system: {system!r}; accepted: {sorted(SYSTEMS)}")
    cfg = dict(SYSTEMS[system], **overrides)
    model = load(ROOT / "configs" / cfg["config"])
    return model, _sea(system), cfg


SEA_TEXT = {"m4_134": "JONSWAP Hs 0.04 m, Tp 1.2 s, γ 3.3", "rm3": "regular wave H 2.5 m, T 8 s",
            "stansby_li": "JONSWAP Hs 2 m, Tp 12 s, γ 3.3, heading 45°"}


def _key(c):
    return f"{c['integrator']}|{c['n_per_T']}|{c['radiation']}|{c['option']}"


def _options(radiation, option, T):
    """simulate's radiation keywords for a case's option: a window in periods or "full" (the
    convolution's memory), an order or "auto" (the state space's)."""
    if radiation == "convolution":
        return dict(memory=None if option in (None, "full") else float(option) * T)
    if radiation in ("state_space", "state_space_exact") and option not in (None, "auto"):
        return dict(state_space_options=dict(order=int(option)))
    return {}


def run_case(model, sea, cfg, *, integrator, n_per_T, radiation, option=None, time_it=True):
    """One run: its saved samples (t, q, qd every T/25) and its timing.

    Returns ``(record, series)``: record has the case, ``status`` ("ok" or "non-finite"),
    ``first_s``, ``warm_s``, ``compile_s``, ``repeats``; series is (t, q, qd) or None."""
    import jax

    T = cfg["T"]
    dt = T / n_per_T
    duration = cfg["periods"] * T
    n_steps = int(round(duration / dt))
    save_every = n_per_T // SAVE_PER_PERIOD
    rad = radiation
    if radiation == "auto":
        rad = choose_radiation(model, dt=dt, n_steps=n_steps, integrator=integrator)[0]
    kw = _options(rad, option, T)
    q0 = np.zeros(model.n_coordinates)

    def go():
        loads = model_loads(model, sea, dt=dt, duration=duration, ramp=5 * T, radiation=rad,
                            integrator=integrator, **kw)
        return jax.block_until_ready(rollout(model, q0, q0, dt=dt, n_steps=n_steps,
                                             integrator=integrator, loads=loads,
                                             save_every=save_every))

    rec = dict(integrator=integrator, n_per_T=n_per_T, radiation=radiation, option=option,
               radiation_used=rad, dt=dt, n_steps=n_steps)
    start = time.perf_counter()
    out = go()
    rec["first_s"] = time.perf_counter() - start
    t, q, qd = (np.asarray(a) for a in out[:3])
    finite = np.isfinite(q).all(axis=1) & np.isfinite(qd).all(axis=1)
    if not finite.all():
        rec.update(status="non-finite", stopped_at_s=float(t[int(np.argmax(~finite))]))
        return rec, None
    rec["status"] = "ok"
    if time_it:
        times = []
        while True:
            s = time.perf_counter()
            go()
            times.append(time.perf_counter() - s)
            if len(times) >= (3 if times[0] < 2 else 2 if times[0] < 5 else 1):
                break
        rec.update(warm_s=statistics.median(times), repeats=len(times),
                   compile_s=max(rec["first_s"] - statistics.median(times), 0.0))
    return rec, (t, q, qd)


def spectral_case(model, sea, cfg, t, time_it=True):
    """The spectral level (:func:`mfm.spectral_response`) on the time grid t, timed with the
    series and statistics only."""
    rec = dict(integrator="spectral", n_per_T=None, radiation="database", option=None,
               radiation_used="database", status="ok")
    start = time.perf_counter()
    ds = spectral_response(model, sea, t=t)
    rec["first_s"] = time.perf_counter() - start
    if time_it:
        for name, kw in (("warm_s", dict(t=t)), ("stats_s", {})):
            times = []
            for _ in range(3):
                s = time.perf_counter()
                spectral_response(model, sea, **kw)
                times.append(time.perf_counter() - s)
            rec[name] = statistics.median(times)
        rec.update(repeats=3, compile_s=max(rec["first_s"] - rec["warm_s"], 0.0))
    return rec, (np.asarray(ds.time), np.asarray(ds.q), np.asarray(ds.qd))


def linear_case(model, sea, cfg, *, n_per_T, time_it=True):
    """The linear level (:func:`mfm.linear_response`) at dt = T/n_per_T over the run's duration,
    ramp and samples (every T/25), timed as :func:`run_case`: ``warm_s`` the median of warm calls
    (linearisation, excitation series and the compiled modal scan; the modes of A are cached per
    model and dt, as the state-space fit is, so they are outside it) and ``modes_s`` a warm call
    with that cache emptied (what a new dt or model adds: the eigendecomposition). A load the
    level cannot realise (NotImplementedError) or ill-conditioned modes (ValueError) give
    ``status = "refused"`` and the ``reason``."""
    T = cfg["T"]
    kw = dict(duration=cfg["periods"] * T, dt=T / n_per_T, ramp=5 * T,
              save_every=n_per_T // SAVE_PER_PERIOD)
    rec = dict(integrator="linear", n_per_T=n_per_T, radiation="state_space", option=None,
               radiation_used="state_space", dt=kw["dt"], n_steps=int(round(kw["duration"] / kw["dt"])))
    start = time.perf_counter()
    try:
        ds = _linear.linear_response(model, sea, **kw)
    except (NotImplementedError, ValueError) as err:
        rec.update(status="refused", reason=f"{type(err).__name__}: {err}",
                   first_s=time.perf_counter() - start)
        return rec, None
    rec.update(first_s=time.perf_counter() - start, status="ok",
               mode_condition=float(ds.attrs.get("mode_condition", math.nan)))
    if time_it:
        times = []
        while True:
            s = time.perf_counter()
            _linear.linear_response(model, sea, **kw)
            times.append(time.perf_counter() - s)
            if len(times) >= (3 if times[0] < 2 else 2 if times[0] < 5 else 1):
                break
        _linear._MODES_CACHE.clear()
        s = time.perf_counter()
        _linear.linear_response(model, sea, **kw)
        rec.update(warm_s=statistics.median(times), repeats=len(times),
                   modes_s=time.perf_counter() - s,
                   compile_s=max(rec["first_s"] - statistics.median(times), 0.0))
    return rec, (np.asarray(ds.time), np.asarray(ds.q), np.asarray(ds.qd))


def measures(model, cfg, series):
    """The settled part's coordinate standard deviations, mean damper power and the series."""
    t, q, qd = series
    keep = t >= cfg["settle"] * cfg["T"] - 1e-9
    idx = [model.coordinate_index(c) for c in cfg["coordinates"]]
    c = np.asarray(model.damping)
    return dict(std=q[keep][:, idx].std(axis=0), power=float((c * qd[keep] ** 2).sum(axis=1).mean()),
                x=q[keep][:, idx])


def errors(m, ref):
    """Relative errors of measures ``m`` against ``ref`` (module docstring)."""
    if m["x"].shape != ref["x"].shape:
        raise ValueError(f"the series have different samples: {m['x'].shape} against the "
                         f"reference's {ref['x'].shape}")
    dx = m["x"] - ref["x"]
    return dict(std=float(np.max(np.abs(m["std"] / ref["std"] - 1))),
                power=float(abs(m["power"] / ref["power"] - 1)),
                series=float(np.sqrt((dx ** 2).sum() / ((ref["x"] - ref["x"].mean(0)) ** 2).sum())))


def plan(cfg, system=None):
    """The cases of a system: (slice, case) in the order run: the reference, the fidelity levels,
    the reference's check and the radiation models (a few cases that say most), then the
    integrator grid (the many compilations; a study cut short keeps the others)."""
    out = [("reference", dict(REFERENCE)),
           ("fidelity", dict(integrator="spectral", n_per_T=None, radiation="database",
                             option=None, level="spectral")),
           ("fidelity", dict(integrator="linear", n_per_T=FIDELITY_AT, radiation="state_space",
                             option=None, level="linear")),
           ("fidelity", dict(integrator="verlet", n_per_T=FIDELITY_AT,
                             radiation="state_space_exact", option=None, level="fast")),
           ("fidelity", dict(integrator="rk4", n_per_T=FIDELITY_AT, radiation="auto",
                             option=None, level="full")),
           ("reference_check", dict(REFERENCE, n_per_T=REFERENCE["n_per_T"] // 2))]
    for opt in ("full",) + tuple(cfg["windows"]):
        out.append(("radiation", dict(RADIATION_AT, radiation="convolution", option=opt)))
    for opt in ("auto",) + tuple(cfg["orders"]):
        out.append(("radiation", dict(RADIATION_AT, radiation="state_space", option=opt)))
    for integ in INTEGRATORS:
        for n in COARSE.get(system, {}).get(integ, STEPS_PER_PERIOD):
            out.append(("integrators", dict(integrator=integ, n_per_T=n,
                                            radiation="state_space_exact", option=None)))
    return out


def study(system, *, path=None, slices=None, cases=None, reference=None, time_it=True, log=print,
          **overrides):
    """Run (or resume) a system's study; returns the stored dict. ``slices`` limits the slices
    run (the reference always runs); ``cases`` replaces :func:`plan`'s list of (slice, case);
    ``reference`` the reference case (default :data:`REFERENCE`); ``overrides`` change the
    settings (e.g. a short smoke run); ``time_it`` False runs each case once, untimed; ``path``
    None writes nothing."""
    reference = dict(REFERENCE if reference is None else reference)
    warnings.simplefilter("ignore")
    model, sea, cfg = load_system(system, **overrides)
    data = dict(system=system, settings=dict(cfg, reference=_key(reference)), sea=repr(sea),
                cases=[])
    if path is not None and Path(path).exists():
        old = json.loads(Path(path).read_text())
        if old.get("settings") == json.loads(json.dumps(data["settings"])):   # tuples as lists
            data = old
    done = {(c["slice"], _key(c)): c for c in data["cases"]}
    fit_start = time.perf_counter()
    model.hydro.state_space()          # the default fit, cached, outside every timing
    data.setdefault("fit_s", time.perf_counter() - fit_start)
    data["memory_T_K_s"] = model.hydro.memory()
    data["mfm_version"] = results.version()
    cache = {}

    def series_of(case, time_it=time_it):
        if case["radiation"] == "auto":    # the strategy auto takes: the same run as that case's
            case = dict(case, radiation=choose_radiation(
                model, dt=cfg["T"] / case["n_per_T"], n_steps=cfg["periods"] * case["n_per_T"],
                integrator=case["integrator"])[0])
        k = _key(case)
        if k not in cache:
            if case["integrator"] == "spectral":
                t = cache[_key(reference)][1][0]
                cache[k] = spectral_case(model, sea, cfg, t, time_it=time_it)
            elif case["integrator"] == "linear":
                cache[k] = linear_case(model, sea, cfg, n_per_T=case["n_per_T"], time_it=time_it)
            else:
                cache[k] = run_case(model, sea, cfg, time_it=time_it, **{
                    n: case[n] for n in ("integrator", "n_per_T", "radiation", "option")})
        return cache[k]

    # a resumed study keeps its reference's timing and checks the rerun gives the stored numbers
    stored = data.get("reference")
    ref_rec, ref_series = series_of(reference, time_it=time_it and stored is None)
    ref = measures(model, cfg, ref_series)
    if stored is None:
        data["reference"] = dict(ref_rec, std=ref["std"].tolist(), power=ref["power"])
    elif not (np.allclose(ref["std"], stored["std"], rtol=1e-9, atol=0)
              and math.isclose(ref["power"], stored["power"], rel_tol=1e-9)):
        raise RuntimeError(f"{system}: the reference rerun differs from the stored one (std "
                           f"{ref['std'].tolist()} against {stored['std']}, power {ref['power']} "
                           f"against {stored['power']}): delete {path} to start afresh")
    conv = None
    for sl, case in (plan(cfg, system) if cases is None else cases):
        if sl == "reference" or (slices is not None and sl not in slices):
            continue
        k = (sl, _key(case))
        if k in done:
            continue
        start = time.perf_counter()
        rec, ser = series_of(case)
        row = dict(rec, slice=sl, radiation=case["radiation"],
                   **({"level": case["level"]} if "level" in case else {}))
        if ser is not None:
            m = measures(model, cfg, ser)
            row.update(errors=errors(m, ref), std=m["std"].tolist(), power=m["power"])
            if sl == "radiation":
                if conv is None:
                    conv = measures(model, cfg, series_of(dict(RADIATION_AT, radiation="convolution",
                                                               option="full"))[1])
                row["errors_vs_convolution"] = errors(m, conv)
        data["cases"].append(row)
        done[k] = row
        if path is not None:
            Path(path).write_text(json.dumps(data, indent=1))
        e = row.get("errors", {})
        log(f"{system} {sl:15s} {case['integrator']:13s} T/{case['n_per_T']} {case['radiation']}"
            f"[{case['option']}]: {row['status']} warm {row.get('warm_s', float('nan')):.3g} s, "
            f"compile {row.get('compile_s', float('nan')):.3g} s, errors "
            + ", ".join(f"{n} {v:.2e}" for n, v in e.items())
            + f" ({time.perf_counter() - start:.0f} s)")
    return data


# ------------------------------------------------------------------------------------ figures

METRICS = (("std", "coordinate std (θ_rms)"), ("power", "mean PTO power"),
           ("series", "time series (relative L2)"))
COLOURS = dict(rk4="C0", beeman="C1", semi_implicit="C2", newmark="C3", verlet="C4", spectral="k",
               linear="C8")


def label(row):
    """A case in words: 'rk4 T/100 state_space_exact', 'rk4 T/100 conv 3T', 'spectral'."""
    if row["integrator"] == "spectral":
        return "spectral (linear FD)"
    if row["integrator"] == "linear":
        return f"linear T/{row['n_per_T']} (modal exact, ss)"
    rad = {"state_space_exact": "ss-exact", "state_space": "ss", "convolution": "conv",
           "auto": "auto"}[row["radiation"]]
    opt = row.get("option")
    if row["radiation"] == "convolution":
        rad += " T_K" if opt in (None, "full") else f" {opt:g}T"
    elif opt not in (None, "auto"):
        rad += f" order {opt}"
    elif row["radiation"] == "auto":
        rad += f" ({row['radiation_used']})"
    return f"{row['integrator']} T/{row['n_per_T']} {rad}"


def pareto(points):
    """Indices of the non-dominated (time, error) points, fastest first: no other point is both
    faster and at most as inaccurate."""
    order = sorted(range(len(points)), key=lambda i: (points[i][0], points[i][1]))
    front, best = [], math.inf
    for i in order:
        if points[i][1] < best:
            front.append(i)
            best = points[i][1]
    return front


FLOOR = 1e-12      # errors below are drawn at the floor (round-off of the comparison)


def figure(data, path=None, *, show_labels=True):
    """Error against warm wall time, log–log, one panel per measure; the Pareto front joined and
    labelled; non-finite runs as crosses along the top."""
    import matplotlib.pyplot as plt
    from matplotlib.ticker import NullFormatter

    rows = [r for r in data["cases"] if r["slice"] != "reference_check" and r["status"] != "refused"]
    fig, axes = plt.subplots(1, 3, figsize=(17, 6.2))
    markers = dict(integrators="o", radiation="s", fidelity="D")
    for ax, (metric, title) in zip(axes, METRICS):
        ok = [r for r in rows if r["status"] == "ok"]
        pts = [(r["warm_s"], max(r["errors"][metric], FLOOR)) for r in ok]
        for r, (x, y) in zip(ok, pts):
            ax.plot(x, y, markers[r["slice"]], color=COLOURS.get(r["integrator"], "0.5"),
                    ms=6 if r["slice"] == "integrators" else 7, mfc="none"
                    if r["slice"] == "radiation" and r["radiation"] == "convolution" else None,
                    alpha=0.85)
        # each integrator's dt sweep joined
        for integ in INTEGRATORS:
            line = sorted((p for r, p in zip(ok, pts) if r["slice"] == "integrators"
                           and r["integrator"] == integ), key=lambda p: p[0])
            if line:
                ax.plot(*zip(*line), "-", color=COLOURS[integ], lw=0.8, alpha=0.6)
        front = pareto(pts)
        ax.step([pts[i][0] for i in front], [pts[i][1] for i in front], "-", where="post",
                color="crimson", lw=1.6, alpha=0.7, zorder=0)
        ax.plot([pts[i][0] for i in front], [pts[i][1] for i in front], "o", ms=12,
                mfc="none", mec="crimson", mew=1.4)
        if show_labels:
            for j, i in enumerate(front):
                ax.annotate(label(ok[i]), (pts[i][0], pts[i][1]), fontsize=6.5, color="crimson",
                            xytext=(6, 4 + 7 * (j % 2)), textcoords="offset points")
        bad = [r for r in rows if r["status"] != "ok"]
        if bad:
            top = max(p[1] for p in pts) * 3
            for r in bad:
                ax.plot(r["first_s"], top, "x", color=COLOURS.get(r["integrator"], "0.5"), ms=8)
            ax.text(0.02, 0.97, f"× non-finite: {len(bad)} runs (at their first call's time)",
                    transform=ax.transAxes, fontsize=7, va="top")
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.xaxis.set_minor_formatter(NullFormatter())
        ax.set_xlabel("warm wall time per run (s)")
        ax.set_ylabel(f"relative error, {title}")
        ax.set_title(title)
        ax.grid(True, which="both", alpha=0.25)
    # legend: colours = integrators, markers = slices
    from matplotlib.lines import Line2D
    handles = [Line2D([], [], color=COLOURS[i], marker="o", ls="-", label=i) for i in INTEGRATORS]
    handles += [Line2D([], [], color="k", marker="D", ls="none", label="spectral level"),
                Line2D([], [], color=COLOURS["linear"], marker="D", ls="none",
                       label="linear level (T/200)"),
                Line2D([], [], color="0.4", marker="o", ls="none",
                       label="integrators × dt (ss-exact)"),
                Line2D([], [], color="0.4", marker="s", ls="none", label="radiation: state space"),
                Line2D([], [], color="0.4", marker="s", mfc="none", ls="none",
                       label="radiation: convolution"),
                Line2D([], [], color="0.4", marker="D", ls="none", label="fidelity levels (T/200)"),
                Line2D([], [], color="crimson", marker="o", mfc="none", ms=10, ls="-",
                       label="Pareto front")]
    fig.legend(handles=handles, fontsize=8, loc="lower center", ncol=7)
    s = data["settings"]
    fig.suptitle(f"{data['system']}: {SEA_TEXT.get(data['system'], data['sea'])}; {s['periods']} "
                 f"periods, compared after {s['settle']} T; reference "
                 f"{s.get('reference', _key(REFERENCE))}", fontsize=10)
    fig.tight_layout(rect=(0, 0.09, 1, 1))
    if path is not None:
        fig.savefig(path, dpi=110)
    return fig


def table(data):
    """The cases as markdown rows (case, warm s, compile s, the three errors)."""
    lines = ["| case | slice | warm s | compile s | std err | power err | series err |",
             "|---|---|---|---|---|---|---|"]
    for r in data["cases"]:
        if r["status"] == "refused":
            lines.append(f"| {label(r)} | {r['slice']} | — | — | refused: {r['reason']} | | |")
            continue
        if r["status"] != "ok":
            lines.append(f"| {label(r)} | {r['slice']} | — | — | non-finite at "
                         f"{r['stopped_at_s']:.3g} s | | |")
            continue
        e = r["errors"]
        lines.append(f"| {label(r)} | {r['slice']} | {r['warm_s']:.3g} | {r['compile_s']:.3g} | "
                     f"{e['std']:.2e} | {e['power']:.2e} | {e['series']:.2e} |")
    return "\n".join(lines)


def cheapest(data, metric, tolerance):
    """The fastest case (warm wall time) whose ``metric`` error is ≤ tolerance, or None."""
    ok = [r for r in data["cases"] if r["status"] == "ok" and r["slice"] != "reference_check"
          and r["errors"][metric] <= tolerance]
    return min(ok, key=lambda r: r["warm_s"]) if ok else None


def front_table(data, metric):
    """The Pareto front of one measure as markdown rows, fastest first."""
    ok = [r for r in data["cases"] if r["status"] == "ok" and r["slice"] != "reference_check"]
    front = pareto([(r["warm_s"], max(r["errors"][metric], FLOOR)) for r in ok])
    lines = [f"| Pareto front, {metric} error | warm s | {metric} error |", "|---|---|---|"]
    lines += [f"| {label(ok[i])} | {ok[i]['warm_s']:.3g} | {ok[i]['errors'][metric]:.2e} |"
              for i in front]
    return "\n".join(lines)
