"""Plots of a float tree and of results (matplotlib; imported lazily by the CLI)."""
from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from ..mechanics.model import Model


def plot_layout(model: "Model", q=None, *, ax=None, title=None):
    """Plan (x–y) and side (x–z) views of a tree at configuration q (default q = 0): CoMs sized by
    mass, links from each parent CoM through the joint point to the child CoM, joint axes as arrows.
    Returns the matplotlib figure."""
    import matplotlib.pyplot as plt

    from ..mechanics.kinematics import kinematics

    q = np.zeros(model.n_coordinates) if q is None else np.asarray(q, dtype=float)
    kin = kinematics(model, q)
    x = np.asarray(kin.E[:, :3, 3])
    pj = np.asarray(kin.joint_frame[:, :3, 3])
    Rj = np.asarray(kin.joint_frame[:, :3, :3])
    if ax is None:
        fig, axes = plt.subplots(1, 2, figsize=(11, 4.5))
    else:
        axes = ax
        fig = axes[0].figure
    mass = np.asarray(model.mass)
    sizes = 30 + 300 * mass / mass.max()
    span = max(np.ptp(x[:, 0]), np.ptp(x[:, 1]), np.ptp(x[:, 2]), 1e-3)
    for a, (i, j, label) in zip(axes, [(0, 1, "plan view (x–y)"), (0, 2, "side view (x–z)")]):
        for b in range(model.n_bodies):
            p = model.parents[b]
            if p >= 0:
                a.plot([x[p, i], pj[b, i], x[b, i]], [x[p, j], pj[b, j], x[b, j]], "-", color="0.5",
                       lw=1.5, zorder=1)
            kind = model.joint_kinds[b]
            if kind in ("revolute", "prismatic"):
                d = Rj[b] @ np.asarray(model.motion_axes[b][0]) * 0.12 * span
                a.annotate("", xy=(pj[b, i] + d[i], pj[b, j] + d[j]), xytext=(pj[b, i], pj[b, j]),
                           arrowprops=dict(arrowstyle="->", color="C3"))
                a.plot(pj[b, i], pj[b, j], "s" if kind == "revolute" else "D", color="C3", ms=6, zorder=3)
        a.scatter(x[:, i], x[:, j], s=sizes, color="C0", zorder=2, edgecolor="k")
        for b, name in enumerate(model.body_names):
            a.annotate(name, (x[b, i], x[b, j]), textcoords="offset points", xytext=(6, 6), fontsize=8)
        if j == 2:
            a.axhline(0.0, color="C9", lw=1, ls="--", zorder=0)
        a.set_xlabel("x [m]")
        a.set_ylabel("y [m]" if j == 1 else "z [m]")
        a.set_title(label)
        a.set_aspect("equal", adjustable="datalim")
        a.grid(alpha=0.3)
    text = title or (f"{model.name}: {model.n_bodies} bodies, {model.n_coordinates} coordinates "
                     "(■ hinge, ◆ slider, arrow = joint axis)")
    if ax is None:
        fig.suptitle(text)
        fig.tight_layout()
    else:
        # axes of a larger figure (e.g. one row per layout): the figure's title is the caller's;
        # a suptitle here would name every row after the last model drawn
        axes[0].set_title(f"{model.name}: plan view (x–y)")
        axes[1].set_title(f"{model.name}: side view (x–z)")
    return fig


def plot_time_series(ds, variables=("q",), *, ax=None):
    """Each variable of a simulation dataset against time, one line per coordinate/body."""
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(len(variables), 1, figsize=(9, 2.8 * len(variables)), sharex=True,
                             squeeze=False) if ax is None else (ax.figure, np.array([[ax]]))
    for a, v in zip(axes[:, 0], variables):
        da = ds[v]
        other = [d for d in da.dims if d != "time"]
        flat = da.stack(line=other) if other else da.expand_dims(line=[v])
        for k in range(flat.sizes["line"]):
            lbl = flat.line.values[k]
            a.plot(ds.time, flat.isel(line=k), label=" ".join(map(str, lbl)) if isinstance(lbl, tuple) else str(lbl))
        a.set_ylabel(f"{v} [{da.attrs.get('units', '')}]")
        a.grid(alpha=0.3)
        a.legend(fontsize=7, ncol=3)
    axes[-1, 0].set_xlabel("time [s]")
    fig.tight_layout()
    return fig


# ------------------------------------------------------------------------------ result files
def result_kind(ds) -> str:
    """What a result dataset is: "batch" (simulate_batch: a ``case`` dim), "rao" (mfm rao /
    frequency_response: ``rao`` over ``omega``) or "simulation" (simulate: ``q`` over ``time``)."""
    if "case" in ds.dims:
        return "batch"
    if "rao" in ds and "omega" in ds.dims:
        return "rao"
    if "q" in ds and "time" in ds.dims:
        return "simulation"
    raise ValueError(f"not an mfm result: variables {sorted(ds.data_vars)}, dims {dict(ds.sizes)}; "
                     "`mfm plot` draws the NetCDF files of `mfm simulate`, `mfm rao` and "
                     "simulate_batch (or give a .toml config for its layout)")


def _coordinate_units(ds):
    if "coordinate_unit" in ds.coords:
        return [str(u) for u in ds.coordinate_unit.values]
    return ["m" if str(c).rsplit(".", 1)[-1] in ("surge", "sway", "heave", "stroke") else "rad"
            for c in ds.coordinate.values]


def plot_simulation(ds):
    """A simulation result: q (one panel per unit: m, rad), PTO power, and the amplitude spectra
    of q over the second half (after any start-up transient). Returns the figure."""
    import matplotlib.pyplot as plt

    units = _coordinate_units(ds)
    groups = [u for u in ("m", "rad") if u in units]
    power = "pto_power" in ds
    n = len(groups) + int(power)
    fig, axes = plt.subplots(n + 1, 1, figsize=(9, 2.4 * (n + 1)), squeeze=False)
    axes = axes[:, 0]
    t = np.asarray(ds.time.values, dtype=float)
    for a, u in zip(axes, groups):
        for k, c in enumerate(ds.coordinate.values):
            if units[k] == u:
                a.plot(t, ds.q.isel(coordinate=k), lw=1, label=str(c))
        a.set_ylabel(f"q [{u}]")
    if power:
        a = axes[len(groups)]
        for p in ds.pto.values:
            a.plot(t, ds.pto_power.sel(pto=p), lw=1, label=f"{p}")
        a.set_ylabel("PTO power [W]")
    for a in axes[:n]:
        a.set_xlabel("time [s]")
        a.grid(alpha=0.3)
        a.legend(fontsize=7, ncol=3)
    # amplitude spectrum of the second half (one-sided, |FFT| × 2/N: a sine of amplitude a → a)
    a = axes[n]
    half = ds.isel(time=slice(len(t) // 2, None))
    th = np.asarray(half.time.values, dtype=float)
    if len(th) >= 8:
        dt = float(np.median(np.diff(th)))
        om = 2 * np.pi * np.fft.rfftfreq(len(th), dt)
        for k, c in enumerate(ds.coordinate.values):
            x = np.asarray(half.q.isel(coordinate=k).values, dtype=float)
            amp = 2 * np.abs(np.fft.rfft((x - x.mean()) * np.hanning(len(x)))) / np.hanning(len(x)).sum()
            a.semilogy(om[1:], np.maximum(amp[1:], 1e-12), lw=1, label=f"{c} [{units[k]}]")
        a.set_xlim(0, min(om[-1], 10 * om[np.argmax(amp[1:]) + 1] if len(om) > 2 else om[-1]))
    a.set_xlabel("ω [rad/s]")
    a.set_ylabel(f"amplitude, t ≥ {th[0]:.4g} s" if len(th) else "amplitude")
    a.grid(alpha=0.3)
    a.legend(fontsize=7, ncol=3)
    title = ds.attrs.get("model", ds.attrs.get("config", "simulation"))
    fig.suptitle(f"{title}: {ds.attrs.get('sea_label', ds.attrs.get('sea', 'still water'))}"[:110], fontsize=10)
    fig.tight_layout()
    return fig


def plot_rao(ds):
    """RAOs (|RAO| and phase against ω, one line per coordinate; natural frequencies marked).
    Accepts the file of `mfm rao` (complex split along ``complex``) or the dataset itself."""
    import matplotlib.pyplot as plt

    from hydro.database import merge_complex

    ds = merge_complex(ds)
    rao = ds.rao
    if "heading" in rao.dims:
        rao = rao.isel(heading=0)
    units = _coordinate_units(ds)
    om = np.asarray(ds.omega.values, dtype=float)
    fig, (a1, a2) = plt.subplots(2, 1, figsize=(9, 6), sharex=True)
    for k, c in enumerate(ds.coordinate.values):
        z = np.asarray(rao.isel(coordinate=k).values)
        a1.plot(om, np.abs(z), label=f"{c} [{units[k]}/m]")
        a2.plot(om, np.degrees(np.angle(z)), lw=1)
    if "natural_frequency" in ds:
        for w in np.asarray(ds.natural_frequency.values, dtype=float):
            if om[0] <= w <= om[-1]:
                for a in (a1, a2):
                    a.axvline(w, color="0.6", ls=":", lw=1)
    a1.set_ylabel("|RAO| [m/m or rad/m]")
    a2.set_ylabel("phase [deg]")
    a2.set_xlabel("ω [rad/s]")
    for a in (a1, a2):
        a.grid(alpha=0.3)
    a1.legend(fontsize=7, ncol=3)
    a1.set_title(f"RAOs of {ds.attrs.get('config', '')} (dotted: natural frequencies)", fontsize=10)
    fig.tight_layout()
    return fig


def plot_batch(ds, discard=0.5):
    """A simulate_batch result: mean PTO power per case over the last (1 − discard) of the
    steps, as a power matrix when the cases carry ``hs`` and ``tp`` coordinates, else per case."""
    import matplotlib.pyplot as plt

    if "pto_power" not in ds:
        raise ValueError("this batch result has no pto_power: nothing to plot as a power matrix")
    n = ds.sizes["step"]
    P = ds.pto_power.isel(step=slice(int(discard * n), None)).mean("step").sum("pto")
    fig, a = plt.subplots(figsize=(8, 4.5))
    if "hs" in ds.coords and "tp" in ds.coords and ds.hs.dims == ("case",):
        hs, tp = np.asarray(ds.hs.values, float), np.asarray(ds.tp.values, float)
        H, T = np.unique(hs), np.unique(tp)
        M = np.full((len(H), len(T)), np.nan)
        M[np.searchsorted(H, hs), np.searchsorted(T, tp)] = P.values
        m = a.pcolormesh(T, H, M, shading="nearest")
        fig.colorbar(m, ax=a, label="mean PTO power [W]")
        a.set_xlabel("Tp [s]")
        a.set_ylabel("Hs [m]")
    else:
        x = ds.tp.values if "tp" in ds.coords else ds.case.values
        a.plot(x, P.values, "o-")
        a.set_xlabel("Tp [s]" if "tp" in ds.coords else "case")
        a.set_ylabel("mean PTO power [W]")
        a.grid(alpha=0.3)
    a.set_title(f"mean PTO power over the last {1 - discard:.0%} of each case", fontsize=10)
    fig.tight_layout()
    return fig


def save_result_plot(ds, path, *, dpi=120) -> str:
    """Draw a result dataset (simulation, RAO or batch; see :func:`result_kind`) into a PNG at
    `path`. Returns a few words saying what was drawn."""
    import matplotlib

    if matplotlib.get_backend().lower() not in ("agg", "module://matplotlib_inline.backend_inline"):
        matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    kind = result_kind(ds)
    fig = {"simulation": plot_simulation, "rao": plot_rao, "batch": plot_batch}[kind](ds)
    fig.savefig(path, dpi=dpi)
    plt.close(fig)
    return {"simulation": "time series, PTO power and spectra", "rao": "RAOs",
            "batch": "mean power per case"}[kind]
