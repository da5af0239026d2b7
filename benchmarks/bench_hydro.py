"""Speed of the water: RM3 in a regular wave (H 2.5 m, T 8 s), 200 s at dt 0.1 s. Prints figures.

    python benchmarks/bench_hydro.py [--repeats 7]

Reports, as medians: building K(t) and the state-space fit of the 12×12 RM3 radiation (cold, on a
fresh model); compile time and warm wall time of the compiled rollout with convolution and with
state space; and the whole `simulate` call (dataset included) warm.
"""
import argparse
import os
import statistics
import time
import warnings
from pathlib import Path

import numpy as np

os.environ.setdefault("MFM_COMPILATION_CACHE", "off")  # compile times measured, not loaded from disk (mfm.runner.xla)
os.environ.setdefault("MFM_FIT_CACHE", "off")          # fit times measured, not read from disk (hydro.fitcache)
import hydro
import mfm
from timing import median_time
from mfm.timedomain.setup import model_loads
from mfm.timedomain.rollout import rollout

ROOT = Path(__file__).resolve().parents[1]
warnings.simplefilter("ignore")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--repeats", type=int, default=7)
    args = ap.parse_args()
    cfg = ROOT / "configs" / "rm3.toml"
    sea = hydro.Regular(height=2.5, period=8.0)
    dt, duration = 0.1, 200.0
    n = int(duration / dt)

    def cold_irf_fit():
        m = mfm.load(cfg)
        t0 = time.perf_counter()
        m.hydro.kernel(dt)
        t1 = time.perf_counter()
        m.hydro.state_space()
        return t1 - t0, time.perf_counter() - t1

    irf, fit = zip(*[cold_irf_fit() for _ in range(3)])
    print(f"RM3 radiation 12×12: K(t) and convolution weights {statistics.median(irf):.2f} s, "
          f"state-space fit {statistics.median(fit):.2f} s (median of 3, cold)")
    model = mfm.load(cfg)
    q0 = np.zeros(model.n_coordinates)
    for rad in ("convolution", "state_space"):
        loads = model_loads(model, sea, dt=dt, duration=duration, ramp=20.0, radiation=rad)
        nx = sum(ld.n_states for ld in loads)
        t0 = time.perf_counter()
        rollout(model, q0, q0, dt=dt, n_steps=n, loads=loads)[1].block_until_ready()
        first = time.perf_counter() - t0
        warm = median_time(lambda: rollout(model, q0, q0, dt=dt, n_steps=n, loads=loads)[1].block_until_ready(),
                   args.repeats)
        extra = f", {loads[0].n_lags} lags" if rad == "convolution" else f", {nx} states"
        print(f"rollout RK4 {rad:>12s}{extra}: compile+first {first:.2f} s, warm {warm * 1e3:.1f} ms "
              f"({warm / n * 1e6:.1f} µs/step)")
        for integ in ("semi_implicit", "beeman"):
            rollout(model, q0, q0, dt=dt, n_steps=n, loads=loads, integrator=integ)[1].block_until_ready()
            w2 = median_time(lambda: rollout(model, q0, q0, dt=dt, n_steps=n, loads=loads,
                                     integrator=integ)[1].block_until_ready(), args.repeats)
            print(f"    with {integ}: warm {w2 * 1e3:.1f} ms")
        mfm.simulate(model, sea, duration=duration, dt=dt, ramp=20.0, radiation=rad)
        w = median_time(lambda: mfm.simulate(model, sea, duration=duration, dt=dt, ramp=20.0, radiation=rad), 3)
        print(f"simulate {rad} (loads built, rollout, dataset): warm {w:.2f} s")


if __name__ == "__main__":
    main()
