"""Wu & Yuan (seed 004) in the frequency domain: the five spacings at the seed's ten periods
(H 3.8 m, heading 0) and the severe sea with locked hinges (H 8.1 m, T 11.4 s), from
configs/wu_yuan_m1..m5.toml and their databases. notebooks/wu_yuan.ipynb draws the seed's
Figs. 4–14 from :func:`fd_study` and :func:`severe_study`.

The regular-wave steady states of the linearised system (moorings linearised at the static
equilibrium, hinge preloads included): mfm.frequency_response, per hinge
P = ½ c ω² |θ̂|² (H/2)². Interaction factors (seed eqs. 31–33, the upper limit "2a" of eq. 33
read as 12): q_s = P_m^i / P_s^i, q_r = Σ_row P_m / Σ_row P_s, q_a = Σ P_m / Σ P_s, with P_s from
the lone WEC (mfm/studies/wu_yuan.py, an ASSUMED definition). CWR by eq. 34 as printed: the array's
power over the deep-water flux ρ g² H² T / (32 π) times 8 m × 12.

    python tools/wu_yuan_study.py [--models 1 2 3 4 5] [--out out/wu_yuan_fd.nc]

prints per model the array's power, CWR, q_a, q_r of rows 1 and 3, the platform's surge, heave
and pitch RAOs and the largest fairlead-tension RAO, then the locked severe sea. Each model
compiles its own linearisation (≈ 40–90 s on the 2-core machine: the database rides on the model
as identity-hashed static data).
"""
from __future__ import annotations

import argparse
import functools
import time
import warnings
from pathlib import Path

import numpy as np
import xarray as xr

ROOT = Path(__file__).resolve().parents[1]
H_AVERAGE = 3.8              # m, the seed's average wave height
SEVERE = (8.1, 11.4)         # m, s: the seed's severe sea (hinges locked)
ROWS = {1: [f"wec{k}" for k in range(1, 5)], 2: [f"wec{k}" for k in range(5, 9)],
        3: [f"wec{k}" for k in range(9, 13)]}
RHO, G, WIDTH, N_WEC = 1025.0, 9.81, 8.0, 12     # eq. 34: ρ, g, WEC diameter, number of WECs


def seed_periods() -> np.ndarray:
    """The seed's ten periods (s, ascending): those of the databases (2π/ω, rounded to 0.1 s)."""
    return _seed_periods().copy()


@functools.lru_cache(maxsize=1)
def _seed_periods() -> np.ndarray:
    # read once per process: every study call asks for them, and the file is read whole
    from hydro.database import read_netcdf     # never a bare xr.open_dataset (hydro/database.py)

    w = np.asarray(read_netcdf(ROOT / "hydro" / "data" / "wu_yuan_m1.nc").omega.values)
    return np.sort(np.round(2 * np.pi / w[np.isfinite(w) & (w > 0)], 1))


def _platform_rao(fr) -> xr.DataArray:
    """|surge| (m/m), |heave| (m/m), |pitch| (deg/m) of the platform's CoM: (omega, motion)."""
    br = fr.body_rao.sel(body="platform")
    return xr.concat([np.abs(br.sel(dof="x")), np.abs(br.sel(dof="z")),
                      np.degrees(np.abs(br.sel(dof="ry")))], dim="motion").drop_vars(
        "dof", errors="ignore").assign_coords(motion=["surge", "heave", "pitch"]).transpose("omega", "motion")


def fd_study(models=(1, 2, 3, 4, 5), periods=None, H: float = H_AVERAGE, *,
             platform_damping: float | None = None, verbose: bool = False) -> xr.Dataset:
    """The five spacings in regular waves of height ``H`` (m), heading 0, at ``periods`` (s;
    default the seed's ten). ``platform_damping``: a viscous damping of the platform's heave, roll
    and pitch as a fraction of critical (mfm.loads.body_matrix.LinearBodyMatrix ``damping_ratio``;
    the seed's C_vis, whose values it does not give; default none). Returns a Dataset (model,
    period, wec, row, motion, line):

    power (W) per WEC, P_s (W) the lone WEC's (assumed definition), q_s, row_power (W) and q_r
    per row, array_power (W), q_a, CWR; platform_rao (surge, heave m/m; pitch deg/m);
    tension_rao (N/m) per line; heave_rao (complex, m/m) of the platform's and WEC1's CoM (Fig. 5);
    settings and provenance in the attributes.
    """
    import mfm
    from mfm.studies import wu_yuan
    from hydro.database import HydroDatabaseWarning

    T = seed_periods() if periods is None else np.sort(np.atleast_1d(np.asarray(periods, float)))
    w = 2 * np.pi / T
    a2 = (H / 2) ** 2
    Ps = wu_yuan.wec_alone_power(H, T).transpose("period", "wec")
    out = []
    for k in models:
        t0 = time.perf_counter()
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", HydroDatabaseWarning)
            model = wu_yuan.platform_model(k)
            loads = []
            if platform_damping:
                from mfm.loads.body_matrix import LinearBodyMatrix

                z = float(platform_damping)
                loads = [LinearBodyMatrix.create(model, "platform", name="platform_viscous",
                                                 damping_ratio={"heave": z, "roll": z, "pitch": z})]
            fr = mfm.frequency_response(model, w, 0.0, loads=loads, joint_reactions=False)
        wec = [p.split(".")[0] for p in fr.pto.values]
        P = xr.DataArray(fr.pto_power.values * a2, dims=("period", "wec"), coords={"period": T, "wec": wec})
        heave = fr.body_rao.sel(dof="z", body=["platform", "wec1"]).values
        ds = xr.Dataset({
            "power": P,
            "platform_rao": (("period", "motion"), _platform_rao(fr).values),
            "tension_rao": (("period", "line"), np.abs(fr.fairlead_tension_rao.values)),
            "heave_rao": (("period", "heave_of"), heave)},
            coords={"period": T, "wec": wec, "motion": ["surge", "heave", "pitch"],
                    "line": fr.mooring_line.values, "heave_of": ["platform", "wec1"]})
        out.append(ds.expand_dims(model=[k]))
        if verbose:
            print(f"  model {k}: {time.perf_counter() - t0:.0f} s", flush=True)
    ds = xr.concat(out, dim="model")
    ds["P_s"] = Ps.assign_coords(period=T).drop_vars(["omega", "lone_heading_deg"], errors="ignore")
    ds["q_s"] = ds.power / ds.P_s
    rows = list(ROWS)
    ds["row_power"] = xr.concat([ds.power.sel(wec=ROWS[r]).sum("wec") for r in rows], dim="row").assign_coords(row=rows)
    ds["q_r"] = ds.row_power / xr.concat([ds.P_s.sel(wec=ROWS[r]).sum("wec") for r in rows], dim="row").assign_coords(row=rows)
    ds["array_power"] = ds.power.sum("wec")
    ds["q_a"] = ds.array_power / ds.P_s.sum("wec")
    flux = RHO * G**2 * H**2 * ds.period / (32 * np.pi)                 # W/m, deep water, eq. 34
    ds["CWR"] = ds.array_power / (flux * WIDTH * N_WEC)
    units = {"power": "W", "P_s": "W", "row_power": "W", "array_power": "W", "q_s": "1", "q_r": "1",
             "q_a": "1", "CWR": "1", "platform_rao": "m/m (surge, heave), deg/m (pitch)",
             "tension_rao": "N/m", "heave_rao": "m/m (complex, x(t) = Re[x̂ e^{-iωt}])"}
    for name, u in units.items():
        ds[name].attrs["units"] = u
    ds.period.attrs["units"] = "s"
    ds.attrs.update(title="Wu & Yuan: five WEC spacings in regular waves (frequency domain)",
                    wave_height_m=H, heading_deg=0.0, made_by="tools/wu_yuan_study.py fd_study",
                    platform_damping_ratio=float(platform_damping or 0.0),
                    P_s_definition=Ps.attrs["definition"], mfm_version=fr.attrs.get("mfm_version", ""),
                    configs=", ".join(f"configs/wu_yuan_m{k}.toml" for k in models))
    return ds


def severe_study(models=(1, 2, 3, 4, 5), H: float = SEVERE[0], T: float = SEVERE[1], periods=None, *,
                 verbose: bool = False) -> xr.Dataset:
    """The severe sea of the seed (H 8.1 m, T 11.4 s), every hinge locked (mfm.studies.wu_yuan
    ``platform_model(m, locked=True)``): the platform's RAOs and each line's tension RAO per model
    at ``periods`` (s; default the seed's ten, which include T) — Fig. 14 reads them at T; the
    curves show where the locked platform's resonances sit — and the motions' and tensions'
    amplitudes at (H, T) (linear: RAO × H/2)."""
    import mfm
    from mfm.studies import wu_yuan
    from hydro.database import HydroDatabaseWarning

    Ts = seed_periods() if periods is None else np.sort(np.atleast_1d(np.asarray(periods, float)))
    if not np.any(np.isclose(Ts, T)):
        Ts = np.sort(np.append(Ts, T))
    out = []
    for k in models:
        t0 = time.perf_counter()
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", HydroDatabaseWarning)
            model = wu_yuan.platform_model(k, locked=True)
            fr = mfm.frequency_response(model, 2 * np.pi / Ts, 0.0, joint_reactions=False)
        out.append(xr.Dataset({
            "platform_rao": (("period", "motion"), _platform_rao(fr).values),
            "tension_rao": (("period", "line"), np.abs(fr.fairlead_tension_rao.values)),
            "heave_offset": fr.equilibrium.sel(coordinate="platform.heave").values},
            coords={"period": Ts, "motion": ["surge", "heave", "pitch"],
                    "line": fr.mooring_line.values}).expand_dims(model=[k]))
        if verbose:
            print(f"  locked model {k}: {time.perf_counter() - t0:.0f} s", flush=True)
    ds = xr.concat(out, dim="model")
    at = ds.sel(period=Ts[np.argmin(np.abs(Ts - T))])
    ds["platform_amplitude"] = at.platform_rao * H / 2
    ds["tension_amplitude"] = at.tension_rao * H / 2
    for name, u in {"platform_rao": "m/m (surge, heave), deg/m (pitch)", "tension_rao": "N/m",
                    "heave_offset": "m", "platform_amplitude": "m (surge, heave), deg (pitch)",
                    "tension_amplitude": "N"}.items():
        ds[name].attrs["units"] = u
    ds.period.attrs["units"] = "s"
    ds.attrs.update(title="Wu & Yuan: severe sea, hinges locked (frequency domain)", wave_height_m=H,
                    wave_period_s=T, heading_deg=0.0, made_by="tools/wu_yuan_study.py severe_study")
    return ds


def main(argv=None) -> int:
    from hydro.database import split_complex, write_netcdf

    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--models", type=int, nargs="+", default=[1, 2, 3, 4, 5])
    ap.add_argument("--out", type=Path, default=None, help="NetCDF of the study (average sea)")
    args = ap.parse_args(argv)
    bad = [m for m in args.models if m not in (1, 2, 3, 4, 5)]
    if bad:
        ap.error(f"--models: {bad}; the seed's models are 1 2 3 4 5")
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
