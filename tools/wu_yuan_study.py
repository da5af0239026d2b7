"""Wu & Yuan (seed 004) in the frequency domain, printed: the five spacings at the seed's ten periods
(H 3.8 m, heading 0) and the severe sea with locked hinges (H 8.1 m, T 11.4 s), from
configs/wu_yuan_m1..m5.toml and their databases. The study itself (:func:`fd_study`,
:func:`severe_study`, P_s of the lone WEC, the interaction factors and CWR) is
mfm/studies/wu_yuan.py; notebooks/wu_yuan.ipynb draws the seed's Figs. 4–14 from it.

    python tools/wu_yuan_study.py [--models 1 2 3 4 5] [--out out/wu_yuan_fd.nc]

(with mfm installed; the script does not touch sys.path) prints per model the array's power, CWR,
q_a, q_r of rows 1 and 3, the platform's surge, heave and pitch RAOs and the largest
fairlead-tension RAO, then the locked severe sea. Each model compiles its own linearisation
(≈ 40–90 s on the 2-core machine: the database rides on the model as identity-hashed static data).
"""
from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--models", type=int, nargs="+", default=[1, 2, 3, 4, 5])
    ap.add_argument("--out", type=Path, default=None, help="NetCDF of the study (average sea)")
    args = ap.parse_args(argv)
    bad = [m for m in args.models if m not in (1, 2, 3, 4, 5)]
    if bad:
        ap.error(f"--models: {bad}; the seed's models are 1 2 3 4 5")
    from hydro.database import split_complex, write_netcdf
    from mfm.studies.wu_yuan import H_AVERAGE, SEVERE, fd_study, severe_study

    np.set_printoptions(precision=3, linewidth=200, suppress=True)
    ds = fd_study(args.models, verbose=True)
    print(f"H {H_AVERAGE} m, T = {ds.period.values} s")
    for k in args.models:
        d = ds.sel(model=k)
        top = d.tension_rao.argmax("line").values
        print(f"model {k}")
        print(f"  array power kW   {(d.array_power.values / 1e3).round(0)}")
        print(f"  CWR              {d.CWR.values.round(3)}")
        print(f"  q_a              {d.q_a.values.round(3)}")
        for r in (1, 3):
            print(f"  q_r row {r}        {d.q_r.sel(row=r).values.round(3)}")
        for mo, u in (("surge", "m/m  "), ("heave", "m/m  "), ("pitch", "deg/m")):
            print(f"  |{mo}| {u}     {d.platform_rao.sel(motion=mo).values.round(3)}")
        print(f"  max |T| kN/m     {(d.tension_rao.max('line').values / 1e3).round(1)} "
              f"({', '.join(d.line.values[top])})")
    print(f"P_s (lone WEC) kW  row 3 {(ds.P_s.sel(wec='wec9').values / 1e3).round(1)}")
    print(f"                   row 1 {(ds.P_s.sel(wec='wec1').values / 1e3).round(1)}")
    sv = severe_study(args.models, verbose=True)
    print(f"severe sea H {SEVERE[0]} m, T {SEVERE[1]} s, hinges locked: RAOs per model {args.models}")
    at = sv.sel(period=SEVERE[1])
    for mo in ("surge", "heave", "pitch"):
        print(f"  |{mo}|  {at.platform_rao.sel(motion=mo).values.round(3)}")
    print(f"  max |T| kN/m {(at.tension_rao.max('line').values / 1e3).round(1)}")
    if args.out:
        args.out.parent.mkdir(parents=True, exist_ok=True)
        write_netcdf(split_complex(ds), args.out)
        print(f"-> {args.out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
