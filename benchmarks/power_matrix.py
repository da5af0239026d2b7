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


def run(what, n_steps, chunk_size, tmp):
    out = os.path.join(tmp, f"{what}.nc")
    env = dict(os.environ, PYTHONPATH=str(ROOT), OPENBLAS_NUM_THREADS="1")
    cmd = [sys.executable, str(Path(__file__).resolve()), "--child", what, "--n-steps",
           str(n_steps), "--chunk-size", str(chunk_size), "--out", out]
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
    a = ap.parse_args()
    if a.child:
        return child(a.child, a.n_steps, a.chunk_size, a.out)
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


if __name__ == "__main__":
    main()
