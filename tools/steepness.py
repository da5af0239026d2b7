"""Where linear potential flow stops being enough: the linear and the nonlinear level (issue 53)
against wave steepness H/λ, on the floating sphere, RM3, M4 134 and the Stansby & Li hybrid.

    python tools/steepness.py [--system sphere|rm3|m4_134|stansby_li] [--period T] [--heights H ...]
                              [--sampled K]

Each height: a regular wave of the period, with the system's run settings below, radiation
"state_space", the checks off; the amplitudes at the wave frequency over the last periods (least
squares, :func:`mfm.studies.wec.harmonic_amplitude`) and the mean absorbed power there, linear
against nonlinear (``[hydro] hydrostatics = "nonlinear"``: the hydrostatic and the incident
wave's pressure on the instantaneous wetted hull), and their relative difference. Prints a table
(those in docs/nonlinear.md) and writes notebooks/figures/steepness_<system>.png where matplotlib
is installed.

``--sampled K``: also the nonlinear level with its hull pressure sampled every K steps
(``[hydro] nonlinear_dt`` = K dt, :class:`mfm.loads.water.HeldHulls`), printed as its relative
difference from the every-stage nonlinear level at each height (where the sampled rung stops
being within a tolerance); the figure is unchanged.

The sphere, RM3 and M4 134 are held in surge (their other coordinates free): unmoored, the nonlinear level's mean
wave force (the waterline moving against the wave) carries a body downstream, and the encounter
frequency with it (the unmoored sphere: 0.8 m/s at H 1 m; docs/nonlinear.md), which is a mooring's
question, not the hydrostatics'.

- ``sphere`` (configs/sphere.toml, its analytic hull): T 4 s, 48 s at dt 0.02 s, 8 s ramp, the
  last 24 s; heave and pitch.
- ``rm3`` (configs/rm3.toml): T 8 s (λ 99.9 m), 20 periods at dt 0.05 s, a 4-period ramp, the
  last 8 periods; the float's stroke on the spar, the spar's pitch and heave, the PTO's mean
  power. Hulls: WEC-Sim's float.stl and plate.stl (hydro/data/rm3; closed, about each body's
  centre of gravity). The float's sits at its CoG (z −0.72 m): 728.4 m³ at rest, its centre of
  buoyancy at z −1.302 m, against rm3.out's 725.8 m³ and −1.293 m (+0.35 %; the stroke's
  stiffness within 0.3 % of the database's). plate.stl about the spar's CoG (−21.29 m)
  displaces 911.6 m³ with its centre of buoyancy at −16.11 m, 0.51 m below rm3.out's −15.60 (a
  visual mesh, not WAMIT's panels): it is placed at −20.78 m (897.3 m³, +1.2 %, centre of
  buoyancy −15.85 m, within the load's 3 % check); the spar's heave stiffness is then 0.3 % and
  its pitch stiffness 3.2 % below the database's, an offset the small-wave rows carry in pitch.
- ``m4_134`` (configs/m4_134.toml, each float's hull its [bodies.geometry] under a 0.1 m
  freeboard at panel size 0.02 m): T 1.2 s, 20 periods at dt 0.006 s, a 4-period ramp, the last
  8 periods; the bow float's heave and pitch, the hinge angles of a mid-row and a stern float, the
  PTOs' total mean power.
- ``stansby_li`` (configs/stansby_li.toml: the 5 MW wind semi-submersible with two hinged
  floats, on its own station-keeping springs, no wind; each column's hull its [bodies.geometry]
  under its 9 m freeboard at panel size 1.5 m, the stiffness at rest within 0.5 % of the
  database's): T 9 s, 20 periods at dt 0.09 s, a 4-period ramp, the last 8 periods; the
  platform's heave and pitch, the two floats' hinge angles, the PTOs' total mean power.
"""
from __future__ import annotations

import argparse
import copy
import math
import os
import tomllib
import warnings
from pathlib import Path

import numpy as np

os.environ.setdefault("MFM_FIT_CACHE", "off")
ROOT = Path(__file__).resolve().parents[1]


def _held_in_surge(body):
    """The root body's planar or free joint without its surge (the others kept)."""
    joint = body.get("joint", {})
    dofs = {"planar": ["surge", "heave", "pitch"]}.get(joint.get("type"), joint.get("dofs"))
    if dofs is None:
        dofs = ["surge", "sway", "heave", "roll", "pitch", "yaw"]
    body["joint"] = {"type": "free", "dofs": [d for d in dofs if d != "surge"]}


def _pair(config, hull_of, held=None):
    """configs/``config`` (its body ``held`` held in surge) and its copy at the nonlinear level,
    each body's hull ``hull_of(body)`` (None: a dry body, no hull)."""
    cfg = tomllib.loads((ROOT / "configs" / config).read_text())
    if held is not None:
        _held_in_surge(next(b for b in cfg["bodies"] if b["name"] == held))
    nl = copy.deepcopy(cfg)
    nl["hydro"]["hydrostatics"] = "nonlinear"
    for b in nl["bodies"]:
        hull = hull_of(b)
        if hull is not None:
            b["hull"] = hull
    return cfg, nl


def _sphere():
    cfg, nl = _pair("sphere.toml", lambda b: {"shape": "sphere", "radius": 1.0}, held="sphere")
    return dict(cfg=cfg, nl=nl, period=4.0, heights=[0.05, 0.4, 0.8, 1.2, 1.6, 2.0, 2.5],
                run=dict(duration=48.0, dt=0.02, ramp=8.0), window=24.0,
                coords={"heave": "sphere.heave", "pitch": "sphere.pitch"}, power=False,
                rao="sphere.heave")


def _rm3():
    # WEC-Sim's meshes about each body's centre of gravity; the plate's moved up 0.51 m to the
    # database's centre of buoyancy (the module's docstring)
    cfg, nl = _pair("rm3.toml", lambda b: (
        {"mesh": "../hydro/data/rm3/float.stl", "center": [0.0, 0.0, -0.72]}
        if b["name"] == "float" else
        {"mesh": "../hydro/data/rm3/plate.stl", "center": [0.0, 0.0, -20.78]}), held="spar")
    T = 8.0
    return dict(cfg=cfg, nl=nl, period=T, heights=[0.25, 1.0, 2.0, 3.0, 4.0, 5.0, 6.0],
                run=dict(duration=20 * T, dt=0.05, ramp=4 * T), window=8 * T,
                coords={"stroke": "float.stroke", "spar pitch": "spar.pitch",
                        "spar heave": "spar.heave"}, power=True, rao=None)


def _m4():
    cfg, nl = _pair("m4_134.toml", lambda b: {"shape": "geometry", "top": 0.1, "panel_size": 0.02},
                    held="float1")
    T = 1.2
    return dict(cfg=cfg, nl=nl, period=T, heights=[0.005, 0.02, 0.04, 0.06, 0.08, 0.1, 0.12],
                run=dict(duration=20 * T, dt=0.006, ramp=4 * T), window=8 * T,
                coords={"bow heave": "float1.heave", "bow pitch": "float1.pitch",
                        "float3 angle": "float3.angle", "float7 angle": "float7.angle"},
                power=True, rao=None)


def _stansby_li():
    # the five columns (the turbine is dry); on its own station-keeping springs, not held
    cfg, nl = _pair("stansby_li.toml", lambda b: (
        {"shape": "geometry", "top": 9.0, "panel_size": 1.5} if "geometry" in b else None))
    T = 9.0
    return dict(cfg=cfg, nl=nl, period=T, heights=[0.5, 2.0, 3.0, 4.0, 5.0, 6.0, 7.5],
                run=dict(duration=20 * T, dt=0.09, ramp=4 * T), window=8 * T,
                coords={"heave": "float2.heave", "pitch": "float2.pitch",
                        "float B angle": "floatB.angle", "float C angle": "floatC.angle"},
                power=True, rao=None)


SYSTEMS = {"sphere": _sphere, "rm3": _rm3, "m4_134": _m4, "stansby_li": _stansby_li}


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--system", choices=sorted(SYSTEMS), default="sphere")
    ap.add_argument("--period", type=float, default=None, help="s (default: the system's)")
    ap.add_argument("--heights", type=float, nargs="+", default=None,
                    help="m (default: the system's)")
    ap.add_argument("--sampled", type=int, default=None,
                    help="also the nonlinear level sampled every K steps (nonlinear_dt = K dt)")
    args = ap.parse_args()

    import hydro
    import mfm
    from mfm.studies.wec import harmonic_amplitude

    warnings.simplefilter("ignore")
    case = SYSTEMS[args.system]()
    lin = mfm.load(case["cfg"], base=ROOT / "configs")
    nl = mfm.load(case["nl"], base=ROOT / "configs")
    models = [lin, nl]
    if args.sampled:
        held = copy.deepcopy(case["nl"])
        held["hydro"]["nonlinear_dt"] = args.sampled * case["run"]["dt"]
        models.append(mfm.load(held, base=ROOT / "configs"))
    T = args.period or case["period"]
    heights = args.heights or case["heights"]
    w = 2 * math.pi / T
    lam = 2 * math.pi / float(hydro.wavenumber(w, lin.hydro.water_depth, lin.hydro.g))
    run = dict(case["run"], radiation="state_space", check_stability=False)
    names = list(case["coords"]) + (["power"] if case["power"] else [])
    rows = []
    for H in heights:
        sea = hydro.Regular(height=H, period=T)
        out = []
        for m in models:
            ds = mfm.simulate(m, sea, **run)
            t = ds.time.values
            late = t >= t[-1] - case["window"]
            vals = [abs(harmonic_amplitude(t[late], ds.q.sel(coordinate=c).values[late], w))
                    for c in case["coords"].values()]
            if case["power"]:
                vals.append(float(ds.pto_power.isel(time=late).sum("pto").mean()))
            out.append(vals)
        lin_v, nl_v = np.asarray(out[0]), np.asarray(out[1])
        rao = None
        if case["rao"]:
            k = list(case["coords"].values()).index(case["rao"])
            rao = (lin_v[k] / (H / 2), nl_v[k] / (H / 2))
        rows.append((H, H / lam, lin_v, nl_v, lin_v / nl_v - 1, rao,
                     np.asarray(out[2]) / nl_v - 1 if args.sampled else None))

    print(f"{args.system}: regular waves of T {T:g} s (λ {lam:.2f} m), held in surge; "
          f"amplitudes at the wave frequency (m, rad) and mean power (W), linear against nonlinear")
    head = f"{'H m':>7s} {'H/λ':>7s}"
    if case["rao"]:
        head += f" {'heave RAO lin':>14s} {'heave RAO nl':>13s}"
    for n in names:
        head += f" {n + ' lin/nl−1':>18s}"
    print(head)
    for H, s, lv, nv, d, rao, _ in rows:
        line = f"{H:7.3f} {s:7.4f}"
        if rao:
            line += f" {rao[0]:14.4f} {rao[1]:13.4f}"
        line += "".join(f" {x:+18.2%}" for x in d)
        print(line)
    print("values (linear | nonlinear):")
    for H, s, lv, nv, d, rao, _ in rows:
        print(f"{H:7.3f} " + "  ".join(f"{n} {a:.5g} | {b:.5g}" for n, a, b in zip(names, lv, nv)))
    if args.sampled:
        print(f"sampled every {args.sampled} steps (ω h = {w * args.sampled * run['dt']:.3f}) "
              "against the nonlinear level at every stage:")
        print(f"{'H m':>7s} {'H/λ':>7s}" + "".join(f" {n + ' sampled/nl−1':>22s}" for n in names))
        for H, s, lv, nv, d, rao, ds in rows:
            print(f"{H:7.3f} {s:7.4f}" + "".join(f" {x:+22.3%}" for x in ds))
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        return
    steep = np.array([r[1] for r in rows])
    diff = np.array([r[4] for r in rows])
    fig, ax = plt.subplots(figsize=(6, 3.5))
    for j, n in enumerate(names):
        ax.plot(steep, 100 * diff[:, j], "o-", label=n)
    ax.axhline(5, color="grey", lw=0.8, ls="--")
    ax.axhline(-5, color="grey", lw=0.8, ls="--")
    ax.set_xlabel("wave steepness H/λ")
    ax.set_ylabel("linear / nonlinear − 1 (%)")
    ax.set_title(f"{args.system}, T {T:g} s: linear against nonlinear hydrostatics and FK",
                 fontsize=9)
    ax.legend(fontsize=8)
    fig.tight_layout()
    out = ROOT / "notebooks" / "figures" / f"steepness_{args.system}.png"
    out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out, dpi=120)
    print(f"wrote {out.relative_to(ROOT)}")


if __name__ == "__main__":
    main()
