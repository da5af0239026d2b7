"""Speed of the MFM core on M4 134 (mechanics only). Prints figures; asserts nothing.

    python benchmarks/bench_core.py [--repeats 7]

Reports medians over repeats: µs per jit-compiled forward_dynamics call, compile time and warm
wall time of a 20,000-step simulation (rollout only, and the full `simulate` with its dataset).
"""
import argparse
import os
import time
from pathlib import Path

import jax
import jax.numpy as jnp
import numpy as np

os.environ.setdefault("MFM_COMPILATION_CACHE", "off")  # compile times measured, not loaded from disk (mfm.runner.xla)
os.environ.setdefault("MFM_FIT_CACHE", "off")          # fit times measured, not read from disk (hydro.fitcache)
import mfm
from timing import median_time

ROOT = Path(__file__).resolve().parents[1]


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--repeats", type=int, default=7)
    ap.add_argument("--config", default=str(ROOT / "configs" / "m4_134.toml"))
    ap.add_argument("--steps", type=int, default=20_000)
    args = ap.parse_args()
    model = mfm.load(args.config, hydro=False)  # mechanics only
    n = model.n_coordinates
    rng = np.random.default_rng(0)
    q, qd = jnp.asarray(rng.normal(size=n) * 0.1), jnp.asarray(rng.normal(size=n) * 0.1)
    print(f"model {model.name}: {model.n_bodies} bodies, {n} coordinates; jax {jax.__version__}, "
          f"{jax.devices()[0].platform}")

    fd = jax.jit(mfm.forward_dynamics)
    t0 = time.perf_counter()
    fd(model, q, qd).block_until_ready()
    print(f"forward_dynamics compile: {time.perf_counter() - t0:.2f} s")
    calls = 2000

    def loop():
        for _ in range(calls):
            out = fd(model, q, qd)
        out.block_until_ready()
    per_call = median_time(loop, args.repeats) / calls
    print(f"forward_dynamics: {per_call * 1e6:.1f} µs per call from Python (median of {args.repeats} "
          f"× {calls}, jax dispatch of the model pytree included)")

    @jax.jit
    def loop_fd(model, q, qd):
        # 2000 dependent calls inside one compiled program: the cost of the call itself
        return jax.lax.fori_loop(0, calls, lambda i, a: a + 1e-12 * mfm.forward_dynamics(model, q + a, qd), q)

    loop_fd(model, q, qd).block_until_ready()
    t_loop = median_time(lambda: loop_fd(model, q, qd).block_until_ready(), args.repeats) / calls
    print(f"forward_dynamics: {t_loop * 1e6:.1f} µs per call inside a compiled loop (median of "
          f"{args.repeats} × {calls})")

    vf = jax.jit(jax.vmap(mfm.forward_dynamics, in_axes=(None, 0, 0)))
    Q = jnp.asarray(rng.normal(size=(1000, n)) * 0.1)
    vf(model, Q, Q).block_until_ready()
    t_v = median_time(lambda: vf(model, Q, Q).block_until_ready(), args.repeats)
    print(f"forward_dynamics vmapped over 1000 states: {t_v / 1000 * 1e6:.2f} µs per state")

    for integ in ("rk4", "beeman", "semi_implicit", "newmark"):
        dt = 1.0 / 200  # Tp/200 at Tp = 1 s
        q0 = np.zeros(n)
        q0[3:] = 0.05
        t0 = time.perf_counter()
        mfm.rollout(model, q0, np.zeros(n), dt=dt, n_steps=args.steps, integrator=integ)[1].block_until_ready()
        first = time.perf_counter() - t0
        warm = median_time(lambda: mfm.rollout(model, q0, np.zeros(n), dt=dt, n_steps=args.steps,
                                               integrator=integ)[1].block_until_ready(), args.repeats)
        print(f"rollout {integ:>13s}, {args.steps} steps: compile+first {first:.2f} s, warm "
              f"{warm:.3f} s ({warm / args.steps * 1e6:.1f} µs/step)")

    t0 = time.perf_counter()
    mfm.simulate(model, duration=args.steps * 0.005, dt=0.005, q0=q0)
    first = time.perf_counter() - t0
    warm = median_time(lambda: mfm.simulate(model, duration=args.steps * 0.005, dt=0.005, q0=q0),
                       args.repeats)
    print(f"simulate (rk4, dataset with reactions and energies): first {first:.2f} s, warm {warm:.3f} s")


if __name__ == "__main__":
    main()
