"""Stability where methods fail: the stability map of the integrators against the added-mass
ratio, and the RM3 long-run finding explained by Floquet multipliers (docs/stability.md).

    PYTHONPATH=. python tools/stability_study.py map       # predicted and measured map (≈ 5 min)
    PYTHONPATH=. python tools/stability_study.py runs      # RM3 4000 s runs (≈ 1 min each)
    PYTHONPATH=. python tools/stability_study.py floquet   # RM3 multipliers and variants (1–4 min each)
    PYTHONPATH=. python tools/stability_study.py figures   # the PNGs from the stored numbers
    PYTHONPATH=. python tools/stability_study.py table     # the Floquet variants as markdown
    PYTHONPATH=. python tools/stability_study.py longrun   # 3 h RM3, 10⁶ steps M4 134 (≈ 30 min)

Numbers go to notebooks/figures/stability/*.json, figures to notebooks/figures/stability/*.png.
"""
from __future__ import annotations

import copy
import dataclasses
import importlib
import json
import math
import sys
import time
import warnings
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
OUT = ROOT / "notebooks" / "figures" / "stability"

RATIOS = [0.0, 0.25, 0.5, 0.75, 0.9, 1.0, 1.5, 2.0, 3.0, 4.0, 6.0]
# (label, integrator name or constructor, added-mass placement)
SCHEMES = [("rk4, A∞ in M*", "rk4", "lhs"),
           ("semi-implicit Euler, A∞ in M*", "semi_implicit", "lhs"),
           ("verlet, A∞ in M*", "verlet", "lhs"),
           ("beeman, A∞ in M*", "beeman", "lhs"),
           ("newmark, A∞ in M*", "newmark", "lhs"),
           ("beeman, A∞ on the rhs, corrector (tol 1 %)", "beeman", "rhs"),
           ("beeman, A∞ on the rhs, no corrector", "beeman0", "rhs")]

RM3_SEA = dict(height=2.5, period=8.0)
RM3_RAMP = 20.0          # Floquet: the orbit after the ramp, whatever its length
RUN_RAMP = 40.0          # the README's RM3 case
# the exponential phase of a run: periods whose deviation from 8 s periodicity is between these
# (above the start-up transient's decay, below the nonlinear saturation at 0.43 rad)
LINEAR_PHASE = (2e-3, 5e-2)
T_START = 120.0


def _integrator(name):
    import mfm

    return mfm.integrators.Beeman(max_iter=0) if name == "beeman0" else name


def stability_map(n_steps=2000):
    """Largest stable dt/T_min per scheme and A∞/m, predicted (spectral radius of the engine's
    step on the linear heave equation) and measured (rollouts of the heave model)."""
    from mfm.studies import stability as st

    model, p = st.heave_model(0.02)
    m, K, c = p["m"], p["K"], p["c"]
    rows = []
    for label, name, am in SCHEMES:
        integ = _integrator(name)
        for r in RATIOS:
            T_min = 2 * math.pi * math.sqrt((m + r * m) / K)
            t0 = time.time()
            pred = st.largest_stable_dt(integ, m, c, K, A_inf=r * m, added_mass=am,
                                        dt_max=2 * T_min)
            meas = st.measured_stable_dt(model, r, integrator=integ, added_mass=am,
                                         dt_lo=1e-3 * T_min, dt_hi=2 * T_min, n_steps=n_steps,
                                         iterations=12)
            rows.append(dict(scheme=label, integrator=name, added_mass=am, ratio=r, T_min=T_min,
                             predicted=pred / T_min, measured=meas / T_min))
            print(f"{label:45s} A∞/m {r:4.2f}: predicted {pred / T_min:.4f}, measured "
                  f"{meas / T_min:.4f} T_min ({time.time() - t0:.1f} s)", flush=True)
    OUT.mkdir(parents=True, exist_ok=True)
    (OUT / "map.json").write_text(json.dumps(dict(
        heave_model=p, n_steps=n_steps, growth="|q| > 1e3 × 1 cm in the last quarter",
        rows=rows), indent=1, default=float))


def rm3(drag=False):
    import mfm

    model = mfm.load(ROOT / "configs" / "rm3.toml")
    if drag:
        # C_D = 1 [A]: spar column 6 m × 35 m draft and the 30 m plate; float 20 m × 5 m and its
        # 20 m disc (WEC-Sim RM3 dimensions, docs/GEOMETRY.md §5)
        spec = copy.copy(model.hydro)
        areas = {"float": [100.0, 100.0, 314.2], "spar": [210.0, 210.0, 706.9]}
        spec.drag = 0.5 * spec.rho * np.asarray([areas[n] for n in spec.config_names], dtype=float)
        model = dataclasses.replace(model, hydro=spec)
    return model


def mooring(model, k):
    """A horizontal linear spring of k N/m at the spar's still-water-line point."""
    from mfm.loads.body_matrix import LinearBodyMatrix

    return LinearBodyMatrix.create(model, "spar", point=[0.0, 0.0, 0.0],
                                   stiffness=[k, 0, 0, 0, 0, 0], name="mooring")


def rm3_runs(which=None):
    import hydro
    import mfm
    from mfm.studies import floquet as fq

    model = rm3()
    sea = hydro.Regular(**RM3_SEA)
    path = OUT / "rm3_runs.json"
    out = json.loads(path.read_text()) if path.exists() else {}
    for integ, rad, dt in [("verlet", "state_space_exact", 0.1), ("rk4", "state_space_exact", 0.1),
                           ("verlet", "state_space_exact", 0.05), ("rk4", "state_space", 0.1),
                           ("rk4", "convolution", 0.1)]:
        if which and f"{integ} {rad} dt {dt}" not in which:
            continue
        t0 = time.time()
        ds = mfm.simulate(model, sea, duration=4000.0, dt=dt, integrator=integ, radiation=rad,
                          ramp=RUN_RAMP, save_every=int(round(0.2 / dt)))
        t = ds.time.values
        pitch = ds.q.sel(coordinate="spar.pitch").values
        power = ds.pto_power.values.reshape(len(t), -1)[:, 0]
        # the envelope of the deviation from 8 s periodicity, whole run; σ fitted on its
        # exponential phase (LINEAR_PHASE), from the first period past its lower bound to the
        # first past its upper one
        _, mids, peaks = fq.envelope_growth_rate(t, pitch, 8.0, 0.0, 3990.0)
        a = mids[np.argmax((peaks > LINEAR_PHASE[0]) & (mids > 2 * RUN_RAMP))] - 4.0
        b = mids[np.argmax((peaks > LINEAR_PHASE[1]) & (mids > a))] + 4.0
        sigma, _, _ = fq.envelope_growth_rate(t, pitch, 8.0, a, b)
        key = f"{integ} {rad} dt {dt}"
        win = lambda a, b: (t >= a) & (t < b)  # noqa: E731
        out[key] = dict(sigma=sigma, fit_window=[float(a), float(b)], wall_s=time.time() - t0,
                        pitch_max_100_140=float(np.abs(pitch[win(100, 140)]).max()),
                        pitch_max_3000_4000=float(np.abs(pitch[win(3000, 4000)]).max()),
                        power_kw_100_140=float(power[win(100, 140)].mean() / 1e3),
                        power_kw_3000_4000=float(power[win(3000, 4000)].mean() / 1e3),
                        # the first 1000 s at 1 s for the figure
                        t=t[t <= 1000.0][::5].tolist(), pitch=pitch[t <= 1000.0][::5].tolist(),
                        env_t=mids.tolist(), env=peaks.tolist())
        print(key, {k: v for k, v in out[key].items() if not isinstance(v, list)}, flush=True)
        OUT.mkdir(parents=True, exist_ok=True)
        path.write_text(json.dumps(out))


def rm3_floquet(which=None):
    import hydro
    from mfm.studies import floquet as fq

    base = rm3()
    cases = {
        "verlet exact dt 0.1": dict(),
        "verlet exact dt 0.05": dict(dt=0.05),
        "rk4 exact dt 0.1": dict(integrator="rk4"),
        "rk4 state_space dt 0.1": dict(integrator="rk4", radiation="state_space"),
        "rk4 exact dt 0.05": dict(integrator="rk4", dt=0.05),
        "drag C_D 1": dict(model=rm3(drag=True)),
        "mooring 3e4 N/m": dict(loads=[mooring(base, 3e4)]),
        "mooring 3e5 N/m": dict(loads=[mooring(base, 3e5)]),
        "PTO 0.6e6 N s/m": dict(model=base.replace(damping=base.damping.at[3].set(0.6e6))),
        "PTO 2.4e6 N s/m": dict(model=base.replace(damping=base.damping.at[3].set(2.4e6))),
    }
    for T in (6.0, 7.0, 7.5, 7.6, 7.7, 7.8, 7.9, 8.1, 8.2, 8.3, 8.5, 9.0, 10.0):
        cases[f"T {T:g} s"] = dict(period=T)
    for H in (0.5, 1.0, 1.5, 1.75, 2.0, 2.25, 3.0):
        cases[f"H {H:g} m"] = dict(height=H)
    OUT.mkdir(parents=True, exist_ok=True)
    path = OUT / "floquet.json"
    out = json.loads(path.read_text()) if path.exists() else {}
    for name, kw in cases.items():
        if which and name not in which:
            continue
        kw = dict(kw)
        T = kw.pop("period", RM3_SEA["period"])
        H = kw.pop("height", RM3_SEA["height"])
        model = kw.pop("model", base)
        dt = kw.pop("dt", 0.1)
        t0 = time.time()
        r = fq.floquet(model, hydro.Regular(height=H, period=T), period=T, dt=dt,
                       t_start=T_START, ramp=RM3_RAMP, **{"integrator": "verlet",
                                                          "radiation": "state_space_exact", **kw})
        mu = r.multipliers
        q_idx = [i for i, nm in enumerate(r.state_names) if nm.startswith("q[")]
        v = r.modes[:, 0]
        out[name] = dict(period=T, height=H, dt=dt, multipliers_re=mu.real[:12].tolist(),
                         multipliers_im=mu.imag[:12].tolist(), all_re=mu.real.tolist(),
                         all_im=mu.imag.tolist(), sigma=float(r.growth_rates[0]),
                         residual=list(r.residual), n_x=len(r.x), wall_s=time.time() - t0,
                         mode_q={r.state_names[i]: abs(complex(v[i])) for i in q_idx})
        print(f"{name:28s} μ₁ = {mu[0]:.5f} (|μ| {abs(mu[0]):.5f}), "
              f"σ = {r.growth_rates[0]:+.5f} /s,"
              f" μ₂ = {mu[1]:.5f}, residual {r.residual[0]:.2g} → {r.residual[1]:.2g}, "
              f"{time.time() - t0:.0f} s", flush=True)
        path.write_text(json.dumps(out, indent=1))


# long runs (issue 14 item 2): irregular seas (RM3's regular H 2.5 m T 8 s wave has a genuine
# parametric resonance, section 2 of docs/stability.md); "default" is simulate's defaults (RK4,
# radiation auto), "fast" the fidelity ladder's fast level
LONG_SETTINGS = {"default": {}, "fast": {"integrator": "verlet", "radiation": "state_space_exact"}}


def _long_cases():
    import hydro

    return {
        # 3 h full scale after a 200 s settle (ramp 40 s), dt = Tp/80, kept every 0.5 s; Tp 8 s puts
        # the peak on the 7.8 s parametric resonance of the 15.6 s pitch–surge mode
        "rm3": dict(config="rm3.toml", sea=hydro.Jonswap(hs=2.5, tp=8.0, gamma=3.3, seed=1),
                    dt=0.1, n_steps=110_000, save_every=5, ramp=40.0, settle=200.0, windows=3),
        # 10⁶ steps at Tp/200 in the sea of benchmarks/speed.py (model scale: 6000 s), kept every
        # 20 steps, five 1176 s windows after 120 s
        "m4_134": dict(config="m4_134.toml",
                       sea=hydro.Jonswap(hs=0.04, tp=1.2, gamma=3.3, seed=1, omega_range=(1.0, 25.0)),
                       dt=1.2 / 200, n_steps=1_000_000, save_every=20, ramp=6.0, settle=120.0,
                       windows=5),
    }


def stationarity(t, y, start, windows, blocks=12):
    """Each of ``windows`` equal windows of y(t) after ``start``: its mean and standard deviation
    with their sampling errors by batch means (``blocks`` blocks per window: the spread of the
    block means (stds) over √blocks), and the largest z = |a_i − a_j| / √(se_i² + se_j²) over the
    pairs of windows for the mean and for the std (≈ N(0, 1) per pair when y is stationary and the
    blocks are longer than its correlation time)."""
    sel = t >= start
    y = np.asarray(y)[sel]
    n = len(y) // (windows * blocks) * windows * blocks
    B = y[:n].reshape(windows, blocks, -1)
    mean, std = B.mean(axis=(1, 2)), B.reshape(windows, -1).std(axis=1)
    se_mean = B.mean(axis=2).std(axis=1, ddof=1) / math.sqrt(blocks)
    se_std = B.std(axis=2).std(axis=1, ddof=1) / math.sqrt(blocks)

    def zmax(a, se):
        return max((abs(a[i] - a[j]) / max(math.hypot(se[i], se[j]), 1e-300)
                    for i in range(windows) for j in range(i + 1, windows)), default=0.0)

    return dict(mean=mean.tolist(), std=std.tolist(), se_mean=se_mean.tolist(),
                se_std=se_std.tolist(), z_mean=zmax(mean, se_mean), z_std=zmax(std, se_std))


def longrun(which=None):
    """Long runs bounded: RM3 3 h in JONSWAP Hs 2.5 m Tp 8 s and M4 134 10⁶ steps, default and fast
    settings; per window the mean and std of every coordinate, of the free ones' velocity and of
    the PTO power, with the batch-means z of their differences (:func:`stationarity`)."""
    import mfm

    path = OUT / "longrun.json"
    out = json.loads(path.read_text()) if path.exists() else {}
    for name, case in _long_cases().items():
        model = mfm.load(ROOT / "configs" / case["config"])
        free = importlib.import_module("mfm.frequency.rest").no_restoring(model)
        for setting, options in LONG_SETTINGS.items():
            key = f"{name} {setting}"
            if which and key not in which:
                continue
            t0 = time.time()
            ds = mfm.simulate(model, case["sea"], duration=case["n_steps"] * case["dt"],
                              dt=case["dt"], ramp=case["ramp"], save_every=case["save_every"],
                              progress={"mininterval": 30.0}, **options)
            wall = time.time() - t0
            t = ds.time.values
            finite = bool(np.isfinite(ds.q.values).all() and np.isfinite(ds.qd.values).all())
            series = {c: ds.q.sel(coordinate=c).values for c in model.coordinates}
            series.update({f"{c} velocity": ds.qd.sel(coordinate=c).values for c in free})
            power = ds.pto_power.values.reshape(len(t), -1).sum(axis=1)
            series["pto_power"] = power
            stats = {k: stationarity(t, v, case["settle"], case["windows"]) for k, v in series.items()}
            # 60 s (RM3) or 12 s (M4) block statistics for the figure
            blk = int(round((60.0 if name == "rm3" else 12.0) / (t[1] - t[0])))
            nb = len(t) // blk
            fig = {k: dict(mean=v[:nb * blk].reshape(nb, blk).mean(1).tolist(),
                           std=v[:nb * blk].reshape(nb, blk).std(1).tolist())
                   for k, v in series.items()}
            out[key] = dict(wall_s=wall, n_steps=case["n_steps"], dt=case["dt"],
                            duration=case["n_steps"] * case["dt"], sea=repr(case["sea"]),
                            settle=case["settle"], windows=case["windows"], finite=finite,
                            free=free, radiation=ds.attrs.get("radiation", ""),
                            integrator=ds.attrs.get("integrator", ""), stats=stats,
                            max_abs={k: float(np.abs(v).max()) for k, v in series.items()},
                            block_t=(t[:nb * blk].reshape(nb, blk).mean(1)).tolist(), blocks=fig)
            print(key, f"wall {wall:.0f} s, finite {finite}, radiation {out[key]['radiation']}",
                  flush=True)
            for k, v in stats.items():
                print(f"  {k:24s} mean {np.round(v['mean'], 5)} std {np.round(v['std'], 5)} "
                      f"z_mean {v['z_mean']:.2f} z_std {v['z_std']:.2f}", flush=True)
            OUT.mkdir(parents=True, exist_ok=True)
            path.write_text(json.dumps(out))
            del ds


def longrun_figure(plt, data):
    keys = [k for k in ("rm3 default", "rm3 fast", "m4_134 default", "m4_134 fast") if k in data]
    models = sorted({k.split()[0] for k in keys}, key=lambda m: m != "rm3")
    fig, axes = plt.subplots(len(models), 2, figsize=(11, 3.4 * len(models)), squeeze=False)
    key_coord = {"rm3": "spar.pitch", "m4_134": "float3.angle"}
    for r, mname in enumerate(models):
        for setting, style in (("default", "-"), ("fast", "--")):
            d = data.get(f"{mname} {setting}")
            if d is None:
                continue
            t = np.asarray(d["block_t"]) / (3600.0 if mname == "rm3" else 1.0)
            for c, (what, label) in enumerate(((key_coord[mname], "std"), ("pto_power", "mean"))):
                y = np.asarray(d["blocks"][what][label])
                ax = axes[r, c]
                ax.plot(t, y, style, lw=0.8, label=f"{setting} ({d['integrator']}, {d['radiation']}), "
                        f"{d['wall_s'] / 60:.1f} min")
                # the window statistics of the study
                st = d["stats"][what]
                edges = np.linspace(d["settle"], d["duration"], d["windows"] + 1) / (
                    3600.0 if mname == "rm3" else 1.0)
                for i in range(d["windows"]):
                    ax.hlines(st[label][i], edges[i], edges[i + 1], colors="k", lw=1.5)
                ax.set_title(f"{mname}: {what} {'std per block' if label == 'std' else 'mean per block'}"
                             f" (z {st['z_' + label]:.2f} across windows)", fontsize=9)
                ax.set_xlabel("t (h)" if mname == "rm3" else "t (s, model scale)")
        for ax in axes[r]:
            ax.legend(fontsize=7)
    fig.suptitle("Long runs bounded: block statistics (thin) and window statistics (black)", fontsize=10)
    fig.tight_layout()
    fig.savefig(OUT / "longrun.png", dpi=110)
    plt.close(fig)


def figures():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    if (OUT / "map.json").exists():
        map_figure(plt, json.loads((OUT / "map.json").read_text()))
    if (OUT / "longrun.json").exists():
        longrun_figure(plt, json.loads((OUT / "longrun.json").read_text()))
    if (OUT / "rm3_runs.json").exists() and (OUT / "floquet.json").exists():
        floquet_figure(plt, json.loads((OUT / "rm3_runs.json").read_text()),
                       json.loads((OUT / "floquet.json").read_text()))


def map_figure(plt, data):
    rows = data["rows"]
    fig, axes = plt.subplots(1, 2, figsize=(13, 6.5), sharey=True)
    colors = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    ymax = 0.6
    for k, (label, _, am) in enumerate(SCHEMES):
        ax = axes[0 if am == "lhs" else 1]
        rr = [r for r in rows if r["scheme"] == label]
        x = [r["ratio"] for r in rr]
        pred = [min(r["predicted"], ymax) for r in rr]
        meas = [min(r["measured"], ymax) for r in rr]
        ax.plot(x, pred, "-", color=colors[k], label=f"{label}: predicted (ρ(G) = 1)")
        ax.plot(x, meas, "o", mfc="none", color=colors[k], label=f"{label}: measured (runs)")
    for ax, title in zip(axes, ("A∞ in M* (mfm)", "A∞ q̈ on the right-hand side (seed 001)")):
        ax.set_xlabel("added-mass ratio A∞/m")
        ax.set_title(title)
        ax.legend(fontsize=7, loc="upper center", bbox_to_anchor=(0.5, -0.14), ncol=2)
        ax.grid(alpha=0.3)
    axes[0].set_ylabel("largest stable dt / T_min  (T_min = 2π √((m + A∞)/K))")
    axes[0].axhline(ymax, color="0.8", lw=0.8)
    axes[0].text(0.02, ymax * 0.97, "no limit up to 2 T_min (newmark), drawn at 0.6", va="top",
                 fontsize=8, color="0.4")
    fig.suptitle("Stability map: heave of a floating hemisphere, 2 % damping; below each line is "
                 "stable")
    fig.tight_layout()
    fig.savefig(OUT / "stability_map.png", dpi=130)
    plt.close(fig)



def leading(v):
    """(μ, σ) of the largest multiplier other than the free surge's μ = 1 (|μ − 1| > 1e-3)."""
    mu = np.asarray(v["all_re"]) + 1j * np.asarray(v["all_im"])
    mu = mu[np.abs(mu - 1) > 1e-3]
    m = mu[np.argmax(np.abs(mu))]
    return m, float(np.log(abs(m)) / v["period"])


def table():
    """The variants of docs/stability.md as a markdown table."""
    fq = json.loads((OUT / "floquet.json").read_text())
    order = ["verlet exact dt 0.1", "drag C_D 1", "mooring 3e4 N/m", "mooring 3e5 N/m",
             "PTO 0.6e6 N s/m", "PTO 2.4e6 N s/m"]
    order += sorted((k for k in fq if k.startswith("T ")), key=lambda k: fq[k]["period"])
    order += sorted((k for k in fq if k.startswith("H ")), key=lambda k: fq[k]["height"])
    print("| change | leading multiplier but the free surge's μ = 1 | \\|μ\\| | σ (s⁻¹) | stable |")
    print("|---|---|---|---|---|")
    for k in order:
        m, sg = leading(fq[k])
        mu = f"{m.real:+.5f}"
        if abs(m.imag) > 1e-9:
            mu += f" {'+' if m.imag >= 0 else '−'} {abs(m.imag):.5f}i"
        name = "none (H 2.5 m, T 8 s)" if k == "verlet exact dt 0.1" else k
        print(f"| {name} | {mu.replace('-', '−')} | {abs(m):.5f} | {sg:+.5f} | "
              f"{'yes' if abs(m) <= 1 else '**no**'} |".replace("+-", "−").replace("| -", "| −"))


def floquet_figure(plt, runs, fq):
    fig, axes = plt.subplots(1, 3, figsize=(16, 4.8))
    ax = axes[0]
    key = "verlet state_space_exact dt 0.1"
    r = runs[key]
    ax.plot(r["t"], np.abs(r["pitch"]), lw=0.4, color="0.6", label="|pitch| (rad)")
    ax.semilogy(r["env_t"], r["env"], ".", ms=3, label="|θ(t + 8 s) − θ(t)| per period (run)")
    sig = fq["verlet exact dt 0.1"]["sigma"]
    a, b = r["fit_window"]
    e, te = np.asarray(r["env"]), np.asarray(r["env_t"])
    i0 = int(np.argmin(abs(te - 0.5 * (a + b))))
    t_fit = np.asarray([a - 150.0, b + 50.0])
    ax.semilogy(t_fit, e[i0] * np.exp(sig * (t_fit - te[i0])), "k--",
                label=f"Floquet: σ = ln|μ₁|/T = {sig:.5f} /s")
    ax.axvspan(a, b, color="C2", alpha=0.1, label=f"fit window, σ = {r['sigma']:.5f} /s")
    ax.set_yscale("log")
    ax.set_xlim(0, 1000)
    ax.set_ylim(1e-4, 2)
    ax.set_xlabel("t (s)")
    ax.set_title("RM3, H 2.5 m, T 8 s, dt 0.1 s (verlet, exact state space)")
    ax.legend(fontsize=7)
    ax = axes[1]
    th = np.linspace(0, 2 * np.pi, 400)
    ax.plot(np.cos(th), np.sin(th), color="0.7", lw=0.8)
    for name, mk in (("verlet exact dt 0.1", "o"), ("rk4 exact dt 0.05", "x"),
                     ("drag C_D 1", "s"), ("T 10 s", "^")):
        if name in fq:
            ax.plot(fq[name]["all_re"], fq[name]["all_im"], mk, mfc="none", ms=5, label=name)
    ax.set_aspect("equal")
    ax.set_xlim(-1.3, 1.3)
    ax.set_ylim(-1.1, 1.1)
    ax.set_title("Floquet multipliers μ (unit circle)")
    ax.legend(fontsize=7)
    ax = axes[2]
    Ts = sorted((v["period"], leading(v)[1]) for k, v in fq.items() if k.startswith("T ")
                or k == "verlet exact dt 0.1")
    ax.plot([a for a, _ in Ts], [b for _, b in Ts], "o-", label="wave period (H 2.5 m)")
    ax.axhline(0, color="0.5", lw=0.8)
    ax.set_xlabel("wave period T (s)")
    ax.set_ylabel("σ = ln|μ|/T of the leading multiplier but surge's 1 (1/s)")
    ax2 = ax.twiny()
    Hs = sorted((v["height"], leading(v)[1]) for k, v in fq.items() if k.startswith("H ")
                or k == "verlet exact dt 0.1")
    ax2.plot([a for a, _ in Hs], [b for _, b in Hs], "s--", color="C1", label="wave height (T 8 s)")
    ax2.set_xlabel("wave height H (m)", color="C1")
    ax.legend(fontsize=7, loc="upper left")
    ax2.legend(fontsize=7, loc="upper right")
    ax.set_title("growth rate against the wave")
    fig.tight_layout()
    fig.savefig(OUT / "rm3_floquet.png", dpi=130)
    plt.close(fig)


if __name__ == "__main__":
    warnings.simplefilter("ignore")
    what = sys.argv[1] if len(sys.argv) > 1 else "figures"
    {"map": stability_map, "runs": lambda: rm3_runs(sys.argv[2:] or None),
     "floquet": lambda: rm3_floquet(sys.argv[2:] or None), "figures": figures,
     "table": table, "longrun": lambda: longrun(sys.argv[2:] or None)}[what]()
