"""Wu & Yuan (seed 004) in the frequency domain: the five spacings at the seed's ten periods
(H 3.8 m, heading 0), from configs/wu_yuan_m1..m5.toml and their databases.

Prints per model: the array's power, CWR (seed eq. 34 as printed: deep-water flux ρg²H²T/(32π)
over 8 m × 12), the interaction factors q_a (eq. 33, upper limit 12) and q_r (eq. 32, rows 1 and 3)
with P_s from the lone WEC (tools/wu_yuan.py, an assumed definition), the platform's surge, heave
and pitch RAOs and the largest fairlead-tension RAO with its line. The regular-wave steady states
of the linearised system (moorings linearised at the static equilibrium, hinge preloads
included): mfm.frequency_response, P = ½ c ω² |θ̂|² (H/2)² per hinge.

    python tools/wu_yuan_study.py [--models 1 2 3 4 5] [--out out/wu_yuan_fd.nc]

The first model compiles the 18-coordinate linearisation (≈ 1–4 min on the 2-core machine); the
others reuse it.
"""
from __future__ import annotations

import argparse
import sys
import time
import warnings
from pathlib import Path

import numpy as np
import xarray as xr

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tools"))
H = 3.8                      # m, the seed's average wave height
ROWS = {1: slice(0, 4), 2: slice(4, 8), 3: slice(8, 12)}


def main(argv=None) -> int:
    import mfm
    import wu_yuan
    from hydro.database import HydroDatabaseWarning, split_complex, write_netcdf

    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--models", type=int, nargs="+", default=[1, 2, 3, 4, 5])
    ap.add_argument("--out", type=Path, default=None, help="NetCDF of every model's RAOs")
    args = ap.parse_args(argv)
    warnings.simplefilter("ignore", HydroDatabaseWarning)
    np.set_printoptions(precision=3, linewidth=200, suppress=True)
    a2 = (H / 2) ** 2
    Ps = wu_yuan.wec_alone_power(H)                                  # (wec, period), W
    out = []
    for k in args.models:
        t0 = time.perf_counter()
        cfg = ROOT / "configs" / f"wu_yuan_m{k}.toml"
        model = mfm.load(cfg)
        w = np.asarray(xr.open_dataset(ROOT / "hydro" / "data" / f"wu_yuan_m{k}.nc").omega.values)
        w = np.sort(w[np.isfinite(w)])[::-1]                             # T ascending
        fr = mfm.frequency_response(model, w, 0.0, joint_reactions=False)
        T = 2 * np.pi / w
        P = fr.pto_power.values * a2                                     # (T, wec), W
        ps = np.stack([Ps.sel(period=t, method="nearest").values for t in T])
        flux = 1025.0 * 9.81**2 * H**2 * T / (32 * np.pi)                # W/m, deep water
        br = fr.body_rao.sel(body="platform")
        tr = np.abs(fr.fairlead_tension_rao.values)
        print(f"model {k} ({time.perf_counter() - t0:.0f} s)   T = {T.round(1)} s")
        print(f"  array power kW   {(P.sum(1) / 1e3).round(0)}")
        print(f"  CWR              {(P.sum(1) / (flux * 8 * 12)).round(3)}")
        print(f"  q_a              {(P.sum(1) / ps.sum(1)).round(3)}")
        for r in (1, 3):
            print(f"  q_r row {r}        {(P[:, ROWS[r]].sum(1) / ps[:, ROWS[r]].sum(1)).round(3)}")
        print(f"  |surge| m/m      {np.abs(br.sel(dof='x').values).round(3)}")
        print(f"  |heave| m/m      {np.abs(br.sel(dof='z').values).round(3)}")
        print(f"  |pitch| deg/m    {np.degrees(np.abs(br.sel(dof='ry').values)).round(3)}")
        print(f"  max |T| kN/m     {(tr.max(1) / 1e3).round(1)} "
              f"({', '.join(fr.mooring_line.values[tr.argmax(1)])})", flush=True)
        out.append(fr.assign_coords(omega=w).expand_dims(model=[k]))
    print(f"P_s (lone WEC) kW  row 3 {(np.stack([Ps.sel(period=t, method='nearest').values for t in T])[:, 8] / 1e3).round(1)}")
    print(f"                   rows 1-2 {(np.stack([Ps.sel(period=t, method='nearest').values for t in T])[:, 0] / 1e3).round(1)}")
    if args.out:
        write_netcdf(split_complex(xr.concat(out, dim="model", combine_attrs="drop_conflicts")), args.out)
        print(f"-> {args.out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
