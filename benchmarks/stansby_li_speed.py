"""Speed of the hybrid wind semi-sub with hinged floats (Stansby & Li; configs/stansby_li.toml).

    python benchmarks/stansby_li_speed.py [--repeats 3] [--sweep]

7 coordinates, 5 floats solved together (30 hydro dofs, all moved by the 5-dof root), state-space
radiation with the default fit, RK4. Prints:

- the radiation fit (time, states, band error, passivity);
- one 3600 s sea state (JONSWAP H_s 2 m, T_p 12 s, γ 3.3, resolved at 2π/3600 s) at dt = T_p/200
  (36,000 steps) and at the notebook's dt = 0.1 s: warm wall time of the pure rollout (median of
  ``--repeats`` after one compiling call) and of ``mfm.simulate_batch`` (dataset included);
- with ``--sweep``: the 36-heading sweep (every 10°, dt 0.1 s, 1 h + 100 s of ramp) in one
  ``simulate_batch`` call, first and warm.

Goals (issue 10): one sea state ≤ 2 s warm; the 36-heading sweep ≤ 60 s.
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




def sea(heading_deg=0.0):
    return hydro.Jonswap(hs=2.0, tp=12.0, gamma=3.3, heading=math.radians(heading_deg), seed=0,
                         omega_range=(0.2, 2.0), repeat_period=3600.0)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--sweep", action="store_true", help="also time the 36-heading sweep")
    args = ap.parse_args()
    m = mfm.load(CONFIGS / "stansby_li.toml")
    t0 = time.perf_counter()
    r = m.hydro.state_space().report
    print(f"Stansby-Li: {len(m.hydro.dofs)} hydro dofs, {len(m.hydro.moving)} moved; state-space fit "
          f"{time.perf_counter() - t0:.1f} s, {r['n_states']} states ({r['pole_sharing']} poles), band "
          f"error {r['overall_error']:.3f}, passive {r['passive']}")
    q0 = jnp.zeros(m.n_coordinates)
    for dt in (12.0 / 200, 0.1):
        n = int(round(3600.0 / dt))
        loads = model_loads(m, sea(), dt=dt, duration=n * dt, ramp=100.0, radiation="state_space")
        out = {}

        def run():
            out["r"] = mfm.rollout(m, q0, q0, dt=dt, n_steps=n, loads=loads)
            out["r"][1].block_until_ready()

        first, warm = first_and_warm(run, args.repeats)
        ok = bool(np.isfinite(np.asarray(out["r"][1])).all())
        print(f"one 3600 s sea state, dt {dt:.3g} s ({n} steps), rollout: first {first:.2f} s, warm "
              f"{warm:.3f} s ({warm / n * 1e6:.1f} µs/step){'' if ok else ', NON-FINITE'}")
        first, warm = first_and_warm(lambda: mfm.simulate_batch(m, sea(), dt=dt, n_steps=n, ramp=100.0,
                                                                outputs=("point_acceleration",)),
                                     max(1, args.repeats - 1))
        print(f"  the same through mfm.simulate_batch (dataset, hub acceleration): first {first:.2f} s, "
              f"warm {warm:.3f} s")
    if args.sweep:
        seas = [sea(b) for b in range(0, 360, 10)]
        n = int(round(3700.0 / 0.1))
        first, warm = first_and_warm(lambda: mfm.simulate_batch(m, seas, dt=0.1, n_steps=n, ramp=100.0,
                                                                save_every=2,
                                                                outputs=("point_acceleration",)), 1)
        print(f"36 headings × {n} steps in one simulate_batch call: first {first:.1f} s, warm {warm:.1f} s")


if __name__ == "__main__":
    main()
