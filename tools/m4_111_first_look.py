"""First look at M4 111 with water: figures for the issue notes (not a test).

    python tools/m4_111_first_look.py

Prints the natural periods (eigenproblem and min |det Λ|), θ_rms and mean PTO power in JONSWAP
Hs 0.04 m, Tp 1.2 s, γ 3.3 (100 Tp at Tp/200, means over the last 50 Tp), and the seed 001 scheme
(A∞ on the right-hand side, Beeman's corrector to 1 %) against ours on JONSWAP Hs 0.04, Tp 1 s, γ 1.
"""
import argparse
import os
import time
import warnings
from pathlib import Path

import numpy as np

os.environ.setdefault("MFM_COMPILATION_CACHE", "off")  # compile times measured, not loaded from disk (mfm.runner.xla)
os.environ.setdefault("MFM_FIT_CACHE", "off")          # fit times measured, not read from disk (hydro.fitcache)
import hydro
import mfm

warnings.simplefilter("ignore", hydro.database.HydroDatabaseWarning)
CFG = Path(__file__).resolve().parents[1] / "configs" / "m4_111.toml"


def stats(ds, t_from):
    half = ds.sel(time=slice(t_from, None))
    th = half.q.sel(coordinate="float3.angle")
    return float(np.degrees(th.std())), float(half.pto_power.mean())


def main():
    m = mfm.load(CFG)
    nat = mfm.natural_frequencies(m)
    print("natural periods [s], eigenproblem:", np.round(2 * np.pi / nat["eigen"], 4),
          " min |det|:", np.round(2 * np.pi / nat["min_det"], 4))
    Tp = 1.2
    sea = hydro.Jonswap(hs=0.04, tp=Tp, gamma=3.3, seed=1, omega_range=(1.0, 25.0))
    t0 = time.perf_counter()
    ds = mfm.simulate(m, sea, duration=100 * Tp, dt=Tp / 200, ramp=5 * Tp, radiation="state_space")
    th, p = stats(ds, 50 * Tp)
    print(f"JONSWAP Hs 0.04 Tp 1.2 γ 3.3: θ_rms {th:.3f}°, mean power {p:.4f} W "
          f"({time.perf_counter() - t0:.1f} s with compilation)")
    Tp = 1.0
    sea = hydro.Jonswap(hs=0.04, tp=Tp, gamma=1.0, seed=2, omega_range=(1.0, 25.0))
    kw = dict(duration=60 * Tp, dt=Tp / 200, ramp=5 * Tp, radiation="state_space")
    ours = mfm.simulate(m, sea, integrator="rk4", **kw)
    seed = mfm.simulate(m, sea, integrator="beeman", added_mass="rhs", **kw)
    (th_o, p_o), (th_s, p_s) = stats(ours, 30 * Tp), stats(seed, 30 * Tp)
    it = seed.iterations.values[1:]
    print(f"JONSWAP Hs 0.04 Tp 1.0 γ 1: ours θ_rms {th_o:.5f}°, P {p_o:.6f} W; seed scheme θ_rms "
          f"{th_s:.5f}°, P {p_s:.6f} W (differences {th_s / th_o - 1:+.2e}, {p_s / p_o - 1:+.2e}); "
          f"corrector iterations mean {it.mean():.2f}, max {it.max()}")


if __name__ == "__main__":
    # no options: --help prints what the script does instead of running it
    argparse.ArgumentParser(description=__doc__,
                            formatter_class=argparse.RawDescriptionHelpFormatter).parse_args()
    main()
