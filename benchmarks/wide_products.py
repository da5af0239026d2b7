"""Wide small products in a time loop compiled whole: one multiply–reduce against column by column
(``mfm.mechanics.se3.matmul_small``; issue 34's Wu & Yuan rows). Prints figures; not a test.

    python benchmarks/wide_products.py [--steps 3000] [--skip-model]

1. The product X Y alone, X (m, k) constant, Y (k, p) the loop's carry, 20,000 iterations of a
   compiled ``fori_loop`` (µs an iteration, median of 3): the multiply–reduce ``Σ_j X_ij Y_jl``
   that XLA emits as one scalar chain per output element, and :func:`se3._by_columns` (p
   matrix–vector products in a loop), for M4 134's A∞ H (24 × 24 × 7: below the threshold),
   two sizes between, and Wu & Yuan's (75 × 75 × 18).
2. Wu & Yuan m1's RK4 time loop (``mfm.rollout`` over ``model_loads(..., radiation=
   "state_space")``, regular wave H 2 m, T 8 s, dt 0.05 s), warm, median of 5, with the products
   as mfm makes them and with every product a multiply–reduce (the threshold raised, the jit
   caches cleared), in one process, in turn; and how far apart the two end states are (the same
   to round-off: the sums differ in order).
"""
from __future__ import annotations

import argparse
import os
import time
import warnings

import numpy as np

os.environ.setdefault("MFM_COMPILATION_CACHE", "off")
os.environ.setdefault("MFM_PROGRAM_CACHE", "off")


def _median_time(f, repeats):
    f()
    ts = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        f()
        ts.append(time.perf_counter() - t0)
    return float(np.median(ts))


def products(repeats=3, steps=20_000):
    import jax
    import jax.numpy as jnp

    from mfm.mechanics import se3

    rng = np.random.default_rng(0)
    print("| X Y, m × k × p | multiply–reduce | by columns | ratio |")
    print("|---|---|---|---|")
    for m, p in ((24, 7), (36, 12), (48, 14), (75, 18)):
        X = jnp.asarray(rng.standard_normal((m, m)))
        Y0 = jnp.asarray(rng.standard_normal((m, p)))
        per = {}
        for name, fn in (("reduce", lambda Y: jnp.sum(X[:, :, None] * Y[None, :, :], axis=1)),
                         ("columns", lambda Y: se3._by_columns(X, Y))):
            run = jax.jit(lambda Y, fn=fn: jax.lax.fori_loop(
                0, steps, lambda i, Y: 0.9999 * Y + 1e-9 * fn(Y), Y))
            per[name] = _median_time(lambda: jax.block_until_ready(run(Y0)), repeats) / steps
        print(f"| {m} × {m} × {p} | {1e6 * per['reduce']:.2f} µs | {1e6 * per['columns']:.2f} µs "
              f"| {per['columns'] / per['reduce']:.2f} |")


def model(steps, repeats=5):
    import jax
    import jax.numpy as jnp

    import hydro
    import mfm
    from mfm.mechanics import se3
    from mfm.timedomain.setup import model_loads

    warnings.simplefilter("ignore")
    root = os.path.join(os.path.dirname(__file__), "..")
    m = mfm.load(os.path.join(root, "configs", "wu_yuan_m1_td.toml"))
    dt = 0.05
    loads = model_loads(m, hydro.Regular(height=2.0, period=8.0), dt=dt, duration=steps * dt,
                        ramp=6.0, radiation="state_space", integrator="rk4")
    q0 = jnp.zeros(m.n_coordinates)
    kept = se3._COLUMNS_LIMIT
    ends, times = {}, {}
    for name, limit in (("as mfm makes them", kept), ("every product a multiply–reduce", 2**62)):
        se3._COLUMNS_LIMIT = limit
        jax.clear_caches()
        try:
            def run():
                return jax.block_until_ready(mfm.rollout(m, q0, q0, dt=dt, n_steps=steps,
                                                         integrator="rk4", loads=loads))
            times[name] = _median_time(run, repeats)
            ends[name] = np.asarray(run()[1])
        finally:
            se3._COLUMNS_LIMIT = kept
    a, b = ends.values()
    print(f"\nWu & Yuan m1, {steps} RK4 steps (state space integrated), warm, median of {repeats}:")
    for name, t in times.items():
        print(f"  {name}: {t:.3f} s ({1e6 * t / steps / 4:.1f} µs an evaluation)")
    first, second = times.values()
    print(f"  ratio {first / second:.2f}; end states apart by {np.abs(a - b).max() / np.abs(b).max():.1e} "
          "of the largest |q| (the sums' order; the run amplifies round-off: a 1-ulp change of "
          "A∞ moves it by ~1e-7)")


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--steps", type=int, default=3000)
    ap.add_argument("--skip-model", action="store_true")
    a = ap.parse_args(argv)
    import mfm  # noqa: F401  (first: the loop option before jax starts)

    print(f"{os.cpu_count()} cores, load average {os.getloadavg()[0]:.1f}")
    products()
    if not a.skip_model:
        model(a.steps)


if __name__ == "__main__":
    main()
