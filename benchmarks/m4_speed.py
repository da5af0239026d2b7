"""Speed of M4 134 with coupled hydrodynamics against seed 001 Table 3 (not a test).

    python benchmarks/m4_speed.py [--repeats 3] [--sweep]

M4 134 (8 floats, 7 coordinates, 48 hydro dofs of which the planar model moves 24), JONSWAP
Hs 0.04 m, Tp 1.2 s, γ 3.3, 100 Tp at Tp/200 = 20,000 steps. Warm wall times (median of
``--repeats`` after one compiling call) of the pure rollout (no per-step recording) for:

- state-space radiation (the default fit: one common pole set, 24 inputs), RK4;
- state-space radiation, semi-implicit Euler (one evaluation per step);
- convolution (product-integration weights over the memory T_K, 24 × 24 moved dofs), RK4;
- the seed's own scheme in this engine: A∞ on the right-hand side, Beeman's corrector iterated to
  1 % (seed 001 §5), state space;
- ``mfm.simulate`` (the dataset with reactions, energies and hydro loads at every step), RK4;

and, with ``--sweep``, the whole Fig. 7 sweep (3 layouts × 11 Tp, 20,000 steps each, one
``simulate_batch`` call per layout), first (compiling) and warm call. Ratios are against seed 001
Table 3: 0.0044 s per step (MFM, 111) → 88 s for 20,000 steps.
"""
import argparse
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
SEED_PER_STEP = 0.0044          # s, seed 001 Table 3 (MFM, 111 layout, i5 laptop)
TP = 1.2
N = 20_000




def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--sweep", action="store_true", help="also time the whole Fig. 7 sweep")
    args = ap.parse_args()
    m = mfm.load(CONFIGS / "m4_134.toml")
    sea = hydro.Jonswap(hs=0.04, tp=TP, gamma=3.3, seed=1, omega_range=(1.0, 25.0))
    dt = TP / 200
    t0 = time.perf_counter()
    ss = m.hydro.state_space()
    r = ss.report
    print(f"M4 134: {len(m.hydro.dofs)} hydro dofs, {len(m.hydro.moving)} moved by the planar model")
    print(f"state-space fit: {time.perf_counter() - t0:.1f} s, {r['n_states']} states "
          f"({r['pole_sharing']} poles, order {max(r['orders'].values())}), band error "
          f"{r['overall_error']:.3f}, passive {r['passive']} (min eig {r['passivity_min_eig']:.1e})")
    t0 = time.perf_counter()
    m.hydro.kernel(dt, 10.0)
    print(f"convolution weights (10 s of memory): {time.perf_counter() - t0:.1f} s; the decay of K "
          f"gives T_K = {m.hydro.memory():.1f} s")
    q0 = jnp.zeros(m.n_coordinates)
    seed_time = SEED_PER_STEP * N
    rows = []
    cases = [("state space, RK4", "state_space", "rk4", "lhs"),
             ("state space, semi-implicit Euler", "state_space", "semi_implicit", "lhs"),
             ("convolution (memory 10 s), RK4", "convolution", "rk4", "lhs"),
             ("seed scheme (A∞ rhs, Beeman + corrector to 1 %), state space", "state_space", "beeman", "rhs")]
    for label, rad, integ, am in cases:
        # M4 134's K decays to 1e-3 of its peak only after T_K ≈ 39 s (6,600 lags at dt 6 ms, minutes
        # per run): the convolution is timed over 10 s of memory
        loads = model_loads(m, sea, dt=dt, duration=N * dt, ramp=5 * TP, radiation=rad, added_mass=am,
                            memory=10.0 if rad == "convolution" else None)
        out = {}

        def run():
            out["r"] = mfm.rollout(m, q0, q0, dt=dt, n_steps=N, integrator=integ, loads=loads)
            out["r"][1].block_until_ready()

        # the convolution over T_K ≈ 22 s of memory is the slow one: one warm repeat
        first, warm = first_and_warm(run, 1 if rad == "convolution" else args.repeats)
        finite = bool(np.isfinite(np.asarray(out["r"][1])).all())
        it = np.asarray(out["r"][5])[1:]
        extra = f", corrector iterations mean {it.mean():.2f} max {it.max()}" if integ == "beeman" else ""
        rows.append((label, warm))
        print(f"{label:<64s} first {first:6.2f} s, warm {warm:6.3f} s ({warm / N * 1e6:5.1f} µs/step), "
              f"{seed_time / warm:6.0f}× seed 001{'' if finite else ', WENT NON-FINITE'}{extra}")
    first, warm = first_and_warm(lambda: mfm.simulate(m, sea, duration=N * dt, dt=dt, ramp=5 * TP,
                                                      radiation="state_space"), max(1, args.repeats - 1))
    print(f"{'mfm.simulate (dataset recorded every step), state space, RK4':<64s} first {first:6.2f} s, "
          f"warm {warm:6.3f} s, {seed_time / warm:6.0f}× seed 001")
    ours = dict(rows)["state space, RK4"]
    seed_ours = dict(rows)["seed scheme (A∞ rhs, Beeman + corrector to 1 %), state space"]
    print(f"the seed's scheme in this engine takes {seed_ours / ours:.2f}× our default (RK4, A∞ in M*)")

    if args.sweep:
        tps = np.round(np.arange(0.8, 1.81, 0.1), 2)
        total_first = total_warm = 0.0
        for k in ("111", "132", "134"):
            mk = mfm.load(CONFIGS / f"m4_{k}.toml")
            mk.hydro.state_space()
            seas = [hydro.Jonswap(hs=0.04, tp=tp, gamma=3.3, seed=1, omega_range=(1.0, 25.0)) for tp in tps]
            first, warm = first_and_warm(lambda: mfm.simulate_batch(mk, seas, dt=tps / 200, n_steps=N,
                                                                    ramp=5 * tps, save_every=2), 1)
            total_first += first
            total_warm += warm
            print(f"Fig. 7 sweep M4 {k}: 11 Tp × 20,000 steps in one call: first {first:.1f} s, warm {warm:.1f} s")
        print(f"whole Fig. 7 sweep (33 runs): first {total_first:.1f} s, warm {total_warm:.1f} s; "
              f"seed 001 at 0.0044 s/step: {33 * seed_time:.0f} s ({33 * seed_time / total_warm:.0f}×)")


if __name__ == "__main__":
    main()
