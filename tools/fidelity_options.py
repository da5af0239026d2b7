"""The options within each level of the fidelity ladder (issue 14 item 3): for M4 134 and the
Stansby & Li hybrid semi-sub in head seas, each option's warm wall time and its error on the
scene's outputs against the full model with default options, at the levels where it applies.

    PYTHONPATH=. python tools/fidelity_options.py m4_134       # 25 min on 2 shared cores (load 4–6)
    PYTHONPATH=. python tools/fidelity_options.py stansby_li   # 20 min
    PYTHONPATH=. python tools/fidelity_options.py table        # the markdown tables from the JSON

(from the repository root; the script does not touch sys.path: ``PYTHONPATH=.`` runs this
checkout's mfm, or leave it out with mfm installed from here).

Each system's rows go to notebooks/figures/fidelity_options/<system>.json as they finish (a rerun
skips the rows already there; delete the file to start afresh).

The scene and its measure are those of :func:`mfm.reduce` (:mod:`mfm.fidelity`), reused: a pilot
of 40 peak periods at Tp/200 with a 5-period ramp, compared after 15 periods; the outputs are the
mean power of each PTO (error against the total mean power) and the standard deviation of each
hinge angle (error against its own); a row's error is the largest. The reference is the "full"
level (RK4, ``radiation="auto"``: the exact-update state space for both systems at this length)
with the default options of the config. Wall time: the second (warm) call of the whole run,
compiled and fitted, as :func:`mfm.reduce` reports it (setup of the loads included).

The options (the state-space order and the convolution window are charted in
tools/speed_accuracy.py, not here):

- ``default``: the config as shipped, each level (the ladder itself, for the side-by-side);
- ``no body coupling``: :meth:`hydro.prepare.HydroSpec.replace` ``(body_coupling=False)``, the
  same as ``mfm.load(path, body_coupling=False)``: the cross-body blocks of A∞, A(ω), B(ω), K are
  zero; with no coupling the state space is fitted per entry (each body's own poles) instead of
  one common pole set;
- ``drop_tol 0.1``: the state-space fit drops the radiation entries whose band peak is below
  0.1 √(K_ii K_jj) (the default 0.01), the "small IRF entries";
- ``3-D`` (M4 134, planar as shipped: its root made ``free``) and ``planar`` (Stansby & Li, 3-D
  as shipped: its root made ``planar``, surge, heave and pitch): the other kinematics, from the
  config's text with the root joint changed, written to a temporary directory. The hydro dofs the
  coordinates move follow (:func:`mfm.loads.water.moving_dofs`: 24 of 48 for planar M4 134,
  48 for 3-D);
- ``3-D, head-sea hydro dofs`` (M4 134): the 3-D model with radiation modelled on the surge, heave
  and pitch of each float only (what its coordinates move in head seas, by the layout's symmetry),
  :meth:`~hydro.prepare.HydroSpec.replace` ``(moving=...)``;
- ``N components``: the sea discretised with N components instead of the default 200. The
  excitation is tabulated before the run, so the time-domain levels pay for components only in
  the setup; and another N is another realisation of the sea, so the pilot's error of a time-domain
  run with N components is the realisation's (statistical), not a model error. The error that is
  the discretisation's alone is that of the expected statistics (the spectral level's, no time
  series): against 1,600 components, in ``spectral_expected``.
"""
from __future__ import annotations

import dataclasses
import importlib
import json
import math
import re
import sys
import tempfile
import time
import warnings
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
OUT = ROOT / "notebooks" / "figures" / "fidelity_options"

PILOT = dict(pilot_periods=40.0, settle_periods=15.0, steps_per_period=200)
COMPONENTS = (50, 100)
FINE_COMPONENTS = 1600

SYSTEMS = {
    # tools/fidelity.py's sea (Hs 0.04 m: motions of a few degrees)
    "m4_134": dict(config="m4_134.toml", T=1.2, other_root="free",
                   sea=dict(hs=0.04, tp=1.2, gamma=3.3, seed=1, omega_range=(1.0, 25.0)),
                   coordinates=("float3.angle", "float7.angle", "float6.angle", "float8.angle"),
                   text="JONSWAP Hs 0.04 m, Tp 1.2 s, γ 3.3, seed 1, head seas"),
    # notebooks/stansby_li.ipynb's sea12 (Fig. 4), heading 0, without its repeat period
    "stansby_li": dict(config="stansby_li.toml", T=12.0, other_root="planar",
                       sea=dict(hs=2.0, tp=12.0, gamma=3.3, seed=0, omega_range=(0.2, 2.0)),
                       coordinates=("floatB.angle", "floatC.angle"),
                       text="JONSWAP Hs 2 m, Tp 12 s, γ 3.3, seed 0, head seas"),
}


def _sea(system, n_components=None):
    import hydro

    return hydro.Jonswap(**SYSTEMS[system]["sea"], n_components=n_components)


def other_kinematics(system, directory):
    """The system's config with its root joint changed (M4 134 planar → free, Stansby & Li free →
    planar), written to ``directory``; the database path made absolute. Returns the new path."""
    cfg = SYSTEMS[system]
    path = ROOT / "configs" / cfg["config"]
    text = path.read_text()
    db = re.search(r'^database = "([^"]+)"', text, flags=re.M)
    text = text.replace(db.group(0), f'database = "{(path.parent / db.group(1)).resolve()}"')
    if cfg["other_root"] == "free":
        new, n = re.subn(r'^type = "planar"', 'type = "free"', text, count=1, flags=re.M)
    else:
        new, n = re.subn(r'^type = "free"\ndofs = \[[^\]]*\][^\n]*', 'type = "planar"', text,
                         count=1, flags=re.M)
    if n != 1:
        raise RuntimeError(f"{system}: the root joint was not found in {path}")
    out = Path(directory) / cfg["config"]
    out.write_text(new)
    return out


def with_hydro(model, **options):
    """The model with its HydroSpec's options changed (:meth:`hydro.prepare.HydroSpec.replace`)."""
    return dataclasses.replace(model, hydro=model.hydro.replace(**options))


def head_sea_dofs(model):
    """The surge, heave and pitch of each hydro body among the dofs the model moves."""
    keep = ("Surge", "Heave", "Pitch")
    return [k for k in model.hydro.moving if any(model.hydro.dofs[k].endswith(m) for m in keep)]


def run_level(model, sea, level, settings, ss_options=None):
    """One pilot run of ``level`` (the levels of mfm.fidelity) and its warm wall time: the second
    call, as mfm.reduce times it."""
    from mfm.studies.fidelity import LEVEL_OPTIONS, Reduction

    T = settings["T"]
    dt = T / PILOT["steps_per_period"]
    duration, ramp = PILOT["pilot_periods"] * T, 5.0 * T
    red = Reduction(level, dict(LEVEL_OPTIONS.get(level, {})), {}, {}, "", 0.0, dt,
                    (duration, ramp))
    if ss_options:
        if level in ("fast", "full"):
            red = dataclasses.replace(red, options=dict(red.options,
                                                        state_space_options=ss_options))
        elif level == "linear":
            red = None

    def go():
        if red is None:
            from mfm.runner.linear import linear_response
            return linear_response(model, sea, duration=duration, dt=dt, ramp=ramp,
                                   state_space_options=ss_options)
        return red.run(model, sea, duration=duration)

    start = time.perf_counter()
    ds = go()
    first = time.perf_counter() - start
    start = time.perf_counter()
    go()
    warm = time.perf_counter() - start
    return ds, dict(first_s=first, warm_s=warm, compile_s=max(first - warm, 0.0),
                    radiation=ds.attrs.get("radiation", ""),
                    states=ds.attrs.get("fit_n_states", ds.attrs.get("state_space_states", "")))


def measure(ds, settings):
    from mfm.studies.fidelity import _measures

    T = settings["T"]
    return _measures(ds, slice(PILOT["settle_periods"] * T, None), settings["coordinates"])


def expected(model, sea, coordinates):
    """The spectral level's expected statistics (no time series): mean power per PTO, std per
    coordinate, in the keys of mfm.studies.fidelity._measures."""
    from mfm.runner.spectral import spectral_response

    ds = spectral_response(model, sea)
    out = {f"pto_power[{p}]": float(ds.pto_power_mean.sel(pto=p)) for p in ds.pto.values}
    out.update({f"std[{c}]": float(ds.q_rms.sel(coordinate=c)) for c in coordinates})
    return out


def plan(system):
    """(row name, levels, how) in the order run: the cheap, telling ones first."""
    other = "3-D" if SYSTEMS[system]["other_root"] == "free" else "planar"
    rows = [("default", ("full", "fast", "spectral", "linear"), {}),
            ("no body coupling", ("full", "fast", "spectral", "linear"), dict(body_coupling=False)),
            ("drop_tol 0.1", ("full", "fast"), dict(ss=dict(drop_tol=0.1)))]
    rows += [(f"{n} components", ("full", "spectral"), dict(n_components=n)) for n in COMPONENTS]
    rows.append((other, ("full", "fast", "spectral"), dict(kinematics=True)))
    if other == "3-D":
        rows.append(("3-D, head-sea hydro dofs", ("full", "fast"),
                     dict(kinematics=True, head_sea=True)))
    return rows


def study(system, path, log=print):
    import mfm
    from mfm.studies.fidelity import _errors

    settings = SYSTEMS[system]
    data = json.loads(path.read_text()) if path.exists() else {}
    data.setdefault("settings", dict(system=system, sea=settings["text"], **PILOT,
                                     coordinates=list(settings["coordinates"])))
    rows = data.setdefault("rows", {})

    def save():
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(json.dumps(data, indent=1))

    base = mfm.load(ROOT / "configs" / settings["config"])
    tmp = tempfile.mkdtemp()
    reference = data.get("reference")
    for name, levels, how in plan(system):
        for level in levels:
            key = f"{name}|{level}"
            if key in rows:
                continue
            if reference is None and key != "default|full":
                raise RuntimeError("the reference (default|full) runs first")
            model = base
            if how.get("kinematics"):
                model = mfm.load(other_kinematics(system, tmp))
                if how.get("head_sea"):
                    model = with_hydro(model, moving=head_sea_dofs(model))
            if "body_coupling" in how:
                model = with_hydro(model, body_coupling=how["body_coupling"])
            sea = _sea(system, how.get("n_components"))
            log(f"{system}: {key} …")
            ds, rec = run_level(model, sea, level, settings, how.get("ss"))
            m = measure(ds, settings)
            if key == "default|full":
                reference = data["reference"] = m
            rec.update(measures=m, errors=_errors(m, reference),
                       moved_hydro_dofs=len(model.hydro.moving), coordinates=model.n_coordinates)
            rec["error"] = max(rec["errors"].values())
            if "n_components" in how and level == "spectral":
                fine = expected(model, _sea(system, FINE_COMPONENTS), settings["coordinates"])
                rec["spectral_expected"] = _errors(expected(model, sea, settings["coordinates"]),
                                                   fine)
                rec["spectral_expected_error"] = max(rec["spectral_expected"].values())
            rows[key] = rec
            save()
            log(f"{system}: {key}: error {rec['error']:.3g}, warm {rec['warm_s']:.3g} s "
                f"(first {rec['first_s']:.3g} s)")
            del ds
    if "expected_components" not in data:
        # the discretisation's own error: expected statistics with N components against 1,600
        log(f"{system}: expected statistics against the number of components …")
        fine = expected(base, _sea(system, FINE_COMPONENTS), settings["coordinates"])
        data["expected_components"] = {
            str(n): max(_errors(expected(base, _sea(system, n), settings["coordinates"]),
                                fine).values()) for n in COMPONENTS + (200, 400)}
        save()
    return data


def table(system):
    """The markdown table of a system's stored rows."""
    data = json.loads((OUT / f"{system}.json").read_text())
    rows = data["rows"]
    ref = rows["default|full"]["warm_s"]
    lines = [f"{system} ({data['settings']['sea']}; pilot {PILOT['pilot_periods']:g} Tp at "
             f"Tp/{PILOT['steps_per_period']}, compared after {PILOT['settle_periods']:g} Tp)", "",
             "| option | level | coordinates | moved hydro dofs | warm s | × faster than full | "
             "largest error | notes |", "|---|---|---:|---:|---:|---:|---:|---|"]
    for key, r in rows.items():
        name, level = key.split("|")
        note = []
        if r.get("states") not in ("", None, 0):
            note.append(f"{r['states']} states")
        if "spectral_expected_error" in r:
            note.append(f"expected statistics vs {FINE_COMPONENTS} components: "
                        f"{r['spectral_expected_error']:.2g}")
        elif "components" in name:
            note.append("another realisation")
        lines.append(f"| {name} | {level} | {r['coordinates']} | {r['moved_hydro_dofs']} | "
                     f"{r['warm_s']:.3g} | {ref / r['warm_s']:.3g} | {r['error']:.2g} | "
                     f"{'; '.join(note)} |")
    if "expected_components" in data:
        lines += ["", f"Expected statistics (spectral, no time series) with N components against "
                  f"{FINE_COMPONENTS}: " + ", ".join(f"N = {n}: {e:.2g}" for n, e in
                                                      data["expected_components"].items())]
    return "\n".join(lines)


def main(argv):
    if not argv or argv[0] not in tuple(SYSTEMS) + ("table",):
        print(__doc__)
        return 2
    if argv[0] == "table":
        for s in SYSTEMS:
            if (OUT / f"{s}.json").exists():
                print(table(s) + "\n")
        return 0
    warnings.simplefilter("ignore")
    start = time.perf_counter()
    study(argv[0], OUT / f"{argv[0]}.json", log=lambda s: print(s, flush=True))
    print(f"{argv[0]}: {time.perf_counter() - start:.0f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
