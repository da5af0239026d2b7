"""Compare this tree's RM3 and M4 results with those of another commit (default 853d6c5, before
loads became plug-ins): the same runs in both trees, in subprocesses, and the largest relative
difference of each output. Prints a table; exits 1 if any differs by more than --rtol (1e-10).

    python tools/regression_check.py [--commit 853d6c5] [--rtol 1e-10]
"""
from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent

PROBE = r'''
import json, sys, warnings
import numpy as np
warnings.simplefilter("ignore")
import hydro, mfm
out = {}
def put(name, a):
    z = np.asarray(a, dtype=complex).ravel()
    out[name] = np.stack([z.real, z.imag], 1).tolist()
rm3 = mfm.load("configs/rm3.toml")
sea = hydro.Regular(height=2.5, period=8.0)
for rad in ("convolution", "state_space"):
    ds = mfm.simulate(rm3, sea, duration=40.0, dt=0.1, ramp=10.0, radiation=rad)
    for v in ("q", "qd", "joint_force", "pto_power", "hydro_force"):
        put(f"rm3 simulate {rad} {v}", ds[v].values)
sea_i = hydro.Jonswap(hs=2.0, tp=9.0, gamma=3.3, seed=1)
ds = mfm.simulate(rm3, sea_i, duration=30.0, dt=0.1, ramp=10.0, radiation="state_space",
                  integrator="newmark")
put("rm3 simulate jonswap newmark q", ds.q.values)
om = np.linspace(0.3, 1.8, 16)
for rad in ("database", "convolution"):
    fr = mfm.frequency_response(rm3, om, radiation=rad)
    put(f"rm3 frequency_response {rad} rao", fr.rao.values)
    put(f"rm3 frequency_response {rad} pto_power", fr.pto_power.values)
nat = mfm.natural_frequencies(rm3)
put("rm3 natural_frequencies eigen", np.asarray(nat["eigen"]))
put("rm3 equilibrium", mfm.equilibrium(rm3)[0])
for name in ("m4_111", "m4_134"):
    m = mfm.load(f"configs/{name}.toml")
    s = hydro.Jonswap(hs=0.04, tp=1.2, gamma=3.3, seed=1, omega_range=(1.0, 25.0))
    ds = mfm.simulate(m, s, duration=1.2, dt=0.006, ramp=0.6, radiation="convolution", memory=1.0)
    put(f"{name} simulate q", ds.q.values)
    put(f"{name} simulate pto_power", ds.pto_power.values)
    fr = mfm.frequency_response(m, np.linspace(3.0, 9.0, 7))
    put(f"{name} frequency_response rao", fr.rao.values)
ds = mfm.simulate(mfm.load("configs/m4_111.toml"), hydro.Regular(height=0.04, period=1.0),
                  duration=0.6, dt=0.005, radiation="none", integrator="beeman")
put("m4_111 simulate beeman q", ds.q.values)
json.dump(out, open(sys.argv[1], "w"))
'''


def run(tree: Path, out: Path):
    env = dict(os.environ, PYTHONPATH=str(tree))
    subprocess.run([sys.executable, "-c", PROBE, str(out)], cwd=tree, env=env, check=True)
    return json.loads(out.read_text())


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--commit", default="853d6c5")
    ap.add_argument("--rtol", type=float, default=1e-10)
    args = ap.parse_args(argv)
    import numpy as np

    with tempfile.TemporaryDirectory() as tmp:
        old = Path(tmp) / "old"
        subprocess.run(["git", "-C", str(ROOT), "worktree", "add", "--detach", str(old), args.commit],
                       check=True, capture_output=True)
        try:
            ref = run(old, Path(tmp) / "old.json")
        finally:
            subprocess.run(["git", "-C", str(ROOT), "worktree", "remove", "--force", str(old)],
                           capture_output=True)
        new = run(ROOT, Path(tmp) / "new.json")
    worst = 0.0
    print(f"{'output':48s} {'max |new − old| / max |old|':>28s}")
    for k, a in ref.items():
        a = np.asarray([complex(*x) if isinstance(x, list) else complex(x) for x in a])
        b = np.asarray([complex(*x) if isinstance(x, list) else complex(x) for x in new[k]])
        if a.shape != b.shape:
            print(f"{k:48s} shape {a.shape} → {b.shape}")
            worst = np.inf
            continue
        d = float(np.max(np.abs(b - a)) / max(np.max(np.abs(a)), 1e-300)) if a.size else 0.0
        worst = max(worst, d)
        print(f"{k:48s} {d:28.2e}")
    print(f"largest: {worst:.2e} (tolerance {args.rtol:g}) against commit {args.commit}")
    return 0 if worst <= args.rtol else 1


if __name__ == "__main__":
    sys.exit(main())
