"""Issue 53's batch above linear: ``mfm.simulate_batch`` of the nonlinear sphere over many seas,
its cost per case-step against one ``mfm.simulate`` per case (not a test).

    python benchmarks/nonlinear_batch.py [--cases 16] [--steps 400] [--panel 0.125]
                                         [--options nonlinear relative newman] [--lanes N]

The floating sphere (configs/sphere.toml, R 1 m, surge–heave–pitch) with the [hydro] options
asked (``nonlinear``: hydrostatics = "nonlinear" with the sphere hull of ``--panel`` m;
``relative``: drag_flow = "relative" with C_D 1 on 3.1 m²; the drift needs a database with a
mean_drift: not the sphere's), in B regular seas of heights 0.2–1.0 m and periods 3.5–6 s and,
every fourth case, a 4-component JONSWAP (the regular ones padded to 4 components), dt 0.05 s,
ramp 4 s, radiation "state_space". Rows: the batch's first call (compiling) and its warm wall
time (the median of ``--repeats``), per case-step; one ``mfm.simulate`` of a regular case and of
a JONSWAP case warm, per step (a batch's case costs what its most components cost: the padded
ones are evaluated too). ``--lanes``: the cases vmapped together (default: all on a GPU, 1 on a CPU). On a GPU
the issue's benchmark is ``--cases 1000``.

Figures depend on the machine and its load: quote them with the machine (RESULTS.md).
"""
from __future__ import annotations

import argparse
import copy
import os
import time
import tomllib
import warnings
from pathlib import Path

import numpy as np

os.environ.setdefault("MFM_FIT_CACHE", "off")

ROOT = Path(__file__).resolve().parents[1]


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cases", type=int, default=16)
    ap.add_argument("--steps", type=int, default=400)
    ap.add_argument("--panel", type=float, default=0.125)
    ap.add_argument("--options", nargs="+", default=["nonlinear"],
                    choices=["nonlinear", "relative"])
    ap.add_argument("--lanes", type=int, default=None)
    ap.add_argument("--repeats", type=int, default=3)
    args = ap.parse_args()

    import jax

    import hydro
    import mfm

    warnings.simplefilter("ignore")
    cfg = tomllib.loads((ROOT / "configs" / "sphere.toml").read_text())
    cfg = copy.deepcopy(cfg)
    if "nonlinear" in args.options:
        cfg["hydro"]["hydrostatics"] = "nonlinear"
        cfg["bodies"][0]["hull"] = {"shape": "sphere", "radius": 1.0, "panel_size": args.panel}
    if "relative" in args.options:
        cfg["hydro"]["drag_flow"] = "relative"
        cfg["bodies"][0]["hydro"] = {"drag_coefficient": [1.0, 1.0, 1.0],
                                     "drag_area": [3.1, 3.1, 3.1]}
    model = mfm.load(cfg, base=ROOT / "configs")
    B, n, dt = args.cases, args.steps, 0.05
    rng = np.random.default_rng(0)
    seas = [hydro.Jonswap(hs=0.5, tp=4.5, n_components=4, seed=i,
                          omega_range=(0.5, 6.0)) if i % 4 == 3 else
            hydro.Regular(height=float(rng.uniform(0.2, 1.0)), period=float(rng.uniform(3.5, 6.0)))
            for i in range(B)]
    kw = dict(dt=dt, ramp=4.0, radiation="state_space")

    t0 = time.perf_counter()
    mfm.simulate_batch(model, seas, n_steps=n, lanes=args.lanes, **kw)
    first = time.perf_counter() - t0
    walls = []
    for _ in range(args.repeats):
        t0 = time.perf_counter()
        out = mfm.simulate_batch(model, seas, n_steps=n, lanes=args.lanes, **kw)
        walls.append(time.perf_counter() - t0)
    warm = float(np.median(walls))
    assert np.isfinite(out.q.values).all()
    single = {}
    for i in (0, 3) if B > 3 else (0,):
        mfm.simulate(model, seas[i], duration=n * dt, check_stability=False, **kw)
        times = []
        for _ in range(args.repeats):
            t0 = time.perf_counter()
            mfm.simulate(model, seas[i], duration=n * dt, check_stability=False, **kw)
            times.append(time.perf_counter() - t0)
        single[i] = float(np.median(times))
    panels = ", ".join(str(len(T)) for T in getattr(model.hydro, "hulls", ())) or "-"
    print(f"backend {jax.default_backend()} ({jax.devices()[0].device_kind}); options "
          f"{args.options}; hull panels {panels}; {B} cases x {n} RK4 steps, lanes "
          f"{out.attrs.get('lanes')}")
    print("| what | wall s | µs per case-step |")
    print("|---|---|---|")
    print(f"| simulate_batch, first call (compiling) | {first:.2f} | {first / B / n * 1e6:,.0f} |")
    print(f"| simulate_batch, warm | {warm:.3f} | {warm / B / n * 1e6:,.1f} |")
    for i, w in single.items():
        what = "a regular case (1 component)" if i == 0 else "a JONSWAP case (4 components)"
        print(f"| mfm.simulate of {what}, warm | {w:.3f} | {w / n * 1e6:,.1f} |")


if __name__ == "__main__":
    main()
