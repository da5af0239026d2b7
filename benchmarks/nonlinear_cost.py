"""Issue 53's first rung, nonlinear hydrostatics and Froude–Krylov on the wetted hull: its cost per
step against the linear level, and the convergence of its loads with the panel size (not a test).

    python benchmarks/nonlinear_cost.py [--repeats 3] [--panels 0.25 0.125 0.0625]
    python benchmarks/nonlinear_cost.py --system m4_134 [--panels 0.04 0.02 0.01]
    python benchmarks/nonlinear_cost.py --system m4_134 --panels 0.04 --every 1 2 4
    python benchmarks/nonlinear_cost.py --panels 0.125 --every 1 2 4 8 --height 1.0
    python benchmarks/nonlinear_cost.py --system wu_yuan_m1 --panels 2.0 --every 2 4

The floating sphere (configs/sphere.toml, R 1 m, surge–heave–pitch) in a regular wave H 0.5 m,
T 4 s, 40 s at dt 0.02 s (2,000 RK4 steps), radiation "state_space", the checks off. Rows:

- ``linear``: the database's buoyancy, C_wp and excitation;
- ``nonlinear, panel s``: ``[hydro] hydrostatics = "nonlinear"`` with the sphere hull of panel
  size s (m): its panel count, the median warm wall and CPU time per step of ``mfm.simulate``
  over ``--repeats`` calls after a first (compiling) one, its ratio to the linear level's, and the
  heave and pitch amplitudes at the wave frequency (the last 20 s) with their change from the
  finest panels' (the convergence).

``--every k …``: for each panel size, rows of the held level too (``[hydro] nonlinear_dt`` =
k·dt: the hull pressure sampled every k steps, the linear level's loads at every stage,
:class:`mfm.loads.water.HeldHulls`), with the largest difference of each reported coordinate's
series from the same panels' every-stage run, as a fraction of its range ("series Δ").

``--system m4_134`` (issue 53's speed goal, ≤ 10× the linear level's step): M4 134, its bow
float held in surge, with each float's hull its [bodies.geometry] under an assumed 0.1 m freeboard, in a regular wave H 0.04 m,
T 1.2 s, 12 s at dt 0.006 s (2,000 RK4 steps), the bow float's heave and pitch and float 3's
hinge angle over the last 6 s; panel sizes 0.04, 0.02, 0.01 m by default.

``--system wu_yuan_m1`` (issue 53's second speed row): Wu & Yuan model 1 on its time-domain
database (configs/wu_yuan_m1_td.toml: 3 columns and 12 hinged WECs, 90 hydro dofs), each hull its
[bodies.geometry] (the columns closed up to 15 m above the water, the WECs to their 2 m), the
seed's regular wave H 3.8 m T 8.3 s, 49.8 s at dt 0.083 s (600 steps), the platform's heave and
pitch and WEC 1's hinge; panel sizes 2 and 1 m by default.

Figures depend on the machine and its load: quote them with the machine (RESULTS.md).
"""
from __future__ import annotations

import argparse
import copy
import os
import time
import tomllib
import warnings
from pathlib import Path

import numpy as np

os.environ.setdefault("MFM_FIT_CACHE", "off")

ROOT = Path(__file__).resolve().parents[1]


SYSTEMS = {
    # config, regular wave (H, T), dt, duration, ramp, hull table (of the panel size and the
    # body's name), reported coordinates, panel sizes
    "sphere": ("sphere.toml", (0.5, 4.0), 0.02, 40.0, 8.0,
               lambda s, name: {"shape": "sphere", "radius": 1.0, "panel_size": s},
               ("sphere.heave", "sphere.pitch"), [0.25, 0.125, 0.0625]),
    "m4_134": ("m4_134.toml", (0.04, 1.2), 0.006, 12.0, 2.4,
               lambda s, name: {"shape": "geometry", "top": 0.1, "panel_size": s},
               ("float1.heave", "float1.pitch", "float3.angle"), [0.04, 0.02, 0.01]),
    # the seed's regular wave; the columns' hulls up to 15 m (the fairleads' height), the WECs'
    # to their stated 2 m freeboard
    "wu_yuan_m1": ("wu_yuan_m1_td.toml", (3.8, 8.3), 0.083, 49.8, 16.6,
                   lambda s, name: {"shape": "geometry", "panel_size": s,
                                       "top": 15.0 if name.startswith("column") else 2.0},
                   ("platform.heave", "platform.pitch", "wec1.angle"), [2.0, 1.0]),
}


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--system", choices=sorted(SYSTEMS), default="sphere")
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--panels", type=float, nargs="+", default=None)
    ap.add_argument("--height", type=float, default=None,
                    help="the regular wave's height (m) in place of the system's")
    ap.add_argument("--every", type=int, nargs="+", default=[],
                    help="also the held level, the hull pressure sampled every k steps")
    args = ap.parse_args()

    import hydro
    import mfm
    from mfm.studies.wec import harmonic_amplitude

    warnings.simplefilter("ignore")
    config, (H, T), dt, duration, ramp, hull, coords, panels = SYSTEMS[args.system]
    H = H if args.height is None else args.height
    base = tomllib.loads((ROOT / "configs" / config).read_text())
    if args.system == "m4_134":
        # the bow float held in surge (heave and pitch free), as tools/steepness.py holds it:
        # free, the nonlinear level's mean wave force carries the device downstream and the
        # amplitudes at the wave frequency with it (+84 % heave against the linear level here)
        base["bodies"][0]["joint"] = {"type": "free", "dofs": ["heave", "pitch"]}
    sea = hydro.Regular(height=H, period=T)
    n = int(round(duration / dt))
    w = 2 * np.pi / T

    def timed(model):
        run = dict(duration=duration, dt=dt, ramp=ramp, radiation="state_space",
                   check_stability=False)
        out = mfm.simulate(model, sea, **run)
        walls, cpus = [], []
        for _ in range(args.repeats):
            t0, c0 = time.perf_counter(), time.process_time()
            out = mfm.simulate(model, sea, **run)
            walls.append(time.perf_counter() - t0)
            cpus.append(time.process_time() - c0)
        late = out.time.values >= duration / 2
        amps = [abs(harmonic_amplitude(out.time.values[late],
                                       out.q.sel(coordinate=c).values[late], w))
                for c in coords]
        series = np.stack([out.q.sel(coordinate=c).values for c in coords])
        return np.median(walls) / n, np.median(cpus) / n, amps, series

    rows = [("linear", None, *timed(mfm.load(base, base=ROOT / "configs")), "")]
    for s in args.panels or panels:
        cfg = copy.deepcopy(base)
        cfg["hydro"]["hydrostatics"] = "nonlinear"
        for b in cfg["bodies"]:
            if b["name"] == "sphere" or "geometry" in b:
                b["hull"] = hull(s, b["name"])
        model = mfm.load(cfg, base=ROOT / "configs")
        tri = sum(int(h.shape[0]) for h in model.hydro.hulls)
        every_stage = timed(model)
        rows.append((f"nonlinear, panel {s:g} m", tri, *every_stage, ""))
        for k in args.every:
            held = copy.deepcopy(cfg)
            held["hydro"]["nonlinear_dt"] = k * dt
            wall, cpu, amps, series = timed(mfm.load(held, base=ROOT / "configs"))
            ref = every_stage[3]
            worst = np.max(np.abs(series - ref), axis=1) / np.ptp(ref, axis=1)
            rows.append((f"  sampled every {k} steps", tri, wall, cpu, amps, series,
                         " ".join(f"{x:.1e}" for x in worst)))
    fine = [r for r in rows if r[0].startswith("nonlinear")][-1][4]
    lin_wall = rows[0][2]
    print(f"{args.system}, regular H {H:g} m T {T:g} s, {n} RK4 steps of {dt} s; median of "
          f"{args.repeats} warm calls")
    names = [c.split(".", 1)[1] if args.system == "sphere" else c for c in coords]
    print(f"{'row':28s} {'triangles':>9s} {'wall µs/step':>13s} {'CPU µs/step':>12s} "
          f"{'× linear':>9s} " + " ".join(f"{c:>13s}" for c in names) + " "
          + " ".join(f"{'Δ ' + c:>15s}" for c in names)
          + ("  series Δ against every stage" if args.every else ""))
    for name, tri, wall, cpu, amps, _, held in rows:
        d = [a / f - 1 for a, f in zip(amps, fine)]
        print(f"{name:28s} {tri if tri else '':>9} {wall * 1e6:13.1f} {cpu * 1e6:12.1f} "
              f"{wall / lin_wall:9.1f} " + " ".join(f"{a:13.5f}" for a in amps) + " "
              + " ".join(f"{x:+15.2%}" for x in d) + (f"  {held}" if held else ""))


if __name__ == "__main__":
    main()
