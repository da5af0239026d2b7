"""Mesh convergence of a config's BEM database: solve again at finer panel sizes at a few
frequencies and print a markdown table of each body's diagonal added mass, radiation damping and
excitation modulus against the finest mesh.

    python tools/mesh_convergence.py configs/stansby_li.toml --dx 1.4 1.0 --omega 0.5 1.0 1.5

Every solve uses the config's own [hydro.bem] settings with ``dx``, ``omega``, one heading
(``--heading``, degrees) and ω = ∞ (the reader needs it) overridden (`mfm.io.bemgen.generate(overrides=...)`), into a
temporary directory; capytaine is needed. Modes: ``--modes`` (default Surge Heave Pitch).
"""
import argparse
import tempfile
import time
from pathlib import Path

import numpy as np

from hydro.prepare import open_any_database
from mfm.io.bemgen import generate


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("config")
    ap.add_argument("--dx", type=float, nargs="+", required=True, help="panel sizes (m), coarse to fine")
    ap.add_argument("--omega", type=float, nargs="+", required=True, help="rad/s")
    ap.add_argument("--heading", type=float, default=0.0, help="degrees")
    ap.add_argument("--modes", nargs="+", default=["Surge", "Heave", "Pitch"])
    args = ap.parse_args()
    tmp = Path(tempfile.mkdtemp())
    dbs = []
    for dx in args.dx:
        t0 = time.perf_counter()
        out = generate(args.config, out=tmp / f"dx{dx}.nc", force=True, progress=False, cache=False,
                       overrides={"dx": dx, "omega": list(args.omega), "headings_deg": [args.heading],
                                  "infinite_frequency": True})
        print(f"dx {dx} m: {time.perf_counter() - t0:.0f} s")
        dbs.append(open_any_database(out))
    ref = dbs[-1]
    head = " | ".join(f"dx {dx}" for dx in args.dx)
    rel = " | ".join(f"{dx}→{args.dx[-1]}" for dx in args.dx[:-1])
    print(f"\n| body | mode | quantity | ω (rad/s) | {head} | {rel} |")
    print("|---|---|---|---|" + "---|" * (2 * len(args.dx) - 1))
    bodies = [str(b) for b in ref.body.values]
    for b in bodies:
        for mode in args.modes:
            dof = f"{b}__{mode}"
            for name, get in (("A", lambda d, w: float(d.added_mass.sel(omega=w, radiating_dof=dof, influenced_dof=dof))),
                              ("B", lambda d, w: float(d.radiation_damping.sel(omega=w, radiating_dof=dof, influenced_dof=dof))),
                              ("abs X", lambda d, w: float(abs(d.excitation.sel(omega=w, influenced_dof=dof).isel(wave_direction=0))))):
                for w in args.omega:
                    vals = [get(d, d.omega.values[np.argmin(abs(d.omega.values - w))]) for d in dbs]
                    diffs = [f"{100 * (v / vals[-1] - 1):+.2f}%" if vals[-1] else "—" for v in vals[:-1]]
                    print(f"| {b} | {mode} | {name} | {w:g} | " + " | ".join(f"{v:.4g}" for v in vals)
                          + " | " + " | ".join(diffs) + " |")


if __name__ == "__main__":
    main()
