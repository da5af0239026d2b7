"""Speed of the FOWT with an articulated absorber and hydraulic PTO (Hallak et al.;
configs/hallak_*.toml).

    python benchmarks/hallak_speed.py [--repeats 3]

Prints:

- the 48-frequency RAO set of Table 4 for the four scenarios (single-body FOWT, single-body WEC,
  hydrodynamically coupled, fully coupled; every output incl. joint reactions): the first call
  (compilation) and the warm median;
- one 3-hour irregular sea state (JONSWAP H_s 2 m, T_p 7 s) of the fully coupled model at
  dt = 0.1 s (108,000 RK4 steps; state-space radiation, 30 hydro dofs): the radiation fit, then
  the pure rollout, first and warm.

Goals (issue 11): the RAO set ≤ 1 s after compilation; the sea state ≤ 2 s warm.
"""
import argparse
import math
import os
import time
import warnings
from pathlib import Path

import jax.numpy as jnp
import numpy as np

os.environ.setdefault("MFM_COMPILATION_CACHE", "off")  # compile times measured, not loaded from disk (mfm.runner.xla)
os.environ.setdefault("MFM_FIT_CACHE", "off")          # fit times measured, not read from disk (hydro.fitcache)
import hydro
import mfm
from mfm.timedomain.setup import model_loads
from timing import first_and_warm

warnings.simplefilter("ignore", hydro.database.HydroDatabaseWarning)
CONFIGS = Path(__file__).resolve().parents[1] / "configs"
OMEGA = np.round(0.19 + 0.03 * np.arange(48), 2)
SCENARIOS = ("fowt", "wec", "hydro_coupled", "fwwp")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--repeats", type=int, default=3)
    args = ap.parse_args()
    models = {k: mfm.load(CONFIGS / f"hallak_{k}.toml") for k in SCENARIOS}

    def raos():
        return [mfm.frequency_response(m, OMEGA, 0.0) for m in models.values()]

    first, warm = first_and_warm(raos, args.repeats)
    print(f"48-frequency RAO set, four scenarios: first {first:.2f} s, warm {warm:.3f} s")

    m = models["fwwp"]
    t0 = time.perf_counter()
    r = m.hydro.state_space().report
    print(f"fully coupled: {len(m.hydro.dofs)} hydro dofs, {len(m.hydro.moving)} moved; state-space "
          f"fit {time.perf_counter() - t0:.1f} s, {r['n_states']} states, band error "
          f"{r['overall_error']:.3f}, passive {r['passive']}")
    sea = hydro.Jonswap(hs=2.0, tp=7.0, gamma=3.3, seed=0, omega_range=(0.35, 2.0),
                        repeat_period=10800.0)
    dt = 0.1
    n = int(round(10800.0 / dt))
    loads = model_loads(m, sea, dt=dt, duration=n * dt, ramp=60.0, radiation="state_space")
    q0 = jnp.asarray(mfm.equilibrium(m)[0])
    out = {}

    def run():
        out["r"] = mfm.rollout(m, q0, jnp.zeros_like(q0), dt=dt, n_steps=n, loads=loads)
        out["r"][1].block_until_ready()

    first, warm = first_and_warm(run, args.repeats)
    ok = bool(np.isfinite(np.asarray(out["r"][1])).all())
    print(f"one 3-hour sea state, dt {dt} s ({n} steps), rollout: first {first:.2f} s, warm "
          f"{warm:.3f} s ({warm / n * 1e6:.1f} µs/step){'' if ok else ', NON-FINITE'}")


if __name__ == "__main__":
    main()
