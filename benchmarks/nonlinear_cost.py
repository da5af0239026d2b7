"""Issue 53's first rung, nonlinear hydrostatics and Froude–Krylov on the wetted hull: its cost per
step against the linear level, and the convergence of its loads with the panel size (not a test).

    python benchmarks/nonlinear_cost.py [--repeats 3] [--panels 0.25 0.125 0.0625]

The floating sphere (configs/sphere.toml, R 1 m, surge–heave–pitch) in a regular wave H 0.5 m,
T 4 s, 40 s at dt 0.02 s (2,000 RK4 steps), radiation "state_space", the checks off. Rows:

- ``linear``: the database's buoyancy, C_wp and excitation;
- ``nonlinear, panel s``: ``[hydro] hydrostatics = "nonlinear"`` with the sphere hull of panel
  size s (m): its panel count, the median warm wall and CPU time per step of ``mfm.simulate``
  over ``--repeats`` calls after a first (compiling) one, its ratio to the linear level's, and the
  heave and pitch amplitudes at the wave frequency (the last 20 s) with their change from the
  finest panels' (the convergence).

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


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--panels", type=float, nargs="+", default=[0.25, 0.125, 0.0625])
    args = ap.parse_args()

    import hydro
    import mfm
    from mfm.studies.wec import harmonic_amplitude

    warnings.simplefilter("ignore")
    base = tomllib.loads((ROOT / "configs" / "sphere.toml").read_text())
    sea = hydro.Regular(height=0.5, period=4.0)
    dt, duration = 0.02, 40.0
    n = int(round(duration / dt))
    w = 2 * np.pi / 4.0

    def timed(model):
        run = dict(duration=duration, dt=dt, ramp=8.0, radiation="state_space",
                   check_stability=False)
        out = mfm.simulate(model, sea, **run)
        walls, cpus = [], []
        for _ in range(args.repeats):
            t0, c0 = time.perf_counter(), time.process_time()
            out = mfm.simulate(model, sea, **run)
            walls.append(time.perf_counter() - t0)
            cpus.append(time.process_time() - c0)
        late = out.time.values >= duration - 20.0
        amps = [abs(harmonic_amplitude(out.time.values[late],
                                       out.q.sel(coordinate=c).values[late], w))
                for c in ("sphere.heave", "sphere.pitch")]
        return np.median(walls) / n, np.median(cpus) / n, amps

    rows = [("linear", None, *timed(mfm.load(ROOT / "configs" / "sphere.toml")))]
    for s in args.panels:
        cfg = copy.deepcopy(base)
        cfg["hydro"]["hydrostatics"] = "nonlinear"
        cfg["bodies"][0]["hull"] = {"shape": "sphere", "radius": 1.0, "panel_size": s}
        model = mfm.load(cfg, base=ROOT / "configs")
        rows.append((f"nonlinear, panel {s:g} m", int(model.hydro.hulls[0].shape[0]), *timed(model)))
    fine = rows[-1][4]
    lin_wall, lin_cpu = rows[0][2], rows[0][3]
    print(f"sphere, regular H 0.5 m T 4 s, {n} RK4 steps of {dt} s; median of {args.repeats} warm "
          "calls")
    print(f"{'row':28s} {'triangles':>9s} {'wall µs/step':>13s} {'CPU µs/step':>12s} "
          f"{'× linear':>9s} {'heave m':>9s} {'pitch rad':>10s} {'Δ heave':>9s} {'Δ pitch':>9s}")
    for name, tri, wall, cpu, amps in rows:
        d = [a / f - 1 for a, f in zip(amps, fine)]
        print(f"{name:28s} {tri if tri else '':>9} {wall * 1e6:13.1f} {cpu * 1e6:12.1f} "
              f"{wall / lin_wall:9.1f} {amps[0]:9.5f} {amps[1]:10.5f} {d[0]:+9.2%} {d[1]:+9.2%}")


if __name__ == "__main__":
    main()
