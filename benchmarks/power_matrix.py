"""The M4 134 power matrix through :func:`mfm.sweep` (issue 14 item 4), not a test.

    python benchmarks/power_matrix.py [--workers 1 2] [--chunk-size 16] [--n-steps 20000]
                                      [--skip-batch]

10 H_s (0.01–0.06 m) × 12 T_p (0.8–1.8 s) JONSWAP (γ 3.3, seed 1, ω 1–25 rad/s, the sea
states of benchmarks/speed.py), 100 T_p at dt = T_p/200 (20,000 steps) each, ramp 5 T_p, Verlet with the
exact state-space radiation, every 10th step kept. Each way of running it is a fresh child process
(its own compilation, fit and peak memory): one in-process ``simulate_batch`` over the 120 cases;
``mfm.sweep`` in this process in chunks; ``mfm.sweep`` on a ``LocalCluster`` of N single-threaded
worker processes (its start timed apart). Wall times include the radiation fit and compilation.
Peak memory: the child's maximum resident set (and each worker's). The results of every way are
compared with the one-call batch (the acceptance: 1e-12) and the mean PTO power matrix over the
last 80 T_p is printed.

    python benchmarks/power_matrix.py --spectral [--td-file out/td_chunked.nc] [--pilot-tp 0.8 1.2 1.8]

The same matrix through the spectral level (``mfm.sweep(m, seas, level="spectral", dt=, n_steps=,
save_every=10)``: linearised once, RAOs solved once on the union of the seas' frequencies, the
series synthesised on the time domain's saved grid), timed cold (a fresh process: load, linearise,
RAOs, 120 cases) and warm (median of 3), and compared cell by cell with the time-domain matrix
(``mfm.sweep`` in process, Verlet + exact state space; read from ``--td-file`` if it exists, else
run once and written there): the mean power over the same last 80 T_p of the same samples. Then
``mfm.reduce`` (tolerance 0.005, levels spectral, fast, full; its default 40-T_p pilot at T_p/200)
at the largest H_s and the T_p of ``--pilot-tp``: is the linear level justified where the motions
are largest?
"""
import argparse
import json
import os
import resource
import subprocess
import sys
import tempfile
import time
import warnings
from pathlib import Path

import numpy as np
os.environ.setdefault("MFM_COMPILATION_CACHE", "off")  # compile times measured, not loaded from disk (mfm.runner.xla)
os.environ.setdefault("MFM_FIT_CACHE", "off")          # fit times measured, not read from disk (hydro.fitcache)

ROOT = Path(__file__).resolve().parents[1]
TP, HS = np.round(np.linspace(0.8, 1.8, 12), 3), np.round(np.linspace(0.01, 0.06, 10), 3)


def cases():
    import hydro

    seas = [hydro.Jonswap(hs=h, tp=t, gamma=3.3, seed=1, omega_range=(1.0, 25.0))
            for h in HS for t in TP]
    tps = np.array([s.tp for s in seas])
    return seas, tps / 200, 5 * tps


def _maxrss_gb():
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1e6


def _worker_maxrss():
    import resource as r

    return r.getrusage(r.RUSAGE_SELF).ru_maxrss / 1e6


def child(what, n_steps, chunk_size, out):
    warnings.simplefilter("ignore")
    import mfm

    t0 = time.perf_counter()
    m = mfm.load(ROOT / "configs" / "m4_134.toml")
    seas, dts, ramps = cases()
    kw = dict(dt=dts, ramp=ramps, n_steps=n_steps, integrator="verlet",
              radiation="state_space_exact", save_every=10)
    res = {"what": what, "load_s": time.perf_counter() - t0}
    t0 = time.perf_counter()
    if what == "batch":
        ds = mfm.simulate_batch(m, seas, **kw)
    elif what == "chunked":
        ds = mfm.sweep(m, seas, chunk_size=chunk_size, progress={"mininterval": 30}, **kw)
    else:
        import distributed

        n = int(what.split("-")[1])
        cluster = distributed.LocalCluster(n_workers=n, threads_per_worker=1, processes=True,
                                           dashboard_address=None,
                                           env={"OPENBLAS_NUM_THREADS": "1"})
        client = distributed.Client(cluster)
        res["cluster_start_s"] = time.perf_counter() - t0
        t1 = time.perf_counter()
        ds = mfm.sweep(m, seas, chunk_size=chunk_size, client=client,
                       progress={"mininterval": 30}, **kw)
        res["sweep_s"] = time.perf_counter() - t1
        res["worker_maxrss_GB"] = sorted(client.run(_worker_maxrss).values())
        client.close()
        cluster.close()
    res["wall_s"] = time.perf_counter() - t0
    res["maxrss_GB"] = _maxrss_gb()
    res["failed"] = int(ds.failed.sum()) if "failed" in ds else 0
    ds[["pto_power", "q"]].to_netcdf(out)
    print("RESULT " + json.dumps(res), flush=True)


def _timed(fn, repeats=3):
    import statistics

    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - t0)
    return out, statistics.median(times)


def child_spectral(n_steps, out):
    """The matrix through the spectral level in this fresh process: cold (load included), warm."""
    warnings.simplefilter("ignore")
    t0 = time.perf_counter()
    import mfm

    m = mfm.load(ROOT / "configs" / "m4_134.toml")
    seas, dts, _ = cases()
    res = {"what": "spectral", "load_s": time.perf_counter() - t0}
    kw = dict(level="spectral", dt=dts, n_steps=n_steps, save_every=10)
    ds = mfm.sweep(m, seas, **kw)
    res["cold_s"] = time.perf_counter() - t0     # import, load, linearise, RAOs, 120 cases
    res["cold_rao_solve_s"] = float(ds.attrs["rao_solve_s"])
    res["n_frequencies_solved"] = int(ds.attrs["n_frequencies_solved"])
    _, res["warm_s"] = _timed(lambda: mfm.sweep(m, seas, **kw))
    stats, res["warm_stats_s"] = _timed(lambda: mfm.sweep(m, seas, level="spectral"))
    res["warm_rao_solve_s"] = float(stats.attrs["rao_solve_s"])
    res["maxrss_GB"] = _maxrss_gb()
    # the same with the time domain's radiation (the state-space fit, fitted here once)
    t1 = time.perf_counter()
    fit = mfm.sweep(m, seas, radiation="state_space", **kw)
    res["state_space_first_s"] = time.perf_counter() - t1
    xr_ds = ds[["pto_power", "pto_power_mean", "time"]].copy()
    xr_ds["pto_power_fit"] = fit.pto_power
    xr_ds.to_netcdf(out)
    print("RESULT " + json.dumps(res), flush=True)


def child_reduce(tps, out):
    """mfm.reduce at the largest H_s and the given T_p (tolerance 0.005)."""
    warnings.simplefilter("ignore")
    import hydro
    import mfm

    m = mfm.load(ROOT / "configs" / "m4_134.toml")
    angles = [c for c in m.coordinates if c.endswith("angle")]
    rows = []
    for tp in tps:
        sea = hydro.Jonswap(hs=float(HS[-1]), tp=float(tp), gamma=3.3, seed=1,
                            omega_range=(1.0, 25.0))
        t0 = time.perf_counter()
        r = mfm.reduce(m, sea, tolerance=0.005, coordinates=angles,
                       levels=("spectral", "fast", "full"), timing=False)
        rows.append({"tp": float(tp), "level": r.level, "reason": r.reason,
                     "wall_s": time.perf_counter() - t0,
                     "errors": {lv: max(e.values()) for lv, e in r.errors.items()},
                     "spectral": r.errors["spectral"]})
        print(f"# reduce Tp {tp}: {rows[-1]}", file=sys.stderr, flush=True)
    print("RESULT " + json.dumps(rows), flush=True)


def run(what, n_steps, chunk_size, tmp, extra=()):
    out = os.path.join(tmp, f"{what}.nc")
    env = dict(os.environ, PYTHONPATH=str(ROOT), OPENBLAS_NUM_THREADS="1")
    cmd = [sys.executable, str(Path(__file__).resolve()), "--child", what, "--n-steps",
           str(n_steps), "--chunk-size", str(chunk_size), "--out", out, *extra]
    p = subprocess.run(cmd, cwd=ROOT, env=env, capture_output=True, text=True)
    lines = [ln for ln in p.stdout.splitlines() if ln.startswith("RESULT ")]
    if p.returncode or not lines:
        raise RuntimeError(f"{what} failed:\n{p.stdout[-2000:]}\n{p.stderr[-4000:]}")
    return json.loads(lines[-1][7:]), out


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--child")
    ap.add_argument("--out")
    ap.add_argument("--n-steps", type=int, default=20_000)
    ap.add_argument("--chunk-size", type=int, default=16)
    ap.add_argument("--workers", type=int, nargs="*", default=[1, 2])
    ap.add_argument("--skip-batch", action="store_true")
    ap.add_argument("--spectral", action="store_true")
    ap.add_argument("--td-file", default=str(ROOT / "out" / "td_chunked.nc"))
    ap.add_argument("--pilot-tp", type=float, nargs="*", default=[0.8, 1.255, 1.8])
    a = ap.parse_args()
    if a.child == "spectral":
        return child_spectral(a.n_steps, a.out)
    if a.child == "reduce":
        return child_reduce(a.pilot_tp, a.out)
    if a.child:
        return child(a.child, a.n_steps, a.chunk_size, a.out)
    if a.spectral:
        return main_spectral(a)
    import xarray as xr

    ways = ([] if a.skip_batch else ["batch"]) + ["chunked"] + [f"cluster-{n}" for n in a.workers]
    n_cases = len(HS) * len(TP)
    rows, files = [], {}
    with tempfile.TemporaryDirectory() as tmp:
        for w in ways:
            r, files[w] = run(w, a.n_steps, a.chunk_size, tmp)
            rows.append(r)
            print(f"# {w}: {json.dumps(r)}", file=sys.stderr, flush=True)
        ref_way = ways[0]
        ref = xr.open_dataset(files[ref_way]).load()
        diffs = {}
        for w in ways[1:]:
            ds = xr.open_dataset(files[w]).load()
            diffs[w] = max(float(np.abs(ds[v] - ref[v]).max() / np.abs(ref[v]).max())
                           for v in ("q", "pto_power"))
        keep = a.n_steps // 10 // 5
        P = ref.pto_power.sum("pto").isel(step=slice(keep, None)).mean("step").values
    print(f"**M4 134 power matrix**: {len(HS)} H_s × {len(TP)} T_p = {n_cases} cases × "
          f"{a.n_steps:,} steps (dt = T_p/200), Verlet + exact state space, chunks of ≤ "
          f"{a.chunk_size}; wall time including fit and compilation (`python "
          f"benchmarks/power_matrix.py{' --skip-batch' if a.skip_batch else ''}"
          f" --workers {' '.join(map(str, a.workers))}`, {time.strftime('%Y-%m-%d')}; "
          f"load average {os.getloadavg()[0]:.1f} at the end):\n")
    print("| way | wall | of which cluster start | cases/s | case-steps/s | × first row "
          "| peak memory | max rel. diff vs " + ref_way + " |")
    print("|---|---|---|---|---|---|---|---|")
    base = rows[0]["wall_s"]
    for r in rows:
        mem = f"{r['maxrss_GB']:.1f} GB"
        if "worker_maxrss_GB" in r:
            mem += " + workers " + ", ".join(f"{x:.1f}" for x in r["worker_maxrss_GB"]) + " GB"
        d = diffs.get(r["what"])
        print(f"| {r['what']} | {r['wall_s']:.1f} s | "
              f"{r.get('cluster_start_s', 0.0):.1f} s | {n_cases / r['wall_s']:.2f} | "
              f"{n_cases * a.n_steps / r['wall_s']:.3g} | {base / r['wall_s']:.2f} | {mem} | "
              f"{'—' if d is None else f'{d:.1e}'} |")
    print(f"\nMean PTO power (W) over the last 80 T_p, rows H_s {HS.tolist()} m, columns T_p "
          f"{TP.tolist()} s:\n")
    print("| H_s \\ T_p | " + " | ".join(f"{t:g}" for t in TP) + " |")
    print("|---|" + "---|" * len(TP))
    Pm = P.reshape(len(HS), len(TP))
    for h, row in zip(HS, Pm):
        print(f"| {h:g} | " + " | ".join(f"{p:.3g}" for p in row) + " |")


def _matrix(ds, var, n_steps):
    """Mean total PTO power over the last 80 T_p of the saved samples (as the time domain's)."""
    keep = n_steps // 10 // 5
    return ds[var].sum("pto").isel(step=slice(keep, None)).mean("step").values.reshape(
        len(HS), len(TP))


def _table(M, fmt):
    lines = ["| H_s \\ T_p | " + " | ".join(f"{t:g}" for t in TP) + " |",
             "|---|" + "---|" * len(TP)]
    lines += [f"| {h:g} | " + " | ".join(fmt(p) for p in row) + " |" for h, row in zip(HS, M)]
    return "\n".join(lines)


def main_spectral(a):
    import xarray as xr

    td_file = Path(a.td_file)
    with tempfile.TemporaryDirectory() as tmp:
        if td_file.exists():
            td_run = None
        else:
            td_file.parent.mkdir(parents=True, exist_ok=True)
            td_run, _ = run("chunked", a.n_steps, a.chunk_size, tmp)
            os.replace(os.path.join(tmp, "chunked.nc"), td_file)
        sp_run, sp_file = run("spectral", a.n_steps, a.chunk_size, tmp)
        with xr.open_dataset(td_file) as f:
            P_td = _matrix(f.load(), "pto_power", a.n_steps)
        with xr.open_dataset(sp_file) as f:
            sp = f.load()
        P_sp = _matrix(sp, "pto_power", a.n_steps)
        P_fit = _matrix(sp, "pto_power_fit", a.n_steps)
        P_exp = sp.pto_power_mean.sum("pto").values.reshape(len(HS), len(TP))
        pilot = run("reduce", a.n_steps, a.chunk_size, tmp,
                    ["--pilot-tp", *map(str, a.pilot_tp)])[0] if a.pilot_tp else []
    err = P_sp / P_td - 1
    err_fit = P_fit / P_td - 1
    err_exp = P_exp / P_td - 1
    worst = np.unravel_index(np.argmax(np.abs(err)), err.shape)
    print(f"**M4 134 power matrix through the spectral level** (`python benchmarks/power_matrix.py "
          f"--spectral`, {time.strftime('%Y-%m-%d %H:%M')}; load average "
          f"{os.getloadavg()[0]:.1f} at the end): {len(HS)} H_s × {len(TP)} T_p, "
          f"`mfm.sweep(m, seas, level=\"spectral\", dt=T_p/200, n_steps={a.n_steps}, "
          f"save_every=10)`, {sp_run['n_frequencies_solved']} frequencies solved once for all "
          f"{len(HS) * len(TP)} cases.\n")
    print(f"- one call cold (fresh process: import, load, linearise, RAOs, 120 cases with their "
          f"series): {sp_run['cold_s']:.1f} s (of which load {sp_run['load_s']:.1f} s, RAO solve "
          f"{sp_run['cold_rao_solve_s']:.2f} s); warm {sp_run['warm_s']:.2f} s (median of 3); "
          f"statistics only warm {sp_run['warm_stats_s']:.2f} s; with the state-space fit "
          f"(radiation=\"state_space\", fit included) {sp_run['state_space_first_s']:.1f} s; peak "
          f"memory {sp_run['maxrss_GB']:.1f} GB.")
    if td_run is not None:
        print(f"- the time-domain matrix (`mfm.sweep` in process, Verlet + exact state space, "
              f"20,000 steps per case) in this run: {td_run['wall_s']:.1f} s, peak "
              f"{td_run['maxrss_GB']:.1f} GB.")
    else:
        print(f"- the time-domain matrix read from {td_file.name} (run earlier by this script).")
    print(f"- mean power over the last 80 T_p of the same samples, spectral vs time domain: max "
          f"|relative error| over the 120 cells {np.abs(err).max():.2e} (at H_s "
          f"{HS[worst[0]]:g} m, T_p {TP[worst[1]]:g} s), median {np.median(np.abs(err)):.2e}; "
          f"cells over 0.5 %: {int((np.abs(err) > 0.005).sum())}. With the time domain's "
          f"state-space fit: max {np.abs(err_fit).max():.2e}. The expected mean power "
          f"Σ a² ½ c ω² |x̂|² against the 80-T_p window: max {np.abs(err_exp).max():.2e} (the "
          f"window's sampling of the record, not the model).")
    over = [f"(H_s {HS[i]:g}, T_p {TP[j]:g}) {err[i, j]:+.2e}"
            for i, j in np.argwhere(np.abs(err) > 0.005)]
    print(f"- cells over 0.5 % (database radiation): {'; '.join(over) if over else 'none'}.\n")
    print("Relative error of the spectral level's mean power (database radiation) against the "
          "time domain, per cell:\n")
    print(_table(err, lambda e: f"{e:+.1e}"))
    print("\nThe same with the state-space fit in the spectral level:\n")
    print(_table(err_fit, lambda e: f"{e:+.1e}"))
    if pilot:
        print(f"\n`mfm.reduce(m, sea, tolerance=0.005, coordinates=<the hinge angles>, "
              f"levels=(\"spectral\", \"fast\", \"full\"), timing=False)` at H_s {HS[-1]:g} m "
              "(40-T_p pilot at T_p/200 against RK4, radiation auto):\n")
        print("| T_p | level chosen | spectral: largest error | fast: largest error | wall |")
        print("|---|---|---|---|---|")
        for r in pilot:
            print(f"| {r['tp']:g} s | {r['level']} | {r['errors']['spectral']:.2e} | "
                  f"{r['errors'].get('fast', float('nan')):.2e} | {r['wall_s']:.0f} s |")
        for r in pilot:
            print(f"\nT_p {r['tp']:g} s: {r['reason']}; spectral errors "
                  + ", ".join(f"{k} {v:.2e}" for k, v in r["spectral"].items()))


if __name__ == "__main__":
    main()
