"""Issue 34's row "`simulate` defaults warm, M4 134": the time of a repeated ``mfm.simulate`` call
with its defaults, beside the accuracy it keeps (not a test).

    python benchmarks/defaults_warm.py [--repeats 5] [--rows defaults exact fast]

M4 134 in the sea of benchmarks/speed.py (JONSWAP H_s 0.04 m, T_p 1.2 s, γ 3.3, seed 1), 100 T_p
at dt = T_p/200 (20,000 steps), ramp 5 T_p. Rows, each compiled once and then timed
``--repeats`` times (the median, and the least, printed):

- ``defaults``: ``mfm.simulate(model, sea, duration=, dt=, ramp=)``, nothing else (RK4,
  ``radiation="auto"``: what it chose and why is printed);
- ``rk4 + state_space_exact``: what ``"auto"`` chose for this run before the choice of how the
  state space's states advance (the exact update);
- ``verlet + state_space_exact``: the fast path.

Beside each, the same call with its outputs made after the time loop instead of beside it
(in one program, as a run shorter than ``mfm.runner.progress.PIPELINE_MIN_SAMPLES`` makes them;
the pipeline: :func:`mfm.runner.progress.run_pipelined`), timed in turn with it,
and the median of the pairs' ratios (this tree's call / that one); and the compiled time loop
alone (``mfm.rollout`` with the same loads, nothing recorded): what the rest of the call (the
loads' preparation, recording every output of every step, the checks, the dataset) adds.

Accuracy, the issue's criterion: the hinge angles' rms θ_rms and the mean PTO power over the last
80 T_p against RK4 at dt/4 with the states integrated (``radiation="state_space"``, every 4th
step saved), within 0.5 %. Goal: the defaults warm ≤ 0.4 s at that accuracy. The figures depend on
the machine and its load: run the script under ``PYTHONPATH=<tree>`` for each tree to compare, one
after the other, and say which machine.
"""
from __future__ import annotations

import argparse
import contextlib
import os
import time
import warnings

import numpy as np

os.environ.setdefault("MFM_COMPILATION_CACHE", "off")     # compile times are not the point here,
os.environ.setdefault("MFM_FIT_CACHE", "off")             # but nothing read from an earlier run

TP, N = 1.2, 20_000


@contextlib.contextmanager
def one_program():
    """simulate's outputs made after its time loop in the same program, not beside it (no
    pipeline: :data:`mfm.runner.progress.PIPELINE_MIN_SAMPLES` raised), for the column that
    compares the two."""
    from mfm.runner import progress

    kept = progress.PIPELINE_MIN_SAMPLES
    progress.PIPELINE_MIN_SAMPLES = 2**62
    try:
        yield
    finally:
        progress.PIPELINE_MIN_SAMPLES = kept


def measures(ds, keep_from):
    angles = [str(c) for c in ds.coordinate.values if str(c).endswith(".angle")]
    part = ds.isel(time=slice(keep_from, None))
    theta = np.sqrt((part.q.sel(coordinate=angles) ** 2).mean("time")).values
    return theta, float(part.pto_power.sum("pto").mean())


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--rows", nargs="+", choices=("defaults", "exact", "fast"),
                    default=("defaults", "exact", "fast"),
                    help="which rows: defaults, rk4 + state_space_exact, verlet + "
                    "state_space_exact (default: all three)")
    args = ap.parse_args()
    import jax
    import jax.numpy as jnp

    import hydro
    import mfm
    from mfm.timedomain.setup import model_loads

    warnings.simplefilter("ignore")
    m = mfm.load(os.path.join(os.path.dirname(__file__), "..", "configs", "m4_134.toml"))
    sea = hydro.Jonswap(hs=0.04, tp=TP, gamma=3.3, seed=1, omega_range=(1.0, 25.0))
    dt = TP / 200
    kw = dict(duration=N * dt, ramp=5 * TP)
    ref = mfm.simulate(m, sea, dt=dt / 4, integrator="rk4", radiation="state_space",
                       save_every=4, **kw)
    keep = N // 5                                   # the last 80 T_p
    theta_ref, power_ref = measures(ref, keep)
    rows = [("defaults", {}),
            ("rk4 + state_space_exact", dict(radiation="state_space_exact")),
            ("verlet + state_space_exact", dict(integrator="verlet",
                                                radiation="state_space_exact"))]
    rows = [r for r, key in zip(rows, ("defaults", "exact", "fast")) if key in args.rows]
    choice = None
    print(f"M4 134, {N} steps at dt = {dt:g} s; accuracy against RK4 at dt/4 (state space "
          f"integrated) over the last 80 T_p: θ_rms {np.round(theta_ref, 5).tolist()} rad, "
          f"power {power_ref:.6g} W")
    print("| run | warm median (least) | first call | outputs after the loop (ratio) | the loop "
          "alone | θ_rms error | power error | radiation |")
    print("|---|---|---|---|---|---|---|---|")
    for name, options in rows:
        t0 = time.perf_counter()
        ds = mfm.simulate(m, sea, dt=dt, **kw, **options)
        first = time.perf_counter() - t0
        with one_program():
            mfm.simulate(m, sea, dt=dt, **kw, **options)          # its own programs compiled
        times, serial = [], []
        for _ in range(args.repeats):
            # the two ways in turn, so that the ratio holds when the machine's speed drifts
            t0 = time.perf_counter()
            ds = mfm.simulate(m, sea, dt=dt, **kw, **options)
            times.append(time.perf_counter() - t0)
            with one_program():
                t0 = time.perf_counter()
                mfm.simulate(m, sea, dt=dt, **kw, **options)
                serial.append(time.perf_counter() - t0)
        theta, power = measures(ds, keep)
        integ = options.get("integrator", "rk4")
        loads = model_loads(m, sea, dt=dt, radiation=ds.attrs["radiation"], integrator=integ,
                            **kw)
        q0 = jnp.zeros(m.n_coordinates)

        def loop():
            return jax.block_until_ready(mfm.rollout(m, q0, q0, dt=dt, n_steps=N,
                                                     integrator=integ, loads=loads))

        loop()
        loops = []
        for _ in range(args.repeats):
            t0 = time.perf_counter()
            loop()
            loops.append(time.perf_counter() - t0)
        e_theta = float(np.max(np.abs(theta / theta_ref - 1)))
        e_power = abs(power / power_ref - 1)
        ratio = np.median(np.asarray(times) / np.asarray(serial))
        print(f"| {name} | {np.median(times):.3f} s ({min(times):.3f}) | {first:.1f} s | "
              f"{np.median(serial):.3f} s ({ratio:.2f}) | {np.median(loops):.3f} s | "
              f"{e_theta:.1e} | {e_power:.1e} | {ds.attrs['radiation']} |")
        if name == "defaults":
            choice = ds.attrs["radiation_choice"]
    if choice is not None:
        print(f"\ndefaults: integrator rk4, radiation_choice: {choice}")
    print("goal: defaults warm ≤ 0.4 s with θ_rms and power within 0.5 % (issue 34)")


if __name__ == "__main__":
    main()
