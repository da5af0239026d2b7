"""Where linear potential flow stops being enough: the linear and the nonlinear level (issue 53)
against wave steepness H/λ, on the floating sphere (configs/sphere.toml with its hull).

    python tools/steepness.py [--period 4.0] [--heights 0.05 0.4 0.8 1.2 1.6 2.0 2.5]

The sphere is held in surge (heave and pitch free; unmoored, the nonlinear level's mean wave
force carries it downstream). Each height: a regular wave of the period, 48 s at dt 0.02 s with an 8 s ramp, radiation
"state_space", the checks off; the heave and pitch amplitudes at the wave frequency over the last
24 s (least squares, mfm.studies.wec.harmonic_amplitude), linear against nonlinear, and the
relative difference. Prints a table (the one in docs/nonlinear.md) and writes
notebooks/figures/steepness_sphere.png where matplotlib is installed.
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


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--period", type=float, default=4.0)
    ap.add_argument("--heights", type=float, nargs="+",
                    default=[0.05, 0.4, 0.8, 1.2, 1.6, 2.0, 2.5])
    args = ap.parse_args()

    import hydro
    import mfm
    from mfm.studies.wec import harmonic_amplitude

    warnings.simplefilter("ignore")
    cfg = tomllib.loads((ROOT / "configs" / "sphere.toml").read_text())
    # held in surge (heave and pitch free), as a tank test's soft mooring holds it: unmoored, the
    # nonlinear level's mean wave force (the hull's waterline moving against the wave) carries
    # the sphere downstream (0.8 m/s at H 1 m), and the encounter frequency with it
    cfg["bodies"][0]["joint"] = {"type": "free", "dofs": ["heave", "pitch"]}
    lin = mfm.load(cfg, base=ROOT / "configs")
    cfg = copy.deepcopy(cfg)
    cfg["hydro"]["hydrostatics"] = "nonlinear"
    cfg["bodies"][0]["hull"] = {"shape": "sphere", "radius": 1.0}
    nl = mfm.load(cfg, base=ROOT / "configs")
    T = args.period
    w = 2 * math.pi / T
    lam = 2 * math.pi / float(hydro.wavenumber(w, lin.hydro.water_depth, lin.hydro.g))
    run = dict(duration=48.0, dt=0.02, ramp=8.0, radiation="state_space", check_stability=False)
    rows = []
    for H in args.heights:
        sea = hydro.Regular(height=H, period=T)
        amps = []
        for m in (lin, nl):
            ds = mfm.simulate(m, sea, **run)
            late = ds.time.values >= 24.0
            amps.append([abs(harmonic_amplitude(ds.time.values[late],
                                                ds.q.sel(coordinate=c).values[late], w))
                         for c in ("sphere.heave", "sphere.pitch")])
        (zl, pl), (zn, pn) = amps
        rows.append((H, H / lam, zl / (H / 2), zn / (H / 2), zl / zn - 1, pl / pn - 1))
    print(f"sphere R 1 m, regular waves of T {T:g} s (λ {lam:.1f} m); heave RAO = amplitude/(H/2)")
    print(f"{'H m':>6s} {'H/λ':>7s} {'heave RAO lin':>14s} {'heave RAO nl':>13s} "
          f"{'heave lin/nl−1':>15s} {'pitch lin/nl−1':>15s}")
    for H, s, zl, zn, dz, dp in rows:
        print(f"{H:6.2f} {s:7.4f} {zl:14.4f} {zn:13.4f} {dz:+15.2%} {dp:+15.2%}")
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        return
    r = np.asarray(rows)
    fig, ax = plt.subplots(figsize=(6, 3.5))
    ax.plot(r[:, 1], 100 * r[:, 4], "o-", label="heave")
    ax.plot(r[:, 1], 100 * r[:, 5], "s-", label="pitch")
    ax.axhline(5, color="grey", lw=0.8, ls="--")
    ax.axhline(-5, color="grey", lw=0.8, ls="--")
    ax.set_xlabel("wave steepness H/λ")
    ax.set_ylabel("linear / nonlinear − 1 (%)")
    ax.set_title(f"floating sphere, T {T:g} s: linear against nonlinear hydrostatics and FK")
    ax.legend()
    fig.tight_layout()
    out = ROOT / "notebooks" / "figures" / "steepness_sphere.png"
    out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out, dpi=120)
    print(f"wrote {out.relative_to(ROOT)}")


if __name__ == "__main__":
    main()
