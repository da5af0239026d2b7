"""One module builds every result: labelled ``xarray.Dataset``s with units on every variable, PTO
power defined once, and provenance (config and database with their SHA-256, sea state, ramp,
radiation settings and fit report, integrator, dt, versions, git commit), whichever front door
(:func:`mfm.simulate`, :func:`mfm.simulate_batch`, :func:`mfm.frequency_response`,
:func:`mfm.natural_frequencies`) made them.
"""
from __future__ import annotations

import datetime
import functools
import numbers
import subprocess
import time
from pathlib import Path

import numpy as np
import xarray as xr

from .loads.pto import absorbed_power, damped_coordinates, mean_absorbed_power

CONVENTIONS = ("inertial frame: origin on the still-water line, z up; body frames at the CoM, "
               "parallel to inertial at q = 0")
PTO_POWER_ATTRS = {"long_name": "absorbed power: c q̇² (joint dampers), β ẇ² (hydraulic)", "units": "W"}


# ------------------------------------------------------------------------------- provenance
def version() -> str:
    try:
        from importlib.metadata import version as v
        return v("mfm")
    except Exception:  # not installed (running from a source tree)
        return "unknown"


@functools.lru_cache(maxsize=1)
def git_commit() -> str:
    """The commit of the source tree mfm runs from, with "+dirty" if it has changes; "" if none."""
    root = Path(__file__).resolve().parent.parent
    try:
        head = subprocess.run(["git", "-C", str(root), "rev-parse", "HEAD"], capture_output=True,
                              text=True, timeout=5)
        if head.returncode:
            return ""
        dirty = subprocess.run(["git", "-C", str(root), "status", "--porcelain", "--untracked-files=no"],
                               capture_output=True, text=True, timeout=5).stdout.strip()
        return head.stdout.strip() + ("+dirty" if dirty else "")
    except (OSError, subprocess.SubprocessError):
        return ""


def _attr(v):
    """NetCDF attributes take str, numbers and arrays of numbers: anything else as its repr."""
    if isinstance(v, (str, int, float, np.integer, np.floating)) and not isinstance(v, bool):
        return v
    if isinstance(v, bool):
        return str(v)
    if v is None:
        return "none"
    return repr(v)


def provenance(model, loads=(), **settings) -> dict:
    """The attributes every result carries: model, config (path, SHA-256), the loads' own
    settings (database, sea state, ramp, radiation, fit report), the run's settings, versions."""
    import jax

    from . import backend as _xla

    out = {"model": model.name, "config": getattr(model, "source", "") or "none",
           "config_sha256": getattr(model, "source_sha256", "") or "none"}
    if model.hydro is not None:
        out.update(model.hydro.provenance())
    for ld in loads:
        out.update(ld.provenance())
    out.update(settings)
    out.update({"mfm_version": version(), "git_commit": git_commit() or "none",
                "jax_version": jax.__version__, "numpy_version": np.__version__,
                # whether XLA compiled the time loop as one function (mfm.runner.xla: speed only)
                "xla_time_loop": (f"whole (loops reading up to {_xla.LOOP_THRESHOLD} bytes)"
                                  if _xla.LOOPS_COMPILED_WHOLE else "kernel by kernel"),
                "xarray_version": xr.__version__,
                "created": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"),
                "conventions": CONVENTIONS})
    return {k: _attr(v) for k, v in out.items()}


# ------------------------------------------------------------------------------- units
def coordinate_units(model) -> list[str]:
    """"rad" for a rotation coordinate, "m" for a translation, per coordinate of q."""
    units = [""] * model.n_coordinates
    for motions in model.motions:
        for kind, k in motions:
            units[k] = "rad" if kind == "R" else "m"
    return units


def _rate(u, n):
    return {"rad": "rad/s", "m": "m/s"}[u] if n == 1 else {"rad": "rad/s2", "m": "m/s2"}[u]


def _coordinate_attrs(model, n=0):
    units = coordinate_units(model)
    kinds = sorted(set(units))
    u = kinds[0] if len(kinds) == 1 else None
    label = {0: "generalised coordinates", 1: "generalised velocities", 2: "generalised accelerations"}[n]
    if u is not None:
        return {"long_name": label, "units": u if n == 0 else _rate(u, n)}
    return {"long_name": label, "units": {0: "m or rad", 1: "m/s or rad/s", 2: "m/s2 or rad/s2"}[n]
            + " (per coordinate: coordinate_unit)"}


def _coordinate_coords(model):
    return {"coordinate": ("coordinate", list(model.coordinates)),
            "coordinate_unit": ("coordinate", coordinate_units(model))}


# ------------------------------------------------------------------------------- PTOs
def add_ptos(ds, names, power, displacement, force=None, dim="time"):
    """Append PTOs (names, power (…, time, P), displacement (…, time, P)) to ``pto_power`` and
    ``pto_displacement`` of ``ds`` (joint dampers first); ``force`` as ``pto_force``."""
    lead = tuple(d for d in ("case", "step", "time") if d in ds.dims and d in (dim, "case"))
    lead = lead if lead else (dim,)
    power = xr.DataArray(power, dims=lead + ("pto",), coords={"pto": list(names)})
    disp = xr.DataArray(displacement, dims=lead + ("pto",), coords={"pto": list(names)})
    if "pto" in ds.dims:
        power = xr.concat([ds.pto_power, power], dim="pto")
        disp = xr.concat([ds.pto_displacement, disp], dim="pto")
        ds = ds.drop_vars(["pto_power", "pto_displacement", "pto"])
    ds = ds.assign(pto_power=power, pto_displacement=disp)
    ds["pto_power"].attrs = dict(PTO_POWER_ATTRS)
    ds["pto_displacement"].attrs = {"long_name": "joint coordinate (relative angle or stroke) or "
                                    "piston stroke", "units": "rad or m"}
    if force is not None:
        ds["pto_force"] = (lead + ("hydraulic_pto",), force,
                           {"long_name": "hydraulic piston force μẅ + βẇ + κw", "units": "N"})
        ds = ds.assign_coords(hydraulic_pto=list(names))
    return ds


def add_linear_dampers(ds, dampers, q0, q, qd, dim="time"):
    """Append each linearised PTO's power β (G q̇)² and displacement w₀ + G (q − q₀) (time, pto)."""
    for d in dampers:
        G = np.asarray(d.rows)
        ds = add_ptos(ds, d.names, absorbed_power(np.asarray(d.damping), qd @ G.T),
                      np.asarray(d.offset) + (q - q0) @ G.T, dim=dim)
    return ds


def _joint_dampers(ds, model, damping, q, qd, dim):
    """Append the joint dampers (c q̇², the coordinate as displacement); ``damping`` (n_q,) or
    (case, n_q)."""
    damped = damped_coordinates(damping)
    if not damped:
        return ds
    c = np.asarray(damping)[..., damped]
    power = absorbed_power(c[..., None, :] if c.ndim > 1 else c, qd[..., damped])
    names = [model.coordinates[k] for k in damped]
    units = coordinate_units(model)
    ds = add_ptos(ds, names, power, q[..., damped], dim=dim)
    kinds = {units[k] for k in damped}
    if len(kinds) == 1:
        ds["pto_displacement"].attrs["units"] = kinds.pop()
    return ds


def add_load_outputs(ds, load, records: dict):
    """Add a load's recorded diagnostics (:meth:`~mfm.loads.base.Load.outputs`: dims after time,
    attrs, coordinates) to a run's dataset, and, for a load that is a PTO
    (:meth:`~mfm.loads.base.Load.pto_records`), its pistons to ``pto_power``,
    ``pto_displacement`` and ``pto_force``."""
    spec = dict(load.outputs())
    coords = spec.pop("coords", {})
    if spec:
        ds = ds.assign_coords({k: v for k, v in coords.items() if k not in ds.coords})
    for name, (dims, attrs) in spec.items():
        ds[name] = (("time",) + tuple(dims), records[name], dict(attrs))
    pto = load.pto_records(records)
    if pto is not None:
        ds = add_ptos(ds, list(pto.names), pto.power, pto.displacement, pto.force)
    return ds


def sea_labels(seas) -> dict:
    """Per-case labels of a batch's sea states (Hs, Tp, H, T, gamma, heading) where every sea has
    the attribute: name → (values (case,), attrs), for the coordinates on ``case`` of every
    dataset over cases (:func:`batch`, the spectral sweep's, a sweep's)."""
    units = {"hs": "m", "tp": "s", "height": "m", "period": "s", "gamma": "1", "heading": "rad"}
    out = {}
    for name, u in units.items():
        vals = [getattr(s, name, None) for s in seas]
        if all(isinstance(v, numbers.Real) and not isinstance(v, bool) for v in vals):
            out[f"sea_{name}"] = (np.asarray(vals, dtype=float), {"units": u})
    return out


# ------------------------------------------------------------------------------- time domain
# what every run records per sample besides q, q̇, q̈ (mfm.timedomain.record.sample_outputs): dims after time, attrs
RECORD_DIMS = {
    "body_position": (("body", "axis"), {"long_name": "centre of mass position, inertial axes",
                                         "units": "m"}),
    "body_rotation": (("body", "angle"), {"long_name": "body orientation as roll, pitch, yaw with "
                                          "R = Rz(yaw) Ry(pitch) Rx(roll)", "units": "rad"}),
    "joint_force": (("body", "axis"), {"long_name": "force the joint of each body transmits from "
                                       "its parent (or the inertial frame) to the body, inertial "
                                       "axes", "units": "N"}),
    "joint_moment": (("body", "axis"), {"long_name": "moment the joint of each body transmits, "
                                        "about the joint point, inertial axes", "units": "N m"}),
    "kinetic_energy": ((), {"units": "J"}),
    "potential_energy": ((), {"long_name": "gravity and joint springs", "units": "J"}),
}
RECORD_COORDS = {"axis": ["x", "y", "z"], "angle": ["roll", "pitch", "yaw"]}


def record_specs(model, loads):
    """What a run can record per sample with these loads: name → (dims after time, attrs), and the
    coordinate values of those dims (the builtin outputs and each load's :meth:`outputs`)."""
    specs = dict(RECORD_DIMS)
    coords = {"body": list(model.body_names), **RECORD_COORDS}
    for ld in loads:
        spec = dict(ld.outputs())
        coords.update(spec.pop("coords", {}))
        specs.update(spec)
    return specs, coords


def time_series(model, loads, integ, dt, t, q, qd, qdd, iters, rec, settings) -> xr.Dataset:
    """The dataset of one run (:func:`mfm.simulate`)."""
    ds = xr.Dataset(
        {
            "q": (("time", "coordinate"), q, _coordinate_attrs(model, 0)),
            "qd": (("time", "coordinate"), qd, _coordinate_attrs(model, 1)),
            "qdd": (("time", "coordinate"), qdd, _coordinate_attrs(model, 2)),
            **{k: (("time",) + dims, rec[k], dict(attrs)) for k, (dims, attrs) in RECORD_DIMS.items()},
            "iterations": (("time",), iters, {"long_name": "corrector iterations of the step",
                                              "units": "1"}),
        },
        coords={"time": ("time", t, {"units": "s"}), **_coordinate_coords(model),
                "body": list(model.body_names), **RECORD_COORDS},
        attrs={"title": f"mfm simulation of {model.name}",
               **provenance(model, loads, integrator=integ.name, integrator_settings=repr(integ),
                            dt=float(dt), dt_units="s", **settings)},
    )
    ds = _joint_dampers(ds, model, model.damping, q, qd, "time")
    for ld in loads:
        ds = add_load_outputs(ds, ld, rec)
    return ds


def linear_time_series(model, loads, t, q, qd, qdd, q0, eta, settings, source=None,
                       dampers=()) -> xr.Dataset:
    """The dataset of :func:`mfm.runner.linear.linear_response`: q, q̇, q̈ (time, coordinate), the power
    of the joint dampers and of the loads' linearised PTOs (``dampers``,
    :func:`mfm.loads.pto.load_dampers`),
    ``eta`` and the ``equilibrium`` it is linearised about."""
    ds = xr.Dataset(
        {"q": (("time", "coordinate"), q, _coordinate_attrs(model, 0)),
         "qd": (("time", "coordinate"), qd, _coordinate_attrs(model, 1)),
         "qdd": (("time", "coordinate"), qdd, _coordinate_attrs(model, 2)),
         "eta": (("time",), eta, {"long_name": "undisturbed wave elevation at the origin",
                                  "units": "m"}),
         "equilibrium": (("coordinate",), q0, {"long_name": "static equilibrium about which the "
                                               "model is linearised", "units": "m or rad"})},
        coords={"time": ("time", t, {"units": "s"}), **_coordinate_coords(model)},
        attrs={"title": f"mfm linearised time-domain response of {model.name}",
               **provenance(model, loads, **settings)})
    if source is not None:
        ds.attrs["source"] = source
    ds = _joint_dampers(ds, model, model.damping, q, qd, "time")
    return add_linear_dampers(ds, dampers, q0, q, qd)


def batch(model, models, loads, integ, t, q, qd, dts, settings, save_every, labels=None,
          recorded=None) -> xr.Dataset:
    """The dataset of :func:`mfm.simulate_batch`: (case, step, …); ``labels`` per-case values
    (e.g. each sea state's Hs, Tp) as coordinates on ``case``; ``recorded`` the per-sample outputs
    asked for by name (case, step, …)."""
    B = q.shape[0]
    template = loads[0]     # case 0's loads: the provenance and the outputs' specs
    ds = xr.Dataset(
        {"time": (("case", "step"), t, {"units": "s"}),
         "q": (("case", "step", "coordinate"), q, _coordinate_attrs(model, 0)),
         "qd": (("case", "step", "coordinate"), qd, _coordinate_attrs(model, 1)),
         "dt": (("case",), np.broadcast_to(dts, (B,)).copy(), {"units": "s"})},
        coords={"case": np.arange(B), **_coordinate_coords(model)},
        attrs={"title": f"mfm batch of {B} runs of {model.name}",
               **provenance(model, template, integrator=integ.name, save_every=int(save_every),
                            **settings)})
    ds = label_cases(ds, labels or {})
    damping = np.stack([np.asarray(m.damping) for m in models])
    ds = _joint_dampers(ds, model, damping, q, qd, "step")
    if hasattr(loads, "batch_outputs"):     # the cases' loads as one (loads.assembly.CaseLoads)
        for name, (values, attrs) in loads.batch_outputs(save_every, q.shape[1]).items():
            ds[name] = (("case", "step"), np.array(values), attrs)
    else:
        per_case = [{} for _ in range(B)]
        for i in range(B):
            for ld in loads[i]:
                per_case[i].update(ld.batch_outputs(save_every, q.shape[1]))
        for name, (_, attrs) in per_case[0].items():
            ds[name] = (("case", "step"), np.stack([per_case[i][name][0] for i in range(B)]), attrs)
    if recorded:
        specs, coords = record_specs(model, template)
        for name, values in recorded.items():
            dims, attrs = specs[name]
            ds = ds.assign_coords({d: coords[d] for d in dims if d in coords and d not in ds.coords})
            ds[name] = (("case", "step") + tuple(dims), values, dict(attrs))
    return ds


def label_cases(ds, labels: dict, *, as_data=False):
    """``labels`` (name → (values (case,), attrs)) as coordinates on ``case`` (or, ``as_data``,
    as data variables)."""
    for name, (values, attrs) in labels.items():
        if as_data:
            ds[name] = ("case", np.asarray(values), attrs)
        else:
            ds = ds.assign_coords({name: ("case", np.asarray(values), attrs)})
    return ds


def gather_cases(parts, nan_cases, B, labels, dt, chunk_of, failed, attrs) -> xr.Dataset:
    """The dataset of :func:`mfm.sweep` over every case, from the datasets of its chunks
    (``parts``, each over its cases) and NaN for the cases of failed chunks (``nan_cases``: their
    indices, one array per chunk); ``labels`` the seas' and parameters' per-case values, ``dt``
    (case,) s, ``chunk_of`` and ``failed`` (case,), ``attrs`` the sweep's own attributes."""
    template = parts[0]
    parts = list(parts)
    for idx in nan_cases:
        nan = template.isel(case=np.zeros(idx.size, dtype=int)).assign_coords(case=idx)
        for name, v in nan.data_vars.items():
            if np.issubdtype(v.dtype, np.floating) or np.issubdtype(v.dtype, np.complexfloating):
                nan[name] = v.copy(data=np.full(v.shape, np.nan, dtype=v.dtype))
        parts.append(nan)
    ds = xr.concat(parts, dim="case", data_vars="minimal", coords="minimal", compat="override",
                   join="override", combine_attrs="override").sortby("case")
    ds = ds.assign_coords(case=np.arange(B))
    # labels and dt from the arguments (a failed chunk's template carries another case's)
    for name, (values, a) in labels.items():
        if name in ds.data_vars:        # a load's output of that name: keep both
            name = f"parameter_{name}"
        ds = ds.assign_coords({name: ("case", np.asarray(values), a)})
    ds["dt"] = ("case", dt, ds["dt"].attrs)
    ds = ds.assign_coords(sweep_chunk=("case", chunk_of,
                                       {"long_name": "the chunk each case ran in"}))
    ds["failed"] = ("case", failed, {"long_name": "the case's chunk failed: its data are NaN "
                                     "(see the attribute sweep_failed_chunks)"})
    ds.attrs.update(title=f"mfm sweep of {B} runs of {ds.attrs.get('model', '')}", **attrs)
    return ds


# ------------------------------------------------------------------------------- frequency domain
def frequency(model, loads, omega, x, q0, kin0, heading, settings, extra,
              reactions=None) -> xr.Dataset:
    """The dataset of :func:`mfm.frequency_response` from the coordinate amplitudes x (n_ω, n_q);
    ``reactions`` (static, amplitudes) of the joints (:func:`add_joint_reactions`)."""
    Bm = np.asarray(kin0.B)
    R = np.asarray(kin0.E)[:, :3, :3]         # sliced on the host (eager: a program each)
    body = np.concatenate([np.einsum("nai,wi->wna", Bm[:, :3], x),
                           np.einsum("nab,nbi,wi->wna", R, Bm[:, 3:], x)], axis=2)
    damped = damped_coordinates(model.damping)
    c = np.asarray(model.damping)[damped]
    ds = xr.Dataset(
        {"rao": (("omega", "coordinate"), x, {"long_name": "coordinate RAO per metre of wave "
                                             "amplitude, x(t) = Re[x e^{-i omega t}]",
                                             "units": "m/m or rad/m (per coordinate: coordinate_unit + /m)"}),
         "body_rao": (("omega", "body", "dof"), body, {"long_name": "CoM displacement and small "
                                                        "rotation of each body, inertial axes",
                                                        "units": "m/m (x, y, z), rad/m (rx, ry, rz)"}),
         "pto_rao": (("omega", "pto"), x[:, damped], {"long_name": "joint damper coordinate RAO",
                                                      "units": "rad/m or m/m"}),
         "pto_power": (("omega", "pto"), mean_absorbed_power(c, omega[:, None], x[:, damped]),
                       {"long_name": "mean absorbed power per unit wave amplitude squared, ½ c ω² |x|²",
                        "units": "W/m2"}),
         "equilibrium": (("coordinate",), q0, {"long_name": "static equilibrium about which the "
                                               "model is linearised", "units": "m or rad"})},
        coords={"omega": ("omega", omega, {"units": "rad/s"}), **_coordinate_coords(model),
                "body": list(model.body_names), "dof": ["x", "y", "z", "rx", "ry", "rz"],
                "pto": [model.coordinates[k] for k in damped]},
        attrs={"title": f"mfm frequency response of {model.name}",
               **provenance(model, loads, heading=float(heading), heading_units="rad",
                            convention="exp(-i omega t)", **settings)})
    if model.hydro is not None:
        ds.attrs["source"] = model.hydro.source
    for out in extra:
        out = dict(out)
        coords = out.pop("coords", {})
        ds = ds.assign_coords({k: v for k, v in coords.items() if k not in ds.coords})
        for name, (dims, values, attrs) in out.items():
            ds[name] = (("omega",) + tuple(dims), values, attrs)
    if reactions is not None:
        ds = add_joint_reactions(ds, *reactions)
    return ds


def mean_drift(md) -> xr.DataArray:
    """A :class:`mfm.frequency.drift.MeanDrift` as a labelled DataArray (omega, wave_direction,
    influenced_dof), as a database's ``mean_drift`` is laid out, its attributes kept."""
    return xr.DataArray(np.asarray(md.D, float), dims=("omega", "wave_direction", "influenced_dof"),
                        coords={"omega": ("omega", np.asarray(md.omega, float), {"units": "rad/s"}),
                                "wave_direction": ("wave_direction",
                                                   np.asarray(md.wave_direction, float),
                                                   {"units": "rad"}),
                                "influenced_dof": list(md.dofs)},
                        attrs=dict(md.attrs), name="mean_drift")


def linear_outputs(model, loads, kin0) -> tuple[dict, dict]:
    """Every load's :meth:`~mfm.loads.base.Load.linear_outputs` at ``kin0``, merged: ({name →
    (dims, y₀, L, attrs)}, their coordinates)."""
    out, coords = {}, {}
    for ld in loads:
        got = dict(ld.linear_outputs(model, kin0))
        coords.update(got.pop("coords", {}))
        out.update(got)
    return out, coords


def add_linear_outputs(ds, outs, coords, q0, q=None, lead=("time",), rms=None) -> xr.Dataset:
    """``ds`` with the linear levels' outputs of the loads (``outs``, ``coords``:
    :func:`linear_outputs`): ``<name>`` (lead…, dims) = y₀ + L (q − q₀) where ``q`` (lead…, n_q)
    is given, the value at the equilibrium ``<name>_equilibrium`` (dims), and where ``rms``
    {name: (case, k)} is given (the spectral level's Σ ½ a² |L x̂|²) ``<name>_rms`` (case, dims)."""
    if not outs:
        return ds
    ds = ds.assign_coords(coords)
    for name, (dims, y0, L, attrs) in outs.items():
        y0, L = np.asarray(y0, float), np.asarray(L, float)
        units = attrs.get("units", "")
        ds[f"{name}_equilibrium"] = (tuple(dims), y0, {
            "long_name": f"{attrs.get('long_name', name)}: at the equilibrium", "units": units})
        if q is not None:
            ds[name] = (tuple(lead) + tuple(dims),
                        y0 + np.einsum("...i,ki->...k", np.asarray(q) - np.asarray(q0), L),
                        dict(attrs))
        if rms is not None:
            ds[f"{name}_rms"] = (("case",) + tuple(dims), rms[name], {
                "long_name": f"{attrs.get('long_name', name)}: standard deviation about the "
                             "equilibrium, sqrt(Σ ½ a² |L x̂|²)", "units": units})
    return ds


def drag_linearisation(ds, groups, C, sigma, case: bool = True) -> xr.Dataset:
    """``ds`` with the stochastic drag linearisation of the linear levels (:mod:`mfm.frequency.drag`,
    :func:`mfm.spectral_response`, :func:`mfm.linear_response`): ``drag_damping`` ([case,]
    drag_point, flow_axis, flow_axis_col) each point's equivalent damping C (N s/m) and
    ``relative_flow_rms`` ([case,] drag_point, flow_axis) the standard deviation of its relative
    flow (m/s). ``groups``: the loads' :class:`~mfm.loads.base.QuadraticDrag` in the order of C's
    points."""
    labels = [lab for g in groups for lab in g.labels]
    lead = ("case",) if case else ()
    ds = ds.assign_coords(drag_point=labels, flow_axis=["x", "y", "z"],
                          flow_axis_col=["x", "y", "z"])
    ds["drag_damping"] = (lead + ("drag_point", "flow_axis", "flow_axis_col"), C, {
        "long_name": "equivalent linear damping C of each drag point's relative flow "
                     "w = P(u − v), force C w (stochastic linearisation, inertial axes; "
                     "u = 0 for a drag on the body's own velocity)",
        "units": "N s/m"})
    ds["relative_flow_rms"] = (lead + ("drag_point", "flow_axis"), sigma, {
        "long_name": "standard deviation of the relative flow w = P(u − v) at each drag "
                     "point (inertial axes; u = 0 for a drag on the body's own velocity)",
        "units": "m/s"})
    return ds


def drag_settings(groups, drag) -> dict:
    """The provenance attributes of a stochastic drag linearisation (``drag``: the fixed point's
    iterations and last change per case)."""
    on = sorted({"the relative flow" if g.flow else "the bodies' own velocity" for g in groups})
    return dict(drag_linearisation=f"stochastic on {' and '.join(on)} (mfm.frequency.drag): "
                "C = D E[dF/dw], per axis D sqrt(8/pi) sigma",
                drag_iterations=int(np.max(drag["iterations"])),
                drag_change=float(np.max(drag["change"])))


def spectral(model, loads, q0, q_rms, power, ptos, comps, seas, settings, series=None,
             start=None) -> xr.Dataset:
    """The dataset of :func:`mfm.runner.spectral.spectral_sweep` over ``case``: ``q_rms``,
    ``pto_power_mean`` of every PTO (``ptos``: :func:`mfm.loads.pto.linear_ptos`),
    ``n_components`` and ``equilibrium``; with ``series`` = (times, q, qd, eta) the synthesised
    time series and their PTO power c (G q̇)²; the seas' labels; provenance with ``settings``
    and the wall time since ``start`` (``time.perf_counter``)."""
    B = len(seas)
    data = {
        "q_rms": (("case", "coordinate"), q_rms,
                  {"long_name": "standard deviation about the equilibrium",
                   "units": "m or rad (per coordinate: coordinate_unit)"}),
        "pto_power_mean": (("case", "pto"), power,
                           {"long_name": "expected mean power of each joint damper and piston, "
                            "Σ a² ½ c ω² |G x|²", "units": "W"}),
        "n_components": (("case",), np.array([len(cm.omega) for cm in comps]),
                         {"long_name": "wave components of the case's sea"}),
        "equilibrium": (("coordinate",), q0, {"units": "m or rad"}),
    }
    coords = {"case": np.arange(B), **_coordinate_coords(model), "pto": list(ptos.names)}
    if series is not None:
        times, q, qd, eta = series
        data.update(
            time=(("case", "step"), times, {"units": "s"}),
            q=(("case", "step", "coordinate"), q,
               {"long_name": "generalised coordinates",
                "units": "m or rad (per coordinate: coordinate_unit)"}),
            qd=(("case", "step", "coordinate"), qd,
                {"long_name": "generalised velocities", "units": "m/s or rad/s"}),
            pto_power=(("case", "step", "pto"), absorbed_power(ptos.damping, qd @ ptos.rows.T),
                       {"long_name": "power absorbed by each joint damper and piston, c (G q̇)²",
                        "units": "W"}),
            eta=(("case", "step"), eta,
                 {"long_name": "undisturbed wave elevation at the origin", "units": "m"}))
    ds = xr.Dataset(data, coords=coords)
    ds = label_cases(ds, sea_labels(seas))
    wall = {} if start is None else {"wall_time_s": time.perf_counter() - start}
    ds.attrs = {
        "title": f"mfm spectral response of {model.name} in {B} sea states",
        **provenance(model, loads, **settings, **wall),
        "source": model.hydro.source}
    return ds


def spectral_one(ds, sea, t=None) -> xr.Dataset:
    """The one-case dataset of :func:`spectral` as :func:`mfm.spectral_response` gives it: over
    ``time`` (the times ``t``) instead of (case, step), the sea in the attributes."""
    ds = ds.isel(case=0, drop=True)
    attrs = {**ds.attrs, "title": f"mfm spectral response of {ds.attrs['model']}",
             "sea": repr(sea), "n_components": int(ds.n_components)}
    attrs.pop("seas", None)
    ds = ds.drop_vars("n_components")
    if t is not None:
        ds = ds.drop_vars("time").rename_dims(step="time").assign_coords(
            time=("time", t, {"units": "s"}))
    ds.attrs = attrs
    return ds


def add_joint_reactions(ds, static, rao):
    """Add the joint reactions of a frequency response (:func:`mfm.frequency.joint_reactions`):
    static (n, 6) and complex amplitudes (n_ω, n, 6), the last axis (fx, fy, fz, mx, my, mz)."""
    static, rao = np.asarray(static), np.asarray(rao)
    where = "inertial axes, moment about the joint point"
    ds = ds.assign_coords({k: v for k, v in RECORD_COORDS.items() if k == "axis" and k not in ds.coords})
    ds["joint_force_rao"] = (("omega", "body", "axis"), rao[..., :3], {
        "long_name": "force each joint transmits from its parent (or the inertial frame) per metre "
                     f"of wave amplitude, first order about the equilibrium, {where}",
        "units": "N/m"})
    ds["joint_moment_rao"] = (("omega", "body", "axis"), rao[..., 3:], {
        "long_name": f"moment each joint transmits per metre of wave amplitude, {where}",
        "units": "N m/m"})
    ds["joint_force_static"] = (("body", "axis"), static[:, :3], {
        "long_name": f"force each joint transmits at the static equilibrium (preload), {where}",
        "units": "N"})
    ds["joint_moment_static"] = (("body", "axis"), static[:, 3:], {
        "long_name": f"moment each joint transmits at the static equilibrium, {where}",
        "units": "N m"})
    return ds


def natural(model, loads, freqs, modes, zeta, zeta_rad, min_det, settings,
            min_det_damped=()) -> xr.Dataset:
    """The dataset of :func:`mfm.natural_frequencies`."""
    n = len(freqs)
    with np.errstate(invalid="ignore"):
        damped = np.asarray(freqs) * np.sqrt(np.clip(1.0 - np.asarray(zeta) ** 2, 0.0, None))
    return xr.Dataset(
        {"eigen": (("mode",), np.asarray(freqs), {"long_name": "undamped natural frequency, "
                                                  "generalised eigenproblem with A(omega_n)",
                                                  "units": "rad/s"}),
         "period": (("mode",), 2 * np.pi / np.asarray(freqs), {"long_name": "undamped natural period",
                                                               "units": "s"}),
         "damping_ratio": (("mode",), np.asarray(zeta),
                           {"long_name": "modal damping ratio of the linear damping C (joint "
                            "dampers, PTOs, body matrices; radiation excluded)", "units": "1"}),
         "radiation_damping_ratio": (("mode",), np.asarray(zeta_rad),
                                     {"long_name": "modal damping ratio of the radiation damping "
                                      "B(omega_n)", "units": "1"}),
         "damped": (("mode",), damped, {"long_name": "damped natural frequency ω_n √(1 − ζ²) of "
                                        "the linear damping", "units": "rad/s"}),
         "modes": (("coordinate", "mode"), np.asarray(modes).reshape(model.n_coordinates, n),
                   {"long_name": "mode shapes (coordinates)"}),
         "min_det": (("root",), np.asarray(min_det), {"long_name": "local minima of |det Λ(ω)| "
                                                      "(Hallak et al. §2.10)", "units": "rad/s"}),
         "min_det_damped": (("root_damped",), np.asarray(min_det_damped, dtype=float),
                            {"long_name": "local minima of |det(−ω² M(ω) − iω (C + B(ω)) + K)|, "
                             "damping kept: the peaks of the response to a force of constant "
                             "amplitude, ω_n √(1 − 2ζ²) for one dof", "units": "rad/s"})},
        coords={"mode": np.arange(n), **_coordinate_coords(model)},
        attrs={"title": f"mfm natural frequencies of {model.name}",
               **provenance(model, loads, **settings)})


# ------------------------------------------------------------------------------- the command line
def with_command(ds, command: str):
    """``ds`` with the command line that made it (``mfm simulate ...``) in its attributes."""
    ds.attrs["command"] = command
    return ds


def with_natural_frequencies(ds, nat, config):
    """A frequency response (``mfm rao``) with the model's natural frequencies beside it: the
    eigenfrequencies as ``natural_frequency`` (mode), the minima of |det Λ(ω)| and the config's
    path in the attributes."""
    ds["natural_frequency"] = (("mode",), nat["eigen"].values, {
        "units": "rad/s", "long_name": "undamped, generalised eigenproblem"})
    ds.attrs["natural_frequencies_min_det"] = np.array2string(nat["min_det"].values, precision=5)
    ds.attrs["config"] = str(config)
    return ds


def optimum(model, loads, seas, *, labels, units, optimum, baseline, lower, upper, at_bound,
            gradient, objective, objective_baseline, limits, con_opt, con_base, pto_names, power,
            power_base, q_rms, iterations, evaluations, gradient_norm, confirm, settings,
            start) -> xr.Dataset:
    """The dataset of :func:`mfm.studies.optimize.optimize`: the optimum over ``parameter``, the
    constraints over ``constraint`` (their largest value over the seas), the spectral responses
    at the optimum and the baseline over (case, pto) and (case, coordinate), the time-domain
    confirmation when asked; provenance with ``settings`` and the wall time since ``start``."""
    B = len(seas)
    con_labels = [f"{lm.kind}({lm.quantity})" for lm in limits]
    gain = (objective - objective_baseline) / abs(objective_baseline) if objective_baseline else np.nan
    data = {
        "optimum": (("parameter",), optimum, {"long_name": "optimal value"}),
        "baseline": (("parameter",), baseline, {"long_name": "the model's own value"}),
        "lower": (("parameter",), lower, {"long_name": "lower bound"}),
        "upper": (("parameter",), upper, {"long_name": "upper bound"}),
        "parameter_unit": (("parameter",), np.array(units, dtype=object).astype(str)),
        "at_bound": (("parameter",), np.asarray(at_bound).astype(str),
                     {"long_name": "the bound that holds the optimum ('' for none)"}),
        "gradient": (("parameter",), gradient,
                     {"long_name": "derivative of the objective at the optimum",
                      "units": "objective units per parameter unit"}),
        "objective": ((), objective, {"long_name": "objective at the optimum",
                                      "units": "W (mean absorbed power) or the user's"}),
        "objective_baseline": ((), objective_baseline,
                               {"long_name": "objective at the model's own values"}),
        "gain": ((), gain, {"long_name": "relative gain over the baseline", "units": "1"}),
        "constraint_value": (("constraint",), con_opt.max(axis=1) if len(limits) else np.zeros(0),
                             {"long_name": "largest value over the seas at the optimum",
                              "units": "m, rad or N"}),
        "constraint_value_baseline": (("constraint",),
                                      con_base.max(axis=1) if len(limits) else np.zeros(0),
                                      {"units": "m, rad or N"}),
        "constraint_limit": (("constraint",), np.array([lm.limit for lm in limits]),
                             {"units": "m, rad or N"}),
        "constraint_active": (("constraint",),
                              (con_opt.max(axis=1) >= np.array([lm.limit for lm in limits])
                               * (1 - 1e-4)) if len(limits) else np.zeros(0, bool),
                              {"long_name": "the limit holds the optimum (within 1e-4 of it)"}),
        "pto_power_mean": (("case", "pto"), power,
                           {"long_name": "expected mean power at the optimum, Σ a² ½ c ω² |G x|²",
                            "units": "W"}),
        "pto_power_mean_baseline": (("case", "pto"), power_base, {"units": "W"}),
        "q_rms": (("case", "coordinate"), q_rms,
                  {"long_name": "standard deviation about the equilibrium at the optimum",
                   "units": "m or rad (per coordinate: coordinate_unit)"}),
        "iterations": ((), iterations), "evaluations": ((), evaluations),
        "gradient_norm": ((), gradient_norm,
                          {"long_name": "norm of the projected gradient of objective/|baseline| "
                           "on parameters scaled to [0, 1] by their bounds"}),
    }
    if confirm is not None:
        data.update(
            time_domain_power=(("case",), confirm["power"],
                               {"long_name": "mean power of every PTO in the time domain at the "
                                "optimum, after the settling time", "units": "W"}),
            time_domain_objective=((), confirm["objective"], {"units": "W"}),
            time_domain_relative_difference=((), confirm["relative_difference"],
                                             {"long_name": "(time domain − spectral) / spectral"}))
        settings = dict(settings, time_domain_settle_s=confirm["settle_s"],
                        time_domain_options=confirm["options"])
    coords = {"parameter": list(labels), "constraint": con_labels, "case": np.arange(B),
              "pto": list(pto_names), **_coordinate_coords(model)}
    ds = xr.Dataset(data, coords=coords)
    ds = label_cases(ds, sea_labels(seas))
    ds.attrs = {"title": f"mfm optimum of {model.name} in {B} sea states",
                **provenance(model, loads, **settings, wall_time_s=time.perf_counter() - start),
                "source": model.hydro.source}
    return ds


# ------------------------------------------------------------------------------- saving
class ResultNotSaved(OSError):
    """A result file that could not be written where asked. The message names the file, the
    error and where the result went instead: ``saved`` (a file in the system's temporary folder)
    or None, in which case ``dataset`` is all there is (returned to a caller in Python)."""

    def __init__(self, message, target=None, saved=None, dataset=None):
        super().__init__(message)
        self.target, self.saved, self.dataset = target, saved, dataset


def is_partial(ds) -> bool:
    """Whether a result is a run that stopped before its end (``complete = "false"``)."""
    return str(ds.attrs.get("complete", "")).lower() == "false"


def _holds_partial(path: Path) -> bool:
    """Whether the file at ``path`` is no better than a partial run: one marked incomplete, or one
    that cannot be read as NetCDF (a torn file). A file without the mark (a complete run, another
    command's result, someone's own file) is kept."""
    try:
        import netCDF4

        with netCDF4.Dataset(path) as f:
            return str(getattr(f, "complete", "")).lower() == "false"
    except Exception:
        try:
            with xr.open_dataset(path) as f:
                return is_partial(f)
        except Exception:
            return True


def partial_path(path) -> Path:
    """Where a partial run goes when ``path`` holds a complete one: ``<name>.partial.nc``."""
    path = Path(path)
    return path.with_name(f"{path.stem}.partial{path.suffix}")


def _why(e: BaseException) -> str:
    import errno

    text = getattr(e, "strerror", None) or str(e) or type(e).__name__
    if isinstance(e, OSError) and e.errno == errno.ENOSPC:
        return f"{text}: the disk is full"
    if "HDF error" in str(e) or "NetCDF" in str(e):
        return f"{text} (the NetCDF library's error: a full disk, a quota, or a folder gone)"
    return text


def save_netcdf(ds, path, *, announce=None) -> Path:
    """Write the result ``ds`` to ``path`` without ever putting a worse file in place of a good
    one, and return the path written:

    - written whole to a temporary file beside ``path``, renamed onto it only once complete
      (:func:`hydro.database.write_netcdf`): a failed write leaves the earlier file as it was;
    - a partial run (``complete = "false"``) never replaces a complete file: it goes to
      ``<name>.partial.nc`` beside it (:func:`partial_path`), and ``announce`` (a function of
      one line of text, e.g. ``print``) is told so;
    - a write that fails (a full disk, a folder made read-only, a NetCDF error) is tried again in
      the system's temporary folder, and :class:`ResultNotSaved` raised, naming the file, the
      error and where the result is now (that file, or only the dataset in memory).
    """
    from hydro.database import write_netcdf

    path = Path(path)
    target = path
    if is_partial(ds) and path.exists() and not _holds_partial(path):
        target = partial_path(path)
        if announce is not None:
            announce(f"{path} holds a complete run and is kept; this partial run is written "
                     f"beside it, to {target}")
    try:
        return write_netcdf(ds, target)
    except Exception as e:
        why = _why(e)
        error = e
    import tempfile

    saved = None
    try:
        saved = Path(tempfile.mkdtemp(prefix="mfm-unsaved-")) / target.name
        write_netcdf(ds, saved)
        where = f"the result was saved to {saved} instead"
    except Exception as e2:
        saved = None
        where = (f"it could not be saved in the temporary folder either ({_why(e2)}): the result "
                 "exists only in memory (the dataset returned, or attached to this error as "
                 "`.dataset`)")
    kept = " (the file there before is unchanged)" if target.exists() else ""
    raise ResultNotSaved(f"{target} could not be written ({why}){kept}; {where}",
                         target=target, saved=saved, dataset=ds) from error
