"""A batch's cost outside the stepping, and large studies (issue 34's rows "per-case cost outside
the stepping in a batch", "10,000-case M4 134 study" and the GPU rows). Prints figures; not a test.

    OMP_NUM_THREADS=1 python benchmarks/batch_prepare.py [--cases 240] [--repeats 3]
        [--study 0] [--study-steps 20000] [--chunk 240] [--reference PATH]

Every case is M4 134 (configs/m4_134.toml) in a JONSWAP sea of the power matrix's range
(Hs 0.01–0.06 m, Tp 0.8–1.8 s, γ 3.3, a seed per case), dt = Tp/200, Verlet with the exact
state-space radiation, ``simulate_batch``'s defaults otherwise (threads: one per core on a CPU,
the cases in one vmapped loop on a GPU).

- **Outside the stepping**: the warm wall time T(n) of ``cases`` cases of n steps, at n = 200 and
  400; the cost a case pays whatever its length is the extrapolation to no steps,
  (2 T(200) − T(400)) / cases, beside the same for one case (the issue measured it as
  T(240 × 200) against T(1 × 200)). Medians of ``--repeats`` warm calls, alternated.
- **Study** (``--study N``): N cases of ``--study-steps`` steps in chunks of ``--chunk`` cases,
  one ``simulate_batch`` each (every 10th sample kept), after a first chunk that compiles: the
  warm wall time of the whole study, per case and per step, and each chunk's; and the time of the
  compiled time loops alone (``batch._batch_jit``, timed in the threads that run them, per
  thread) and of the wave tables (``batch._tables``): the study against the stepping alone.
- **The host's preparation alone**: the warm time of ``carried_loads_batch`` for the ``cases``
  cases (the seas discretised together, the radiation's arrays for every dt, the excitation
  brackets; what the batch does on the host before the device makes the tables), per case.
- ``--reference PATH``: save the study's mean PTO power per case (``.npy``), or compare with a
  saved one (a CPU run against a GPU run: the largest relative difference is printed).
"""
from __future__ import annotations

import argparse
import statistics
import time
import warnings
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]


def seas_of(n, seed=0):
    import hydro

    rng = np.random.default_rng(seed)
    hs, tp = rng.uniform(0.01, 0.06, n), rng.uniform(0.8, 1.8, n)
    seeds = rng.integers(0, 2**31 - 1, n)
    return [hydro.Jonswap(hs=float(h), tp=float(t), gamma=3.3, seed=int(s), omega_range=(1.0, 25.0))
            for h, t, s in zip(hs, tp, seeds)], tp / 200


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cases", type=int, default=240)
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--study", type=int, default=0, help="cases of the large study (0: none)")
    ap.add_argument("--study-steps", type=int, default=20000)
    ap.add_argument("--chunk", type=int, default=240)
    ap.add_argument("--reference", type=Path, default=None)
    ap.add_argument("--skip-prepare", action="store_true")
    args = ap.parse_args(argv)
    warnings.simplefilter("ignore")
    import jax

    import mfm

    m = mfm.load(ROOT / "configs" / "m4_134.toml")
    print(f"backend {jax.default_backend()} ({jax.devices()[0].device_kind}), jax {jax.__version__}")
    kw = dict(integrator="verlet", radiation="state_space_exact")

    if not args.skip_prepare:
        seas, dts = seas_of(args.cases)

        def run(n_cases, n_steps):
            return lambda: mfm.simulate_batch(m, seas[:n_cases], dt=dts[:n_cases],
                                              ramp=5 * dts[:n_cases] * 200, n_steps=n_steps, **kw)

        calls = {(c, n): run(c, n) for c in (1, args.cases) for n in (200, 400)}
        for f in calls.values():     # compile every shape first
            f()
        times = {k: [] for k in calls}
        for _ in range(args.repeats):
            for k, f in calls.items():
                t = time.perf_counter()
                f()
                times[k].append(time.perf_counter() - t)
        med = {k: statistics.median(v) for k, v in times.items()}
        B = args.cases
        print(f"warm medians of {args.repeats}: " + ", ".join(
            f"{c} × {n}: {med[(c, n)]:.3f} s" for c, n in calls))
        fixed_b = (2 * med[(B, 200)] - med[(B, 400)]) / B
        fixed_1 = 2 * med[(1, 200)] - med[(1, 400)]
        print(f"outside the stepping, per case (extrapolated to no steps): {1e3 * fixed_b:.2f} ms "
              f"in a batch of {B}; {1e3 * fixed_1:.1f} ms for one case alone")
        print(f"as the issue measured it, (T({B} × 200) − T(1 × 200)) / {B - 1} − stepping: "
              f"{1e3 * (med[(B, 200)] - med[(1, 200)]) / (B - 1):.2f} ms per case in all "
              f"(stepping of 200 steps per case {1e3 * (med[(B, 400)] - med[(B, 200)]) / B:.2f} ms)")

        # the host's part alone, timed directly (the extrapolation above differences two noisy
        # times of which the stepping is most): the cases' loads made together
        # (loads.assembly.carried_loads_batch: the seas discretised, the radiation's arrays for
        # every dt, the excitation brackets), before the device makes their tables
        from mfm.loads.assembly import carried_loads_batch
        from mfm.timedomain import integrators
        from mfm.timedomain.setup import stage_offsets

        offsets = stage_offsets(integrators.get(kw["integrator"]))

        def prepare():
            carried_loads_batch(m, seas, dts=dts, ramps=5 * dts * 200, n_steps=200, t0=0.0,
                                radiation=kw["radiation"], memory=None,
                                state_space_options=None, stage_offsets=offsets)

        prepare()
        host = []
        for _ in range(max(3, args.repeats)):
            t = time.perf_counter()
            prepare()
            host.append(time.perf_counter() - t)
        print(f"the host's preparation alone (carried_loads_batch, {B} cases, median of "
              f"{len(host)}): {1e3 * statistics.median(host) / B:.3f} ms per case")

    if args.study:
        # the time each part's compiled loop and its tables take, from the threads that run them
        # (blocking on each result there, as simulate_batch's threads do anyway)
        import mfm.runner.batch as batch_mod

        spent = {"stepping": [], "tables": []}

        def timed(fn, what):
            def call(*a, **k):
                t = time.perf_counter()
                out = jax.block_until_ready(fn(*a, **k))
                spent[what].append(time.perf_counter() - t)
                return out
            return call

        batch_mod._batch_jit = timed(batch_mod._batch_jit, "stepping")
        batch_mod._tables = timed(batch_mod._tables, "tables")
        N, n = args.study, args.study_steps
        seas, dts = seas_of(N, seed=1)
        chunk = min(args.chunk, N)
        skw = dict(n_steps=n, save_every=10, **kw)
        t = time.perf_counter()
        mfm.simulate_batch(m, seas[:chunk], dt=dts[:chunk], ramp=5 * dts[:chunk] * 200, **skw)
        first = time.perf_counter() - t
        for v in spent.values():
            v.clear()
        t = time.perf_counter()
        power, walls = [], []
        for k in range(0, N, chunk):
            sl = slice(k, min(N, k + chunk))
            tc = time.perf_counter()
            ds = mfm.simulate_batch(m, seas[sl], dt=dts[sl], ramp=5 * dts[sl] * 200, **skw)
            walls.append(time.perf_counter() - tc)
            last = ds.pto_power.isel(step=slice(ds.sizes["step"] // 2, None))
            power.append(np.asarray(last.sum("pto").mean("step")))
        total = time.perf_counter() - t
        power = np.concatenate(power)
        n_chunks = len(walls)
        print(f"study: {N} cases × {n} steps in {n_chunks} chunks of {chunk}: {total:.1f} s warm "
              f"({1e3 * total / N:.2f} ms per case, {1e6 * total / n:.1f} µs per step of the "
              f"whole study); the first chunk (compiling) {first:.1f} s; chunks "
              f"{', '.join(f'{w:.2f}' for w in walls[:6])}{' …' if n_chunks > 6 else ''} s")
        parts = max(1, len(spent["stepping"]) // n_chunks)     # the threads of a chunk
        step_s = sum(spent["stepping"]) / parts
        tab_s = sum(spent["tables"]) / parts
        print(f"of which the compiled time loops {step_s:.1f} s and the wave tables {tab_s:.1f} s "
              f"per thread ({parts} threads); the whole study {total / step_s:.2f} × the stepping "
              f"alone")
        if args.reference is not None:
            if args.reference.exists():
                ref = np.load(args.reference)
                k = min(ref.size, power.size)
                rel = np.abs(power[:k] - ref[:k]).max() / np.abs(ref[:k]).max()
                print(f"against {args.reference} ({k} cases): largest difference of the mean "
                      f"PTO power {rel:.2e} of its largest")
            else:
                np.save(args.reference, power)
                print(f"saved the mean PTO power of each case to {args.reference}")


if __name__ == "__main__":
    main()
