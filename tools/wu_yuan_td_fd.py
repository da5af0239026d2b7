"""Wu & Yuan model 1 (configs/wu_yuan_m1_td.toml, the band database hydro/data/wu_yuan_m1_td.nc):
the time domain against the frequency domain, the catenary lines' nonlinearity, and the cost.

    OMP_NUM_THREADS=1 python tools/wu_yuan_td_fd.py [--repeats 2] [--skip-database]
        [--skip-tdfd] [--skip-nonlinear] [--skip-timing] [--ss "dict(order=12, ...)"]
        [--fit-ladder "dict(order=24, enforce_passivity=False)" ...] [--save runs.npz]

18 coordinates (platform 6 + 12 hinges), 15 hulls solved together (90 hydro dofs, all moved),
six MoorPy catenary lines, state-space radiation (--ss: common poles, order 12, passivity not
enforced: the data themselves are not passive, min eig of B −1.77, and enforcement does not reach
it in 60 iterations), RK4. About 17 min and 5.1 GB on the shared 2-core machine. Prints:

1. the band database: its coefficients against wu_yuan_m1.nc's at the seed's periods (the same
   hulls; the lid and the interpolation in ω differ), and what float32 storage would change in the
   frequency response (against the BEM's own error);
2. the radiation fits (--fit-ladder, then --ss): time, states, band error, passivity, and the
   frequency response with the fit's A, B against the database's at the three periods;
3. regular waves H 0.5 m at T = 6, 8.3, 11.4 s, heading 0, one simulate_batch (dt = T/100,
   60 periods, ramp 5 T, from the static equilibrium), the lines linearised about it in both
   domains (mfm.frequency.rest.linearise_lines): the complex amplitude of each hinge angle and of
   the platform's surge, heave and pitch over the last 10 periods (least squares with free terms
   for the natural modes still alive there, :func:`alive`, mfm.studies.wec.harmonic_amplitude) and each
   PTO's mean power there, against mfm.frequency_response(..., radiation="state_space") with the
   same fit: |TD/FD − 1| (the issue's acceptance: 1 %); and the same amplitudes from the 10
   periods before (what transient is left);
4. H 3.8 m (the seed's average sea) at T = 8.3 s, 160 periods, ramp 40 T: the nonlinear lines
   against the linearised ones in the time domain (platform surge mean, first-harmonic
   amplitudes, the largest fairlead tension, the array's mean power);
5. one regular-wave run of 600 s at dt = T/100 (T = 8.3 s, H 3.8 m, nonlinear lines):
   mfm.simulate, first and warm (median of --repeats), and the pure rollout.

Numbers and the command (then benchmarks/wu_yuan_td_fd.py) are recorded in benchmarks/RESULTS.md.
From the repository root, with mfm installed (the script does not touch sys.path).
"""
import argparse
import math
import os
import statistics
import time
import warnings
from pathlib import Path

import jax.numpy as jnp
import numpy as np

os.environ.setdefault("MFM_COMPILATION_CACHE", "off")  # compile times measured, not loaded from disk (mfm.runner.xla)
os.environ.setdefault("MFM_FIT_CACHE", "off")          # fit times measured, not read from disk (hydro.fitcache)
import hydro
import mfm
from mfm.frequency.rest import linearise_lines
from mfm.timedomain.setup import model_loads

warnings.simplefilter("ignore", hydro.database.HydroDatabaseWarning)
ROOT = Path(__file__).resolve().parents[1]
CONFIG = ROOT / "configs" / "wu_yuan_m1_td.toml"
PERIODS = (6.0, 8.3, 11.4)
COMPARED = ["platform.surge", "platform.heave", "platform.pitch"] + [f"wec{k}.angle" for k in range(1, 13)]


def first_and_warm(fn, repeats):
    """(wall time of the first call — compilation included —, median of ``repeats`` warm calls;
    nan when repeats is 0): benchmarks/timing.py's, kept here so that the script runs alone."""
    t0 = time.perf_counter()
    fn()
    first = time.perf_counter() - t0
    ts = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        ts.append(time.perf_counter() - t0)
    return first, statistics.median(ts) if repeats > 0 else float("nan")


def lap(t0, what):
    t = time.perf_counter()
    print(f"  [{what}: {t - t0:.1f} s]", flush=True)
    return t


def alive(wn, zeta, t_start, omega):
    """The natural frequencies whose free transient can still be seen at t_start (e^{−ζ ω t} >
    1e-8; ζ ≤ 0 always), away from the wave's ω by > 10 %: the free terms of
    mfm.studies.wec.harmonic_amplitude. The long-dead modes are left out: the hinges' fourteen modes at
    4.1–4.9 s (ζ 0.55–0.75, dead in seconds) would put 56 near-ω columns into the least squares
    over 10 periods, which then take part of the wave's own harmonic (14 % at T 6 s, measured)."""
    wn, zeta = np.asarray(wn), np.asarray(zeta)
    keep = (np.exp(-np.maximum(zeta, 0.0) * wn * t_start) > 1e-8) & (np.abs(wn - omega) > 0.1 * omega)
    return wn[keep]


def database_checks(model):
    """The band database against wu_yuan_m1.nc at the seed's periods, and float32 storage."""
    from hydro import bem

    band = bem.load(ROOT / "hydro" / "data" / "wu_yuan_m1_td.nc")
    seed = bem.load(ROOT / "hydro" / "data" / "wu_yuan_m1.nc")
    w_seed = seed["omega"].values[np.isfinite(seed["omega"].values)]
    wb = band["omega"].values
    print(f"band database: {np.isfinite(wb).sum()} ω {wb[0]:.3g}…{wb[np.isfinite(wb)][-1]:.3g} rad/s "
          f"+ ∞, {band.attrs['nb_hull_panels']} hull + {band.attrs['nb_lid_panels']} lid panels, "
          f"{band.attrs.get('mfm_wall_time_s')} s")
    # the diagonal coefficients at the seed's ω, interpolated (cubic in ω) from the band
    for var in ("added_mass", "radiation_damping"):
        a = band[var].isel(omega=np.isfinite(wb)).interp(omega=w_seed, method="cubic")
        b = seed[var].sel(omega=w_seed)
        da = np.einsum("wii->wi", a.values)
        db = np.einsum("wii->wi", b.values)
        scale = np.abs(db).max(axis=0)
        keep = scale > 1e-6 * scale.max()
        rel = np.abs(da - db)[:, keep] / scale[keep]
        print(f"  {var}: diagonal, band (interpolated) against wu_yuan_m1.nc at the seed's ω: "
              f"largest difference {rel.max():.2e} of each dof's largest value (median {np.median(rel):.1e})")
    Xa = band["excitation_force"].isel(omega=np.isfinite(wb)).interp(omega=w_seed, method="cubic")
    Xb = seed["excitation_force"].sel(omega=w_seed)
    sc = np.abs(Xb.values).max(axis=(0, 1))
    keep = sc > 1e-6 * sc.max()
    rel = (np.abs(Xa.values - Xb.values).max(axis=(0, 1)))[keep] / sc[keep]
    print(f"  excitation: largest difference {rel.max():.2e} of each dof's largest value")
    # the frequency response from the band database (radiation "database") against the seed
    # database's, and against the band database stored as float32
    w = 2 * math.pi / np.array(PERIODS)
    fr_band = mfm.frequency_response(model, w, joint_reactions=False)
    seed_model = mfm.load(ROOT / "configs" / "wu_yuan_m1.toml")
    fr_seed = mfm.frequency_response(seed_model, w, joint_reactions=False)
    d = np.abs(fr_band["pto_power"].values / fr_seed["pto_power"].values - 1)
    da = np.abs(fr_band["pto_power"].values.sum(axis=1) / fr_seed["pto_power"].values.sum(axis=1) - 1)
    print(f"  frequency response (database A, B, X) at T = {PERIODS}: PTO power from the band "
          f"database against wu_yuan_m1.nc's, largest |ratio − 1| per period "
          f"{np.round(d.max(axis=1), 4).tolist()} (array {np.round(da, 4).tolist()})")
    # float32 storage: the band database written with its float variables as float32, read back
    # (mfm upcasts), its frequency response against the float64 file's
    import tempfile

    with tempfile.TemporaryDirectory() as tmp:
        import xarray as xr

        ds32 = band.copy()
        for v in ds32.data_vars:            # the ω-dependent arrays (the file's bulk) only
            if "omega" not in ds32[v].dims:
                continue
            x = ds32[v].values
            x32 = (x.real.astype(np.float32).astype(float)
                   + 1j * x.imag.astype(np.float32).astype(float)) if np.iscomplexobj(x) \
                else x.astype(np.float32).astype(float)
            ds32[v] = ds32[v].copy(data=x32)
        tmp64 = Path(tmp) / "rounded.nc"
        bem.save(ds32, tmp64)                 # float64 holding float32 values; then stored as float32
        raw = xr.load_dataset(tmp64)
        enc = {v: {"dtype": "float32"} for v in raw.data_vars if "omega" in raw[v].dims}
        f32 = Path(tmp) / "wu_yuan_m1_td_float32.nc"
        raw.to_netcdf(f32, encoding=enc)
        size64 = (ROOT / "hydro" / "data" / "wu_yuan_m1_td.nc").stat().st_size
        cfg = Path(tmp) / "m1_float32.toml"
        cfg.write_text(CONFIG.read_text().replace('"../hydro/data/wu_yuan_m1_td.nc"', f'"{f32.as_posix()}"'))
        fr32 = mfm.frequency_response(mfm.load(cfg), w, joint_reactions=False)
        ic = [model.coordinates.index(c) for c in COMPARED]   # sway, roll, yaw are 0 at heading 0
        d32 = np.abs(fr32["rao"].values[:, ic] / fr_band["rao"].values[:, ic] - 1)
        p32 = np.abs(fr32["pto_power"].values / fr_band["pto_power"].values - 1)
        print(f"  float32 storage: {f32.stat().st_size / 1e6:.2f} MB against {size64 / 1e6:.2f} MB; "
              f"frequency response changes by ≤ {d32.max():.1e} (RAOs of surge, heave, pitch, hinges), "
              f"{p32.max():.1e} (PTO power)")
    return fr_band


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--repeats", type=int, default=2)
    ap.add_argument("--skip-database", action="store_true")
    ap.add_argument("--skip-nonlinear", action="store_true")
    ap.add_argument("--skip-tdfd", action="store_true", help="skip 3. (TD against FD)")
    ap.add_argument("--skip-timing", action="store_true")
    ap.add_argument("--save", default=None, help="write the TD runs of 3. to this .npz (diagnosis)")
    ap.add_argument("--config", default=str(CONFIG), help="another config of model 1 (debugging)")
    ap.add_argument("--periods", type=int, default=60, help="periods per regular-wave run of 3.")
    ap.add_argument("--nl-periods", type=int, default=160, help="periods of the runs of 4.")
    ap.add_argument("--ss", default="dict(order=12, enforce_passivity=False)",
                    help="state_space_options of the comparison (a Python dict)")
    ap.add_argument("--fit-ladder", nargs="*", default=[],
                    help="other state_space_options to report (fit time, states, error)")
    args = ap.parse_args()
    t0 = time.perf_counter()
    model = mfm.load(args.config)
    t0 = lap(t0, "load")
    q0, _ = mfm.equilibrium(model)
    t0 = lap(t0, "equilibrium")
    lin = linearise_lines(model, q0)
    t0 = lap(t0, "linearise the lines")
    if not args.skip_database:
        database_checks(model)
        t0 = lap(t0, "database checks")

    SS = eval(args.ss)
    if args.skip_tdfd and args.skip_nonlinear and args.skip_timing and not args.fit_ladder:
        return
    fr_db = mfm.frequency_response(lin, 2 * math.pi / np.array(PERIODS), q0=q0, joint_reactions=False)
    t0 = lap(t0, "frequency response (database)")
    for opts in [eval(o) for o in args.fit_ladder] + [SS]:
        tf = time.perf_counter()
        r = model.hydro.state_space(**opts).report
        fr = mfm.frequency_response(lin, 2 * math.pi / np.array(PERIODS), q0=q0, radiation="state_space",
                                    state_space_options=opts, joint_reactions=False)
        dp = np.abs(fr.pto_power.values.sum(axis=1) / fr_db.pto_power.values.sum(axis=1) - 1)
        ic = [lin.coordinates.index(c) for c in COMPARED]     # sway, roll, yaw are 0 at heading 0
        dr = np.abs(fr.rao.values[:, ic] / fr_db.rao.values[:, ic] - 1)
        print(f"radiation fit {opts}: {time.perf_counter() - tf:.1f} s, {r['n_states']} states "
              f"({r['pole_sharing']} poles, order {max(r['orders'].values())}), band "
              f"{tuple(round(v, 3) for v in r['omega_fit'])} rad/s, error {r['overall_error']:.3f}, "
              f"stable {r['stable']}, passive {r['passive']} (min eig {r['passivity_min_eig']:.2f}; "
              f"the data's {r['passivity_min_eig_data']:.2f}); against the database's A, B at T = "
              f"{PERIODS} s: array power {np.round(dp, 4).tolist()}, RAOs (surge, heave, pitch, hinges) ≤ "
              f"{np.round(dr.max(axis=1), 3).tolist()}")
    t0 = lap(t0, "radiation fits")

    # 3. TD against FD, lines linearised in both
    H = 0.5
    w = 2 * math.pi / np.array(PERIODS)
    n_per, per = args.periods, 100
    if not (args.skip_tdfd and args.skip_nonlinear):
        nat = mfm.natural_frequencies(lin, q0=q0)
        wn = np.asarray(nat.eigen.values)
        zeta = np.asarray(nat.damping_ratio.values) + np.asarray(nat.radiation_damping_ratio.values)
        print("natural periods (s) and damping ratios (PTO + radiation at the mode's ω; decay time "
              "1/(ζω) s): " + ", ".join(f"{p:.2f} s ζ {z:.3f} ({1 / max(z * o, 1e-12):.0f} s)"
                                        for p, z, o in zip(nat.period.values, zeta, wn)))
        t0 = lap(t0, "natural frequencies")
    fd = None
    if not args.skip_tdfd:
        fd = mfm.frequency_response(lin, w, q0=q0, radiation="state_space", state_space_options=SS,
                                    joint_reactions=False)
        t0 = lap(t0, "frequency response (state space)")
        seas = [hydro.Regular(height=H, period=T) for T in PERIODS]
        ds = mfm.simulate_batch(lin, seas, dt=[T / per for T in PERIODS], n_steps=n_per * per,
                                ramp=[5 * T for T in PERIODS], q0=q0, state_space_options=SS,
                                progress={"mininterval": 30})
        t0 = lap(t0, f"simulate_batch, 3 × {n_per * per} steps (first call)")
        if args.save:
            np.savez(args.save, time=ds.time.values, q=ds.q.values, pto_power=ds.pto_power.values,
                     rao=fd.rao.values, fd_power=fd.pto_power.values, omega=w, wn=wn, H=H,
                     coordinates=np.array(lin.coordinates))
        worst = 0.0
        for k, T in enumerate(PERIODS):
            om = w[k]
            t = ds.time.values[k]
            rao = fd.rao.values[k] * H / 2
            p_fd = fd.pto_power.values[k] * (H / 2) ** 2
            errs, drift = {}, {}
            for name in COMPARED:
                i = lin.coordinates.index(name)
                xs = []
                for j in (0, 1):         # the last 10 periods, and the 10 before (transients left?)
                    sel = (t > t[-1] - (10 * j + 10) * T) & (t <= t[-1] - 10 * j * T)
                    xs.append(mfm.studies.wec.harmonic_amplitude(t[sel], ds.q.values[k, sel, i], om,
                                                         alive(wn, zeta, t[sel][0], om)))
                errs[name] = abs(xs[0] / rao[i] - 1)
                drift[name] = abs(xs[0] / xs[1] - 1)
            sel = t > t[-1] - 10 * T
            p_td = ds.pto_power.values[k, sel].mean(axis=0)
            perr = np.abs(p_td / p_fd - 1)
            worst = max(worst, max(errs.values()), perr.max())
            big = max(errs, key=errs.get)
            print(f"T {T:g} s: |TD/FD − 1| surge {errs['platform.surge']:.1e}, heave "
                  f"{errs['platform.heave']:.1e}, pitch {errs['platform.pitch']:.1e}, hinges ≤ "
                  f"{max(errs[f'wec{j}.angle'] for j in range(1, 13)):.1e} (largest: {big}); PTO power "
                  f"≤ {perr.max():.1e} (array {p_td.sum() / 1e3:.3f} kW TD, {p_fd.sum() / 1e3:.3f} kW FD); "
                  f"last 10 periods against the 10 before: ≤ {max(drift.values()):.1e} "
                  f"({max(drift, key=drift.get)})")
            print(f"   FD amplitudes: surge {abs(rao[0]):.4f} m, heave {abs(rao[2]):.4f} m, pitch "
                  f"{math.degrees(abs(rao[4])):.4f}°, hinges {np.round(np.degrees(np.abs(rao[6:])), 3).tolist()}°")
        print(f"largest |TD/FD − 1| over the compared amplitudes and powers: {worst:.2e} (acceptance 1e-2)")

    # 4. nonlinear lines against linearised ones at H 3.8 m, T 8.3 s. The surge mode (113 s,
    # ζ 0.02: it decays in ≈ 950 s) is set ringing by the onset of the lines' mean force: a long
    # ramp (40 T = 332 s ≈ 3 surge periods) keeps it small, and the means are taken over the last
    # 27 periods (224 s ≈ 2 surge periods), the first harmonic with the live modes' free terms.
    if not args.skip_nonlinear:
        T, H = 8.3, 3.8
        om = 2 * math.pi / T
        dt, n, n_win = T / per, args.nl_periods * per, 27
        out = {}
        for label, m in (("linearised", lin), ("nonlinear", model)):
            d = mfm.simulate_batch(m, hydro.Regular(height=H, period=T), dt=dt, n_steps=n, ramp=40 * T,
                                   q0=q0, outputs=("fairlead_tension",), state_space_options=SS,
                                   progress={"mininterval": 30})
            t = d.time.values[0]
            sel = t > t[-1] - n_win * T
            q = d.q.values[0, sel]
            ex = alive(wn, zeta, t[sel][0], om)
            amp = {c: abs(mfm.studies.wec.harmonic_amplitude(t[sel], q[:, lin.coordinates.index(c)], om, ex))
                   for c in COMPARED}
            ten = d.fairlead_tension.values[0, sel]           # (step, line)
            out[label] = dict(mean=q[:, 0].mean() - q0[0], amp=amp, tmax=float(ten.max()),
                              tline=int(np.unravel_index(ten.argmax(), ten.shape)[1]) + 1,
                              tmean=float(ten.mean(axis=0).max()),
                              p=float(d.pto_power.values[0, sel].mean(axis=0).sum()))
            t0 = lap(t0, f"H {H} m, {label} lines, {n} steps (compile included)")
        for label, o in out.items():
            print(f"H {H} m, T {T} s, {label} lines (last {n_win} periods): surge mean {o['mean']:+.4f} m "
                  f"about the equilibrium, first-harmonic amplitudes surge {o['amp']['platform.surge']:.4f} m, "
                  f"heave {o['amp']['platform.heave']:.4f} m, pitch "
                  f"{math.degrees(o['amp']['platform.pitch']):.4f}°; largest fairlead tension "
                  f"{o['tmax'] / 1e3:.1f} kN (line {o['tline']}; largest mean {o['tmean'] / 1e3:.1f} kN); "
                  f"array mean power {o['p'] / 1e3:.2f} kW")
        a, b = out["linearised"], out["nonlinear"]
        da = {c: b["amp"][c] / a["amp"][c] - 1 for c in COMPARED}
        big = max(da, key=lambda c: abs(da[c]))
        print(f"  nonlinear / linearised − 1: surge amplitude {da['platform.surge']:+.2e}, heave "
              f"{da['platform.heave']:+.2e}, pitch {da['platform.pitch']:+.2e}, largest of the "
              f"compared {da[big]:+.2e} ({big}); largest tension {b['tmax'] / a['tmax'] - 1:+.2e}; "
              f"power {b['p'] / a['p'] - 1:+.2e}; surge mean {b['mean'] - a['mean']:+.4f} m")
        if fd is not None:
            k = PERIODS.index(T)
            r = {c: abs(fd.rao.values[k, lin.coordinates.index(c)]) * H / 2 for c in COMPARED}
            e = max(abs(a["amp"][c] / r[c] - 1) for c in COMPARED)
            print(f"  the linearised lines' run against the frequency domain at H {H} m: amplitudes "
                  f"within {e:.1e}; power {a['p'] / (fd.pto_power.values[k].sum() * (H / 2) ** 2) - 1:+.1e}")

    # 5. one 600 s regular wave at dt = T/100, warm
    if args.skip_timing:
        return
    T = 8.3
    dt = T / per
    n = int(round(600.0 / dt))
    sea = hydro.Regular(height=3.8, period=T)
    first, warm = first_and_warm(lambda: mfm.simulate(model, sea, duration=n * dt, dt=dt, ramp=5 * T,
                                                      q0=q0, radiation="state_space",
                                                      state_space_options=SS), args.repeats)
    print(f"one regular wave, 600 s at dt = T/100 = {dt:.3f} s ({n} steps), mfm.simulate (nonlinear "
          f"lines, state space): first {first:.1f} s, warm {warm:.2f} s")
    loads = model_loads(model, sea, dt=dt, duration=n * dt, ramp=5 * T, radiation="state_space",
                        state_space_options=SS)
    res = {}

    def run():
        res["r"] = mfm.rollout(model, jnp.asarray(q0), jnp.zeros(model.n_coordinates), dt=dt,
                               n_steps=n, loads=loads)
        res["r"][1].block_until_ready()

    first, warm = first_and_warm(run, args.repeats)
    print(f"  the pure rollout: first {first:.1f} s, warm {warm:.2f} s ({warm / n * 1e6:.0f} µs/step)")


if __name__ == "__main__":
    main()
