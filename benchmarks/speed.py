"""Issue 13's speed goals, each beside the accuracy it keeps (not a test).

    python benchmarks/speed.py [--repeats 3] [--baseline 853d6c5] [--skip-batch] [--write]

Runs each measurement in a child process (a fresh jax, so compile times are honest) for this
tree and, with ``--baseline REV``, for the code at git revision REV (extracted with ``git archive``
into a temporary folder, its own configs and databases) on the same machine in the same run, and
prints one markdown report; ``--write`` also puts it into benchmarks/RESULTS.md between the
``<!-- speed.py -->`` markers.

M4 134: JONSWAP H_s 0.04 m, T_p 1.2 s, γ 3.3, 100 T_p at dt = T_p/200 (20,000 steps), rollout
only (no per-step recording), warm = median of ``--repeats`` calls after the compiling one.
Accuracy against a reference run with the same radiation model: RK4 at dt/4 with the states
integrated (``radiation="state_space"``): the hinge angles' rms θ_rms and the mean PTO power
Σ c_k θ̇_k² over the last 80 T_p (the issue's criteria: within 0.5 %). RM3: a regular wave
H 2.5 m, T 8 s, 200 s at dt 0.1 s, ramp 20 s; pitch rms and mean PTO power over the last 100 s.
"""
import argparse
import json
import os
import re
import resource
import subprocess
import sys
import tempfile
import time
import warnings
from pathlib import Path

import numpy as np
os.environ.setdefault("MFM_COMPILATION_CACHE", "off")  # compile times measured, not loaded from disk (mfm.runner.xla)
os.environ.setdefault("MFM_FIT_CACHE", "off")          # fits too (hydro.fitcache)

ROOT = Path(__file__).resolve().parents[1]
SEED_PER_STEP = 0.0044          # s, seed 001 Table 3 (MATLAB MFM, 111 layout, i5 laptop)
TP, N_M4 = 1.2, 20_000


def _timed(fn, repeats):
    t0 = time.perf_counter()
    out = fn()
    first = time.perf_counter() - t0
    ts = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        out = fn()
        ts.append(time.perf_counter() - t0)
    return out, first, float(np.median(ts)) if ts else float("nan")


def _rollout(m, loads, dt, n, integ, save_every=1):
    import jax.numpy as jnp

    import mfm

    q0 = jnp.zeros(m.n_coordinates)
    out = mfm.rollout(m, q0, q0, dt=dt, n_steps=n, integrator=integ, loads=loads,
                      save_every=save_every)
    out[1].block_until_ready()
    return out


def _metrics(m, out, keep_from):
    """θ_rms of the revolute coordinates and the mean joint-damper power, after ``keep_from``."""
    q, qd = np.asarray(out[1])[keep_from:], np.asarray(out[2])[keep_from:]
    c = np.asarray(m.damping)
    ang = [k for k, name in enumerate(m.coordinates) if name.endswith(".angle")]
    return {"rms": np.sqrt(np.mean(q**2, axis=0)).tolist(), "theta_rms": np.sqrt(np.mean(q[:, ang]**2, axis=0)).tolist(),
            "power": float(np.mean(np.sum(c * qd**2, axis=1))), "finite": bool(np.isfinite(q).all())}


def child_m4(new, repeats, batch):
    import equinox as eqx

    import hydro
    import mfm
    from mfm.timedomain.setup import model_loads

    res = {}
    sea = hydro.Jonswap(hs=0.04, tp=TP, gamma=3.3, seed=1, omega_range=(1.0, 25.0))
    dt = TP / 200
    if new:
        m, ds, wall = _defaults_call()
        res["defaults"] = {"wall": wall, "choice": ds.attrs["radiation_choice"],
                           "integrator": ds.attrs["integrator"]}
        # the same call again: the fit is cached on the model, the compilation is not redone
        _, _, res["defaults"]["warm"] = _timed(
            lambda: mfm.simulate(m, sea, duration=N_M4 * dt, dt=dt, ramp=5 * TP), 1)
    else:
        m = mfm.load(ROOT / "configs" / "m4_134.toml")
    t0 = time.perf_counter()
    ss = m.hydro.state_space()
    r = dict(ss.report)
    res["fit"] = {"wall": time.perf_counter() - t0 if not new else None,
                  "states": int(r.get("n_states", ss.A.shape[0])),
                  "error": float(r.get("overall_error", np.nan)),
                  "passive": bool(r.get("passive", False)),
                  "min_eig": float(r.get("passivity_min_eig", np.nan))}
    if new:
        # the fit's own time, in a model that has none cached
        m_fresh = mfm.load(ROOT / "configs" / "m4_134.toml")
        if "hydro.fitcache" in sys.modules:       # fits kept by content in the process
            sys.modules["hydro.fitcache"].clear()
        t0 = time.perf_counter()
        m_fresh.hydro.state_space()
        res["fit"]["wall"] = time.perf_counter() - t0
    keep = N_M4 // 5
    loads = model_loads(m, sea, dt=dt / 4, duration=N_M4 * dt, ramp=5 * TP, radiation="state_space")
    out = _rollout(m, loads, dt / 4, 4 * N_M4, "rk4", save_every=4)
    res["reference"] = _metrics(m, out, keep)
    cases = [("rk4", "state_space")]
    if new:
        cases += [("rk4", "state_space_exact"), ("verlet", "state_space_exact")]
    else:
        cases += [("semi_implicit", "state_space")]
    for integ, rad in cases:
        loads = model_loads(m, sea, dt=dt, duration=N_M4 * dt, ramp=5 * TP, radiation=rad,
                            **({"integrator": integ} if new else {}))
        out, first, warm = _timed(lambda: _rollout(m, loads, dt, N_M4, integ), repeats)
        res[f"{integ}/{rad}"] = {"first": first, "warm": warm, **_metrics(m, out, keep)}
    out, first, warm = _timed(lambda: mfm.simulate(m, sea, duration=N_M4 * dt, dt=dt, ramp=5 * TP,
                                                   radiation="state_space"), max(1, repeats - 1))
    res["simulate rk4/state_space"] = {"first": first, "warm": warm}
    if not new:
        return res
    # the cost of one step of the fast path, part by part
    from mfm.loads.radiation import NoRadiation

    loads = model_loads(m, sea, dt=dt, duration=N_M4 * dt, ramp=5 * TP,
                        radiation="state_space_exact", integrator="verlet")
    w = loads[0]
    parts = {"mechanics only": loads[1:],
             "+ water without radiation": (eqx.tree_at(lambda x: x.rad, w, NoRadiation()),) + loads[1:],
             "+ radiation (all)": loads}
    res["parts"] = {}
    for k, lds in parts.items():
        _, first, warm = _timed(lambda: _rollout(m, lds, dt, N_M4, "verlet"), repeats)
        res["parts"][k] = warm
    n_x, n_out = int(w.rad.p.shape[0]), len(w.rad.outputs)
    # the water works on the moved hydro dofs (mfm.loads.water.Water._moved_load)
    nd, nm, nq = len(m.hydro.dofs), len(m.hydro.moving), m.n_coordinates
    res["flops"] = {"radiation": 14 * n_x + 4 * n_out * n_x,
                    "added_mass_product": 2 * (nm * nm * nq + nq * nm * nq),
                    "water_plane_product": 2 * nm * nd, "n_x": n_x, "n_out": n_out, "nd": nd,
                    "nm": nm}
    if batch:
        tps = np.round(np.linspace(0.8, 1.8, 12), 3)
        hss = np.round(np.linspace(0.01, 0.06, 10), 3)
        seas = [hydro.Jonswap(hs=h, tp=t, gamma=3.3, seed=1, omega_range=(1.0, 25.0))
                for h in hss for t in tps]
        res["batch"] = []
        res["threads"] = sys.modules["mfm.runner.batch"].default_threads()
        for B in (1, 4, 16, 64, 128):
            ss_b = (seas * 2)[:B]
            dts = np.array([s.tp / 200 for s in ss_b])
            # ramp 5 T_p (= 1000 dt), as everywhere else here (the cost does not depend on it)
            fn = lambda: mfm.simulate_batch(m, ss_b, dt=dts, n_steps=2000, ramp=1000 * dts,  # noqa: E731
                                            integrator="verlet", radiation="state_space_exact",
                                            save_every=100)
            _, first, warm = _timed(fn, 1)
            res["batch"].append({"B": B, "first": first, "warm": warm,
                                 "maxrss_GB": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1e6})
        dts = np.array([s.tp / 200 for s in seas])
        t0 = time.perf_counter()
        ds = mfm.simulate_batch(m, seas, dt=dts, n_steps=N_M4, ramp=1000 * dts, integrator="verlet",
                                radiation="state_space_exact", save_every=10)
        wall = time.perf_counter() - t0
        p = ds.pto_power.sum("pto").isel(step=slice(N_M4 // 50, None)).mean("step").values
        res["power_matrix"] = {"wall": wall, "cases": len(seas), "steps": N_M4,
                               "power_W": p.reshape(len(hss), len(tps)).tolist(),
                               "maxrss_GB": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1e6}
    return res


def child_rm3(new, repeats):
    import hydro
    import mfm
    from mfm.timedomain.setup import model_loads

    m = mfm.load(ROOT / "configs" / "rm3.toml")
    sea = hydro.Regular(height=2.5, period=8.0)
    dt, n = 0.1, 2000
    keep = n // 2
    res = {}
    loads = model_loads(m, sea, dt=dt / 4, duration=n * dt, ramp=20.0, radiation="state_space")
    res["reference"] = _metrics(m, _rollout(m, loads, dt / 4, 4 * n, "rk4", save_every=4), keep)
    cases = [("rk4", "state_space")] + ([("verlet", "state_space_exact")] if new else [])
    for integ, rad in cases:
        loads = model_loads(m, sea, dt=dt, duration=n * dt, ramp=20.0, radiation=rad,
                            **({"integrator": integ} if new else {}))
        out, first, warm = _timed(lambda: _rollout(m, loads, dt, n, integ), repeats)
        res[f"{integ}/{rad}"] = {"first": first, "warm": warm, **_metrics(m, out, keep)}
        kw = {"integrator": integ} if new else {}
        _, first, warm = _timed(lambda: mfm.simulate(m, sea, duration=n * dt, dt=dt, ramp=20.0,
                                                     radiation=rad, **kw), repeats)
        res[f"simulate {integ}/{rad}"] = {"first": first, "warm": warm}
    return res


def _defaults_call():
    """What a new user waits for: load, ``mfm.simulate`` with its defaults (radiation="auto"),
    one call. Returns (model, dataset, wall time)."""
    import hydro
    import mfm

    sea = hydro.Jonswap(hs=0.04, tp=TP, gamma=3.3, seed=1, omega_range=(1.0, 25.0))
    t0 = time.perf_counter()
    m = mfm.load(ROOT / "configs" / "m4_134.toml")
    ds = mfm.simulate(m, sea, duration=N_M4 * TP / 200, dt=TP / 200, ramp=5 * TP)
    return m, ds, time.perf_counter() - t0


def child_defaults():
    """The defaults call alone, for a fresh process that finds the compilation cache filled by
    an earlier one."""
    return {"wall": _defaults_call()[2]}


def run_child(tree, what, new, repeats, batch, cache="off"):
    # a fresh process of this script on the code of ``tree``: PYTHONPATH puts that tree before any
    # installed mfm (the child does not touch sys.path). cache: a folder for the child's compiled
    # programs (MFM_COMPILATION_CACHE) and radiation fits (MFM_FIT_CACHE, a subfolder), or "off":
    # every compilation and fit timed, none loaded
    env = dict(os.environ, PYTHONPATH=str(tree), OMP_NUM_THREADS="1", MFM_COMPILATION_CACHE=cache,
               MFM_FIT_CACHE=cache if cache == "off" else str(Path(cache) / "fits"))
    cmd = [sys.executable, str(Path(__file__).resolve()), "--child", what, "--repeats", str(repeats)]
    cmd += (["--new"] if new else []) + (["--batch"] if batch else [])
    t0 = time.perf_counter()
    p = subprocess.run(cmd, cwd=tree, env=env, capture_output=True, text=True)
    if p.returncode:
        raise RuntimeError(f"{what} in {tree} failed:\n{p.stderr[-3000:]}")
    print(f"  [{what} in {tree.name}: {time.perf_counter() - t0:.0f} s]", file=sys.stderr)
    return json.loads(p.stdout.strip().splitlines()[-1])


def err(a, b):
    a, b = np.asarray(a, float), np.asarray(b, float)
    return float(np.max(np.abs(a / b - 1)))


def _cases(old, new, rev, system):
    """(code label, "integrator/radiation", result, reference) of each timed case, baseline first."""
    for code, res in (("baseline " + str(rev), old[system] if old else None), ("this tree", new[system])):
        if res is None:
            continue
        for k, v in res.items():
            if "/" in k and not k.startswith("simulate"):
                yield code, k, v, res["reference"], res


def report(new, old, rev):
    L = []
    m4 = new["m4"]
    L.append(f"Made by `python benchmarks/speed.py{' --baseline ' + rev if rev else ''} --write` "
             f"({time.strftime('%Y-%m-%d')}; the 2-core machine is shared: compare ratios within "
             "this table, not absolute times across runs).\n")
    L.append("**M4 134, JONSWAP T_p 1.2 s, 100 T_p at T_p/200 (20,000 steps), rollout warm** "
             "(accuracy against RK4 at dt/4, same fit; θ_rms of the four hinges and mean PTO "
             "power over the last 80 T_p; seed 001: 0.0044 s/step = 88 s):\n")
    L.append("| code | integrator / radiation | first | warm | µs/step | × seed | × baseline "
             "| θ_rms err | power err | surge rms err |")
    L.append("|---|---|---|---|---|---|---|---|---|---|")
    base = old["m4"]["rk4/state_space"]["warm"] if old else None
    for code, k, v, ref, _ in _cases(old, new, rev, "m4"):
        L.append(f"| {code} | {k} | {v['first']:.1f} s | {v['warm']:.3f} s | "
                 f"{v['warm'] / N_M4 * 1e6:.0f} | {SEED_PER_STEP * N_M4 / v['warm']:.0f} | "
                 + (f"{base / v['warm']:.2f} | " if base else "— | "))
        L[-1] += (f"{err(v['theta_rms'], ref['theta_rms']):.1e} | "
                  f"{abs(v['power'] / ref['power'] - 1):.1e} | "
                  f"{abs(v['rms'][0] / ref['rms'][0] - 1):.1e} |" if v["finite"] else
                  "non-finite | — | — |")
    L.append("")
    f = m4["fit"]
    L.append(f"**The radiation fit of M4 134** (`m.hydro.state_space()`, 24 moved dofs): "
             f"{f['wall']:.1f} s, {f['states']} states, band error {f['error']:.4f}, passive "
             f"{f['passive']} (min eig {f['min_eig']:.1e})"
             + (f"; baseline {old['m4']['fit']['wall']:.1f} s, {old['m4']['fit']['states']} states, "
                f"band error {old['m4']['fit']['error']:.4f}, passive {old['m4']['fit']['passive']}"
                if old else "") + ".\n")
    d = m4["defaults"]
    L.append(f"**`mfm.simulate(mfm.load('configs/m4_134.toml'), sea, duration=120, dt=0.006, "
             f"ramp=6)` with the defaults**, a fresh process (load, fit, compile, run, dataset): "
             f"{d['wall']:.1f} s without caches ({d['filling']:.1f} s filling them); "
             f"{d['cached']:.1f} s in a later fresh process that loads the compiled programs and "
             f"the radiation fit from them (`mfm.runner.xla`, `hydro.fitcache`); the same call again in "
             f"one process {d['warm']:.1f} s. Integrator "
             f"{d['integrator']}; {d['choice']}.\n")
    s = m4["simulate rk4/state_space"]
    L.append(f"`mfm.simulate` (dataset recorded every step), RK4, state space: first {s['first']:.1f} s, "
             f"warm {s['warm']:.2f} s"
             + (f" (baseline {old['m4']['simulate rk4/state_space']['warm']:.2f} s)" if old else "")
             + ".\n")
    p = m4["parts"]
    fl = m4["flops"]
    keys = list(p)
    L.append("**One step of the fast path (Verlet, exact radiation), part by part** (warm rollouts "
             "with the parts added in turn; flops per evaluation):\n")
    L.append("| part | µs/step | flops |")
    L.append("|---|---|---|")
    L.append(f"| mechanics (7 coordinates, 8 bodies) | {p[keys[0]] / N_M4 * 1e6:.1f} | — |")
    L.append(f"| water without radiation (excitation, hydrostatics, A∞ H; {fl.get('nm', fl['nd'])} "
             f"moved of {fl['nd']} hydro dofs) | {(p[keys[1]] - p[keys[0]]) / N_M4 * 1e6:.1f} | HᵀA∞H "
             f"{fl['added_mass_product']:,}, C_wp ξ {fl['water_plane_product']:,} |")
    L.append(f"| radiation ({fl['n_x']} complex states → {fl['n_out']} dofs) | "
             f"{(p[keys[2]] - p[keys[1]]) / N_M4 * 1e6:.1f} | {fl['radiation']:,} |")
    L.append("")
    if "batch" in m4:
        L.append("**Batches** (`simulate_batch`, Verlet, exact radiation, 2,000 steps per case; "
                 f"its CPU defaults: the cases in turn in {m4.get('threads', 1)} parts, one thread "
                 "each):\n")
        L.append("| cases | first | warm | µs per case-step | peak memory (process) |")
        L.append("|---|---|---|---|---|")
        for b in m4["batch"]:
            L.append(f"| {b['B']} | {b['first']:.1f} s | {b['warm']:.2f} s | "
                     f"{b['warm'] / (b['B'] * 2000) * 1e6:.1f} | {b['maxrss_GB']:.1f} GB |")
        pm = m4["power_matrix"]
        L.append(f"\n**Power matrix** 10 H_s (0.01–0.06 m) × 12 T_p (0.8–1.8 s), 100 T_p each "
                 f"(20,000 steps), one `simulate_batch` call (its defaults), water loads, fit and compilation included: {pm['wall']:.1f} s "
                 f"({pm['wall'] / pm['cases']:.2f} s per sea state), peak memory {pm['maxrss_GB']:.1f} GB.\n")
    L.append("**RM3, regular wave H 2.5 m, T 8 s, 200 s at dt 0.1 s** (accuracy against RK4 at "
             "dt/4; pitch rms and PTO power over the last 100 s):\n")
    L.append("| code | integrator / radiation | rollout warm | `simulate` warm | × baseline | pitch rms err | power err | surge rms err |")
    L.append("|---|---|---|---|---|---|---|---|")
    base = old["rm3"]["rk4/state_space"]["warm"] if old else None
    for code, k, v, ref, res in _cases(old, new, rev, "rm3"):
        sim = res[f"simulate {k}"]["warm"]
        L.append(f"| {code} | {k} | {v['warm'] * 1e3:.0f} ms | {sim * 1e3:.0f} ms | "
                 + (f"{base / v['warm']:.2f} | " if base else "— | ")
                 + f"{abs(v['rms'][2] / ref['rms'][2] - 1):.1e} | {abs(v['power'] / ref['power'] - 1):.1e} | "
                 f"{abs(v['rms'][0] / ref['rms'][0] - 1):.1e} |")
    return "\n".join(L) + "\n"


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--baseline", default=None, help="a git revision to measure beside this tree")
    ap.add_argument("--skip-batch", action="store_true")
    ap.add_argument("--write", action="store_true", help="write the report into RESULTS.md")
    ap.add_argument("--child", help=argparse.SUPPRESS)
    ap.add_argument("--new", action="store_true", help=argparse.SUPPRESS)
    ap.add_argument("--batch", action="store_true", help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.child:
        # the tree timed comes first on the path through the PYTHONPATH run_child set
        warnings.simplefilter("ignore")
        res = (child_m4(args.new, args.repeats, args.batch) if args.child == "m4"
               else child_defaults() if args.child == "defaults"
               else child_rm3(args.new, args.repeats))
        print(json.dumps(res))
        return
    new = {"rm3": run_child(ROOT, "rm3", True, args.repeats, False),
           "m4": run_child(ROOT, "m4", True, args.repeats, not args.skip_batch)}
    # the defaults call in two fresh processes sharing the caches: the second loads what the
    # first compiled and fitted (mfm.runner.xla, hydro.fitcache)
    with tempfile.TemporaryDirectory() as cache:
        walls = [run_child(ROOT, "defaults", True, 0, False, cache=cache)["wall"] for _ in range(2)]
    new["m4"]["defaults"].update(filling=walls[0], cached=walls[1])
    old = None
    if args.baseline:
        with tempfile.TemporaryDirectory() as tmp:
            tree = Path(tmp) / f"mfm_{args.baseline}"
            tree.mkdir()
            archive = subprocess.run(["git", "-C", str(ROOT), "archive", args.baseline],
                                     capture_output=True, check=True).stdout
            subprocess.run(["tar", "-x", "-C", str(tree)], input=archive, check=True)
            old = {"rm3": run_child(tree, "rm3", False, args.repeats, False),
                   "m4": run_child(tree, "m4", False, args.repeats, False)}
    text = report(new, old, args.baseline)
    print(text)
    if args.write:
        path = ROOT / "benchmarks" / "RESULTS.md"
        body = path.read_text()
        block = f"<!-- speed.py -->\n## Speed (issue 13)\n\n{text}<!-- /speed.py -->\n"
        if "<!-- speed.py -->" in body:
            body = re.sub(r"<!-- speed.py -->.*<!-- /speed.py -->\n", lambda _: block, body, flags=re.S)
        else:
            body = body.replace("\n## ", "\n" + block + "\n## ", 1)
        path.write_text(body)


if __name__ == "__main__":
    main()
