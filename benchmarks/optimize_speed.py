"""Speed of mfm.optimize (issue 36's rows), not a test. Each row is a fresh child process with the
compilation cache off (its own compilation), then warm calls in the same process:

    python benchmarks/optimize_speed.py [--only wu_yuan m4_matrix confirm] [--repeats 3]

- ``wu_yuan``: Wu & Yuan model 1, the twelve WEC dampings (1e6–2e8 N m s/rad each) at one period
  (regular wave H 2 m, T 8 s): the first call from the process's start (import and load
  included), then warm at T 9, 10, 11 s (median). Goal: ≤ 60 s fresh, ≤ 10 s warm.
- ``m4_matrix``: M4 134, its four PTO dampings (0–30 N m s/rad) over the 120-sea matrix of
  benchmarks/power_matrix.py (10 H_s × 12 T_p JONSWAP, equal weights): fresh and warm. Goal ≤ 60 s.
- ``confirm``: the time-domain confirmation of an M4 134 optimum (regular 2 cm, T 1.2 s, dt 0.006 s,
  5,000 steps, Verlet + exact radiation) against the same simulate_batch alone, warm. Goal: the
  cost of one run.
"""
import argparse
import json
import os
import statistics
import subprocess
import sys
import time
import warnings
from pathlib import Path

T_START = time.perf_counter()
os.environ.setdefault("MFM_COMPILATION_CACHE", "off")  # compile times measured, not loaded (mfm.runner.xla)
ROOT = Path(__file__).resolve().parents[1]


def child_wu_yuan(repeats):
    import mfm
    from hydro.waves import Regular

    m = mfm.load(str(ROOT / "configs/wu_yuan_m1.toml"))
    params = {f"wec{i}.angle.damping": (1e6, 2e8) for i in range(1, 13)}
    ds = mfm.optimize(m, Regular(height=2.0, period=8.0), params)
    first = time.perf_counter() - T_START
    warm = []
    for T in (9.0, 10.0, 11.0)[:max(repeats, 1)]:
        t = time.perf_counter()
        mfm.optimize(m, Regular(height=2.0, period=T), params)
        warm.append(time.perf_counter() - t)
    return {"first_s": first, "warm_s": statistics.median(warm), "gain": float(ds.gain),
            "iterations": int(ds.iterations), "derivatives": ds.attrs["derivatives"]}


def child_m4_matrix(repeats):
    import numpy as np

    import hydro
    import mfm

    m = mfm.load(str(ROOT / "configs/m4_134.toml"))
    # the matrix of benchmarks/power_matrix.py: 10 H_s × 12 T_p, JONSWAP γ 3.3, seed 1
    seas = [hydro.Jonswap(hs=h, tp=t, gamma=3.3, seed=1, omega_range=(1.0, 25.0))
            for h in np.round(np.linspace(0.01, 0.06, 10), 3)
            for t in np.round(np.linspace(0.8, 1.8, 12), 3)]
    params = {f"{c}.damping": (0.0, 30.0) for c in m.coordinates[3:]}
    t = time.perf_counter()
    ds = mfm.optimize(m, seas, params)
    first_call = time.perf_counter() - t
    first = time.perf_counter() - T_START
    warm = []
    for _ in range(repeats):
        t = time.perf_counter()
        mfm.optimize(m, seas, params)
        warm.append(time.perf_counter() - t)
    return {"first_s": first, "first_call_s": first_call, "warm_s": statistics.median(warm),
            "gain": float(ds.gain), "optimum": ds.optimum.values.tolist(),
            "iterations": int(ds.iterations)}


def child_confirm(repeats):
    import mfm
    from hydro.waves import Regular

    m = mfm.load(str(ROOT / "configs/m4_134.toml"))
    sea = Regular(height=0.02, period=1.2)
    params = {f"{c}.damping": (0.0, 30.0) for c in m.coordinates[3:]}
    run = dict(dt=0.006, n_steps=5000)
    mfm.optimize(m, sea, params, confirm=run)            # compile both
    with_td, plain, alone = [], [], []
    for _ in range(repeats):
        t = time.perf_counter()
        ds = mfm.optimize(m, sea, params, confirm=run)
        with_td.append(time.perf_counter() - t)
        t = time.perf_counter()
        mfm.optimize(m, sea, params)
        plain.append(time.perf_counter() - t)
        t = time.perf_counter()
        mfm.simulate_batch(m, sea, integrator="verlet", radiation="state_space_exact", **run)
        alone.append(time.perf_counter() - t)
    return {"optimize_with_confirm_s": statistics.median(with_td),
            "optimize_s": statistics.median(plain), "simulate_batch_s": statistics.median(alone),
            "relative_difference": float(ds.time_domain_relative_difference)}


ROWS = {"wu_yuan": child_wu_yuan, "m4_matrix": child_m4_matrix, "confirm": child_confirm}


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--only", nargs="*", default=list(ROWS))
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--child", default=None)
    a = ap.parse_args(argv)
    if a.child:
        warnings.simplefilter("ignore")
        print("RESULT " + json.dumps(ROWS[a.child](a.repeats)))
        return
    for row in a.only:
        out = subprocess.run([sys.executable, __file__, "--child", row, "--repeats", str(a.repeats)],
                             capture_output=True, text=True, cwd=ROOT)
        line = [ln for ln in out.stdout.splitlines() if ln.startswith("RESULT ")]
        if not line:
            print(f"{row}: failed\n{out.stderr[-2000:]}")
            continue
        r = json.loads(line[0][7:])
        if row == "wu_yuan":
            print(f"Wu & Yuan m1, 12 dampings, one period: {r['first_s']:.1f} s from a fresh "
                  f"process (goal ≤ 60 s), {r['warm_s']:.2f} s warm (goal ≤ 10 s); gain at T 8 s "
                  f"{r['gain']:+.1%}, {r['iterations']} iterations, {r['derivatives']} mode")
        elif row == "m4_matrix":
            print(f"M4 134, 4 dampings over 120 seas: {r['first_s']:.1f} s from a fresh process "
                  f"(optimize {r['first_call_s']:.1f} s), {r['warm_s']:.2f} s warm (goal ≤ 60 s); "
                  f"gain {r['gain']:+.1%} at {[round(v, 2) for v in r['optimum']]} N m s/rad")
        else:
            print(f"M4 134 confirmation: optimize {r['optimize_s']:.2f} s, with the time domain "
                  f"{r['optimize_with_confirm_s']:.2f} s, simulate_batch alone "
                  f"{r['simulate_batch_s']:.2f} s (goal: the confirmation costs one run); "
                  f"time domain − spectral {r['relative_difference']:+.2%}")


if __name__ == "__main__":
    main()
