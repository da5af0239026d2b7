"""The fidelity ladder on M4 134 (issue 14): the spectral level (mfm.spectral_response) and the
linearised time domain (mfm.linear_response) against the time domain in the JONSWAP sea of
benchmarks/speed.py (Hs 0.04 m, Tp 1.2 s, γ 3.3, 100 Tp at Tp/200), each level's warm wall time
(median of 3) and its error in the mean PTO power and the hinge angles' standard deviations
against RK4 (radiation "auto") over the settled part (after 20 Tp). Not a test; numbers in
benchmarks/RESULTS.md ("The fidelity ladder on M4 134"). From the repository root, with mfm
installed (the script does not touch sys.path):

    python tools/fidelity.py            # about 3 minutes on 2 shared cores

The spectral level is timed twice: statistics only (no time series), and synthesising q, q̇ and the
PTO power on the run's time grid (what is compared here). The linear level's warm time reuses its
modes (cached per model and dt, as the state-space fit is per model); its cold first call (the fit,
the eigendecomposition of the 1,021-state system, compilation) is printed too.
"""
import argparse
import os
import statistics
import time
import warnings
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]

os.environ.setdefault("MFM_COMPILATION_CACHE", "off")  # compile times measured, not loaded from disk (mfm.runner.xla)
os.environ.setdefault("MFM_FIT_CACHE", "off")          # fit times measured, not read from disk (hydro.fitcache)
import hydro  # noqa: E402
import mfm  # noqa: E402

TP = 1.2
N = 20_000


def timed(fn, repeats=3):
    out = fn()
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        fn()
        times.append(time.perf_counter() - start)
    return out, statistics.median(times)


def measures(ds, window, angles):
    sel = ds.sel(time=window)
    return (sel.pto_power.mean("time").values,
            sel.q.sel(coordinate=angles).std("time").values)


def main():
    warnings.simplefilter("ignore")
    m = mfm.load(ROOT / "configs" / "m4_134.toml")
    sea = hydro.Jonswap(hs=0.04, tp=TP, gamma=3.3, seed=1, omega_range=(1.0, 25.0))
    dt = TP / 200
    angles = [c for c in m.coordinates if c.endswith("angle")]
    window = slice(20 * TP, None)
    kw = dict(duration=N * dt, dt=dt, ramp=5 * TP)
    full, t_full = timed(lambda: mfm.simulate(m, sea, integrator="rk4", **kw))
    fast, t_fast = timed(lambda: mfm.simulate(m, sea, integrator="verlet",
                                              radiation="state_space_exact", **kw))
    start = time.perf_counter()
    mfm.linear_response(m, sea, **kw)
    t_lin_cold = time.perf_counter() - start
    lin, t_lin = timed(lambda: mfm.linear_response(m, sea, **kw))
    t = full.time.values
    spec, t_spec = timed(lambda: mfm.spectral_response(m, sea, t=t))
    _, t_stats = timed(lambda: mfm.spectral_response(m, sea))
    P0, S0 = measures(full, window, angles)
    rows = [("full: rk4, radiation " + full.attrs.get("radiation_choice", "auto").split(":")[0],
             t_full, P0, S0),
            ("fast: verlet, state_space_exact", t_fast, *measures(fast, window, angles)),
            ("linear: linearised, modes stepped exactly", t_lin, *measures(lin, window, angles)),
            ("spectral, series on the run's grid", t_spec, *measures(spec, window, angles))]
    print(f"M4 134, JONSWAP Hs 0.04 m Tp {TP} s γ 3.3 seed 1, {N} steps at Tp/200, "
          f"compared after {20 * TP:g} s")
    print(f"{'level':42s} {'warm s':>8s} {'×full':>7s} {'power err':>10s} {'max std err':>12s}")
    for name, wall, P, S in rows:
        print(f"{name:42s} {wall:8.3f} {t_full / wall:7.1f} {abs(P.sum() / P0.sum() - 1):10.2e} "
              f"{np.max(np.abs(S / S0 - 1)):12.2e}")
    print(f"{'spectral, statistics only':42s} {t_stats:8.3f} {t_full / t_stats:7.1f}   "
          f"expected mean power {float(spec.pto_power_mean.sum()):.4g} W (run: {P0.sum():.4g} W over "
          f"{N * dt - 20 * TP:g} s)")
    print(f"linear level cold (fit, modes of {lin.attrs['state_space_states']} radiation states, "
          f"compilation): {t_lin_cold:.1f} s; mode condition {lin.attrs['mode_condition']:.3g}")


if __name__ == "__main__":
    # no options: --help prints what the script does instead of running it
    argparse.ArgumentParser(description=__doc__,
                            formatter_class=argparse.RawDescriptionHelpFormatter).parse_args()
    main()
