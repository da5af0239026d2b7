"""Stansby & Li (configs/stansby_li.toml): where the mean power peaks over T_p, and what moves it.

    OMP_NUM_THREADS=1 python tools/stansby_li_tp_peak.py [--tp 8 9 ... 16] [--skip-td]

The seed (§6, Fig. 7): "The maximum of about 270 kW occurs with T_p = 12 and 13 s". The notebook
(notebooks/stansby_li.ipynb, Fig. 7) finds its maximum at T_p 11 s. This script measures, with the
notebook's sea and run settings (H_s 2 m, JONSWAP γ 3.3 on 0.2–2.0 rad/s, heading 0, seed 0,
3600 s analysed after a 100 s ramp, dt 0.1 s, RK4, state-space radiation), the mean PTO power
over T_p for four variants of one model, each a vmapped batch of one compiled shape:

    as configured (C_D 1 on every float and axis), without drag (C_D 0),
    every float's assumed principal inertia × 0.8, and × 1.2

and prints the T_p of the maximum of each, the power per T_p, and the change the inertias make.
Then the natural periods (mfm.natural_frequencies) of the three variants of inertia: the
relative-pitch modes near 10 s are what the notebook used to blame the inertias.
About 6 min on 2 free cores (each batch of 9 cases ≈ 80 s).
"""
import argparse
import time

import equinox as eqx
import numpy as np

import hydro
import mfm

T_RUN, RAMP, DT, SAVE = 3600.0, 100.0, 0.1, 2
FLOATS = ("float1", "float2", "float3", "floatB", "floatC")   # the turbine is a point mass [S]


def jonswap(tp):
    """The notebook's sea (its `jonswap(2.0, tp)`): one component per 2π/T_RUN, seed 0."""
    return hydro.Jonswap(hs=2.0, tp=tp, gamma=3.3, heading=0.0, seed=0, omega_range=(0.2, 2.0),
                         repeat_period=T_RUN)


def with_inertia(model, factor):
    """Every float's principal inertia about its CoM × factor (the [A] values of the config);
    masses and centres of mass, which the seed states, unchanged."""
    idx = np.array([model.body_index(b) for b in FLOATS])
    return eqx.tree_at(lambda m: m.inertia, model, model.inertia.at[idx].multiply(factor))


def mean_power(ds):
    """Mean PTO power (W) per case over the analysed hour, as the notebook's `stats`."""
    keep = ds.time.values[0] >= RAMP - 1e-9
    return ds.isel(step=keep).pto_power.sum("pto").mean("step").values


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--tp", type=float, nargs="+", default=list(np.arange(8.0, 16.01, 1.0)))
    p.add_argument("--skip-td", action="store_true", help="natural periods only")
    args = p.parse_args(argv)
    model = mfm.load("configs/stansby_li.toml")
    tp = np.array(args.tp)
    seas = [jonswap(t) for t in tp]
    n = len(tp)
    n_steps = int(round((RAMP + T_RUN) / DT))

    variants = {"as configured (C_D 1)": (model, 1.0), "without drag (C_D 0)": (model, 0.0),
                "float inertias × 0.8": (with_inertia(model, 0.8), 1.0),
                "float inertias × 1.2": (with_inertia(model, 1.2), 1.0)}
    if not args.skip_td:
        power = {}
        for name, (m, cd) in variants.items():
            def drag(i, loads, cd=cd):
                water = loads[0]
                return (eqx.tree_at(lambda w: w.drag, water, water.drag * cd),) + tuple(loads[1:])
            t0 = time.perf_counter()
            ds = mfm.simulate_batch([m] * n, seas, dt=DT, n_steps=n_steps, ramp=RAMP,
                                    save_every=SAVE, vary_loads=drag)
            power[name] = mean_power(ds)
            print(f"{name}: {n} cases in {time.perf_counter() - t0:.0f} s", flush=True)
        print(f"\n{'T_p (s)':>24}" + "".join(f"{t:8.1f}" for t in tp))
        for name, P in power.items():
            print(f"{name:>24}" + "".join(f"{x / 1e3:8.1f}" for x in P)
                  + f"   max {P.max() / 1e3:.1f} kW at T_p {tp[P.argmax()]:g} s")
        base = power["as configured (C_D 1)"]
        for name in ("float inertias × 0.8", "float inertias × 1.2"):
            d = power[name] / base - 1
            print(f"{name} against as configured: " + ", ".join(
                f"T_p {t:g} {100 * x:+.2f} %" for t, x in zip(tp, d))
                  + f"; largest |change| {100 * np.abs(d).max():.2f} %")
        k12 = [i for i, t in enumerate(tp) if t in (12.0, 13.0)]
        if len(k12) == 2:
            for name, P in power.items():
                print(f"{name}: P(13 s) / P(12 s) = {P[k12[1]] / P[k12[0]]:.3f} (seed: ≈ 1, "
                      f"'about 270 kW … with T_p = 12 and 13 s')")

    print("\nnatural periods (s) and damping ratios, mfm.natural_frequencies:")
    for f in (0.8, 1.0, 1.2):
        nat = mfm.natural_frequencies(with_inertia(model, f))
        print(f"  float inertias × {f}: periods {np.round(nat['period'].values, 3).tolist()}, "
              f"damping ratios {np.round(nat['damping_ratio'].values, 3).tolist()}")


if __name__ == "__main__":
    main()
