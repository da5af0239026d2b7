"""Wu & Yuan model 1 (configs/wu_yuan_m1_td.toml, the band database hydro/data/wu_yuan_m1_td.nc):
the time domain against the frequency domain, the catenary lines' nonlinearity, and the cost.

    python benchmarks/wu_yuan_td_fd.py [--repeats 2] [--skip-database] [--skip-nonlinear]

18 coordinates (platform 6 + 12 hinges), 15 hulls solved together (90 hydro dofs, all moved),
six MoorPy catenary lines, state-space radiation (the default fit, common poles), RK4. Prints:

1. the band database: its coefficients against wu_yuan_m1.nc's at the seed's periods (the same
   hulls; the lid and the interpolation in ω differ), and what float32 storage would change in the
   frequency response (against the BEM's own error);
2. the radiation fit: time, states, band error, passivity;
3. regular waves H 0.5 m at T = 6, 8.3, 11.4 s, heading 0, one simulate_batch (dt = T/100,
   60 periods, ramp 5 T, from the static equilibrium), the lines linearised about it in both
   domains (mfm.loads.catenary.linearise_lines): the complex amplitude of each hinge angle and of
   the platform's surge, heave and pitch over the last 10 periods (least squares with the natural
   modes' free terms, mfm.wec.harmonic_amplitude) and each PTO's mean power there, against
   mfm.frequency_response(..., radiation="state_space") with the same fit: |TD/FD − 1|;
4. H 3.8 m (the seed's average sea) at T = 8.3 s: the nonlinear lines against the linearised ones
   in the time domain (platform surge: mean and amplitude; the largest fairlead tension; the
   array's mean power);
5. one regular-wave run of 600 s at dt = T/100 (T = 8.3 s): mfm.simulate, first and warm
   (median of --repeats), and the pure rollout warm.

Numbers and the command are recorded in benchmarks/RESULTS.md.
"""
import argparse
import math
import time
import warnings
from pathlib import Path

import jax.numpy as jnp
import numpy as np

import hydro
import mfm
from mfm.loads.catenary import CatenaryLines, linearise_lines
from mfm.simulate import model_loads
from timing import first_and_warm

warnings.simplefilter("ignore", hydro.database.HydroDatabaseWarning)
ROOT = Path(__file__).resolve().parents[1]
CONFIG = ROOT / "configs" / "wu_yuan_m1_td.toml"
PERIODS = (6.0, 8.3, 11.4)
COMPARED = ["platform.surge", "platform.heave", "platform.pitch"] + [f"wec{k}.angle" for k in range(1, 13)]


def lap(t0, what):
    t = time.perf_counter()
    print(f"  [{what}: {t - t0:.1f} s]", flush=True)
    return t


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
    print(f"  frequency response (database A, B, X) at T = {PERIODS}: PTO power from the band "
          f"database against wu_yuan_m1.nc's: largest |ratio − 1| {d.max():.2e} (median {np.median(d):.1e})")
    # float32 storage: the band database written with its float variables as float32, read back
    # (mfm upcasts), its frequency response against the float64 file's
    import tempfile

    with tempfile.TemporaryDirectory() as tmp:
        ds32 = band.copy()
        for v in ds32.data_vars:            # the ω-dependent arrays (the file's bulk) only
            if "omega" not in ds32[v].dims:
                continue
            if ds32[v].dtype.kind == "c":
                ds32[v] = ds32[v].copy(data=(ds32[v].values.real.astype(np.float32)
                                             + 1j * ds32[v].values.imag.astype(np.float32)).astype(np.complex64))
            elif ds32[v].dtype.kind == "f":
                ds32[v] = ds32[v].astype(np.float32)
        f32 = Path(tmp) / "wu_yuan_m1_td_float32.nc"
        bem.save(ds32, f32)
        size64 = (ROOT / "hydro" / "data" / "wu_yuan_m1_td.nc").stat().st_size
        cfg = Path(tmp) / "m1_float32.toml"
        cfg.write_text(CONFIG.read_text().replace('"../hydro/data/wu_yuan_m1_td.nc"', f'"{f32.as_posix()}"'))
        fr32 = mfm.frequency_response(mfm.load(cfg), w, joint_reactions=False)
        d32 = np.abs(fr32["rao"].values / fr_band["rao"].values - 1)
        p32 = np.abs(fr32["pto_power"].values / fr_band["pto_power"].values - 1)
        print(f"  float32 storage: {f32.stat().st_size / 1e6:.2f} MB against {size64 / 1e6:.2f} MB; "
              f"frequency response changes by ≤ {d32.max():.1e} (RAOs), {p32.max():.1e} (PTO power)")
    return fr_band


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--repeats", type=int, default=2)
    ap.add_argument("--skip-database", action="store_true")
    ap.add_argument("--skip-nonlinear", action="store_true")
    ap.add_argument("--config", default=str(CONFIG), help="another config of model 1 (debugging)")
    ap.add_argument("--periods", type=int, default=60, help="periods per regular-wave run")
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

    r = model.hydro.state_space().report
    t0 = lap(t0, "state-space fit")
    print(f"radiation fit: {len(model.hydro.dofs)} hydro dofs, {len(model.hydro.moving)} moved; "
          f"{r['n_states']} states ({r['pole_sharing']} poles, {r.get('orders')}), band "
          f"{r.get('omega_fit')} rad/s, error {r['overall_error']:.4f}, passive {r['passive']} "
          f"(min eig {r['passivity_min_eig']:.2e}), fit {r['fit_seconds']:.1f} s")

    # 3. TD against FD, lines linearised in both
    H = 0.5
    w = 2 * math.pi / np.array(PERIODS)
    fd = mfm.frequency_response(lin, w, q0=q0, radiation="state_space", joint_reactions=False)
    t0 = lap(t0, "frequency response (state space)")
    fd_nl = mfm.frequency_response(model, w, q0=q0, radiation="state_space", joint_reactions=False)
    print(f"frequency response with the nonlinear lines against the linearised ones: largest "
          f"difference {np.abs(fd_nl.rao.values - fd.rao.values).max() / np.abs(fd.rao.values).max():.1e} "
          "of the largest RAO")
    nat = mfm.natural_frequencies(lin, q0=q0)
    wn = np.asarray(nat.eigen.values)
    print(f"natural periods (s): {np.round(nat.period.values, 2).tolist()}")
    t0 = lap(t0, "natural frequencies")
    n_per, per = args.periods, 100
    seas = [hydro.Regular(height=H, period=T) for T in PERIODS]
    ds = mfm.simulate_batch(lin, seas, dt=[T / per for T in PERIODS], n_steps=n_per * per,
                            ramp=[5 * T for T in PERIODS], q0=q0)
    t0 = lap(t0, f"simulate_batch, 3 × {n_per * per} steps (first call)")
    worst = 0.0
    for k, T in enumerate(PERIODS):
        om = w[k]
        t = ds.time.values[k]
        sel = t > t[-1] - 10 * T
        extra = wn[np.abs(wn - om) > 0.1 * om]
        rao = fd.rao.values[k] * H / 2
        errs = {}
        for name in COMPARED:
            i = lin.coordinates.index(name)
            x = mfm.wec.harmonic_amplitude(t[sel], ds.q.values[k, sel, i], om, extra)
            errs[name] = abs(x / rao[i] - 1)
        p_td = ds.pto_power.values[k, sel].mean(axis=0)
        p_fd = fd.pto_power.values[k] * (H / 2) ** 2
        perr = np.abs(p_td / p_fd - 1)
        worst = max(worst, max(errs.values()), perr.max())
        big = max(errs, key=errs.get)
        print(f"T {T:g} s: |TD/FD − 1| surge {errs['platform.surge']:.1e}, heave "
              f"{errs['platform.heave']:.1e}, pitch {errs['platform.pitch']:.1e}, hinges ≤ "
              f"{max(errs[f'wec{j}.angle'] for j in range(1, 13)):.1e} (largest: {big}); PTO power "
              f"≤ {perr.max():.1e} (array {p_td.sum() / 1e3:.2f} kW TD, {p_fd.sum() / 1e3:.2f} kW FD)")
        print(f"   FD amplitudes: surge {abs(rao[0]):.4f} m, heave {abs(rao[2]):.4f} m, pitch "
              f"{math.degrees(abs(rao[4])):.4f}°, hinges {np.round(np.degrees(np.abs(rao[6:])), 3).tolist()}°")
    print(f"largest |TD/FD − 1| over the compared amplitudes and powers: {worst:.2e} (acceptance 1e-2)")

    # 4. nonlinear lines against linearised ones at H 3.8 m, T 8.3 s
    if not args.skip_nonlinear:
        T, H = 8.3, 3.8
        dt, n = T / per, n_per * per
        out = {}
        for label, m in (("linearised", lin), ("nonlinear", model)):
            d = mfm.simulate_batch(m, hydro.Regular(height=H, period=T), dt=dt, n_steps=n, ramp=5 * T,
                                   q0=q0, outputs=("fairlead_tension",))
            t = d.time.values[0]
            sel = t > t[-1] - 10 * T
            s = d.q.values[0, sel, 0]
            out[label] = (s.mean(), 0.5 * (s.max() - s.min()),
                          float(d.fairlead_tension.values[0, sel].max()),
                          float(d.pto_power.values[0, sel].mean(axis=0).sum()))
            t0 = lap(t0, f"H {H} m, {label} lines")
        for label, (sm, sa, tmax, p) in out.items():
            print(f"H {H} m, T {T} s, {label} lines (last 10 periods): surge mean {sm - q0[0]:+.4f} m "
                  f"about the equilibrium, amplitude {sa:.4f} m; largest fairlead tension "
                  f"{tmax / 1e3:.1f} kN; array mean power {p / 1e3:.2f} kW")
        a, b = out["linearised"], out["nonlinear"]
        print(f"  nonlinear / linearised − 1: surge amplitude {b[1] / a[1] - 1:+.2e}, largest tension "
              f"{b[2] / a[2] - 1:+.2e}, power {b[3] / a[3] - 1:+.2e}")

    # 5. one 600 s regular wave at dt = T/100, warm
    T = 8.3
    dt = T / per
    n = int(round(600.0 / dt))
    sea = hydro.Regular(height=3.8, period=T)
    first, warm = first_and_warm(lambda: mfm.simulate(model, sea, duration=n * dt, dt=dt, ramp=5 * T,
                                                      q0=q0, radiation="state_space"), args.repeats)
    print(f"one regular wave, 600 s at dt = T/100 = {dt:.3f} s ({n} steps), mfm.simulate (nonlinear "
          f"lines, state space): first {first:.1f} s, warm {warm:.2f} s")
    loads = model_loads(model, sea, dt=dt, duration=n * dt, ramp=5 * T, radiation="state_space")
    res = {}

    def run():
        res["r"] = mfm.rollout(model, jnp.asarray(q0), jnp.zeros(model.n_coordinates), dt=dt,
                               n_steps=n, loads=loads)
        res["r"][1].block_until_ready()

    first, warm = first_and_warm(run, args.repeats)
    print(f"  the pure rollout: first {first:.1f} s, warm {warm:.2f} s ({warm / n * 1e6:.0f} µs/step)")


if __name__ == "__main__":
    main()
