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
    """Each variable of a simulation dataset against time, one line per coordinate/body; the
    PTO power in kW with its mean over the second half drawn across that window (the window of
    `mfm simulate`'s summary). Legends beside the panels (:data:`LEGEND`), never over the curves."""
    import matplotlib.pyplot as plt

    if ax is None:
        fig, axes = plt.subplots(len(variables), 1, figsize=(10, 2.6 * len(variables)),
                                 sharex=True, squeeze=False, layout="constrained")
    else:
        fig, axes = ax.figure, np.array([[ax]])
    t = np.asarray(ds.time.values, dtype=float)
    h0 = len(t) // 2
    for a, v in zip(axes[:, 0], variables):
        da = ds[v]
        unit = da.attrs.get("units", "")
        scale = 1.0
        if v == "pto_power" and unit == "W":
            scale, unit = 1e-3, "kW"
        other = [d for d in da.dims if d != "time"]
        flat = da.stack(line=other) if other else da.expand_dims(line=[v])
        for k in range(flat.sizes["line"]):
            lbl = flat.line.values[k]
            a.plot(t, scale * flat.isel(line=k).values,
                   label=" ".join(map(str, lbl)) if isinstance(lbl, tuple) else str(lbl))
        if v == "pto_power" and len(t) > h0:
            total = scale * np.asarray(flat.values, dtype=float).reshape(len(t), -1).sum(axis=1)
            m = float(np.mean(total[h0:]))
            what = "mean" if flat.sizes["line"] == 1 else f"mean of the total of {flat.sizes['line']}"
            a.plot([t[h0], t[-1]], [m, m], "--", color="k", lw=1.2,
                   label=f"{what} {m:.4g} {unit} (t ≥ {t[h0]:.4g} s)")
        a.set_ylabel(f"{v} [{unit}]")
        a.grid(alpha=0.3)
        _legend(a, ncol=1 + (len(a.get_lines()) > 2 * MAX_LINES))
    axes[-1, 0].set_xlabel("time [s]")
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


# a panel holds at most this many curves: with more (Wu & Yuan's 12 hinges and 6 platform
# coordinates) the lines cannot be told apart and the legend outgrows the panel
MAX_LINES = 6
LEGEND = dict(loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0.0, fontsize=7)


def _legend(a, **kw):
    """The legend beside the axes, on the right (never over the curves)."""
    if a.get_legend_handles_labels()[0]:
        a.legend(**{**LEGEND, **kw})


def _chunks(items, size=MAX_LINES):
    """Consecutive chunks of at most ``size``, evenly filled (12 → 6 + 6, 7 → 4 + 3)."""
    n = -(-len(items) // size) if items else 0
    return [list(c) for c in np.array_split(np.arange(len(items)), n)] if n else []


def coordinate_panels(names, units, size=MAX_LINES):
    """How the coordinates share panels: a list of (unit, indices, title). One panel per unit
    (m, rad) while it holds at most ``size`` coordinates; beyond, a body with several coordinates
    of that unit gets its own panel(s) (the platform's roll, pitch, yaw) and the bodies with one
    (the hinged floats) share evenly filled panels of at most ``size``."""
    out = []
    for u in dict.fromkeys(units):
        idx = [k for k, v in enumerate(units) if v == u]
        if len(idx) <= size:
            out.append((u, idx, ""))
            continue
        body = [str(names[k]).rsplit(".", 1)[0] for k in idx]
        count = {b: body.count(b) for b in body}
        for b in dict.fromkeys(body):
            if count[b] > 1:
                mine = [k for k, bb in zip(idx, body) if bb == b]
                out += [(u, [mine[i] for i in c], b) for c in _chunks(mine, size)]
        single = [k for k, bb in zip(idx, body) if count[bb] == 1]
        for c in _chunks(single, size):
            ks = [single[i] for i in c]
            first, last = (str(names[ks[0]]).rsplit(".", 1)[0], str(names[ks[-1]]).rsplit(".", 1)[0])
            out.append((u, ks, first if first == last else f"{first} … {last}"))
    return out


def sea_of(ds, sea=None):
    """The sea of a simulation: ``sea`` if given, else rebuilt from the dataset's ``sea`` attribute
    (the repr of hydro.Regular, Jonswap or PiersonMoskowitz: their keywords read as literals, the
    spreading left out, which no spectrum depends on); None for still water or a sea the attribute
    cannot rebuild (a UserSpectrum's table, a measured record)."""
    if sea is not None:
        return sea
    import ast

    import hydro

    text = str(ds.attrs.get("sea", ""))
    try:
        call = ast.parse(text, mode="eval").body
    except SyntaxError:
        return None
    if not (isinstance(call, ast.Call) and isinstance(call.func, ast.Name)
            and call.func.id in ("Regular", "Jonswap", "PiersonMoskowitz")):
        return None
    kw = {}
    for k in call.keywords:
        if k.arg in (None, "spreading"):
            continue
        try:
            kw[k.arg] = ast.literal_eval(k.value)
        except ValueError:
            return None
    try:
        return getattr(hydro, call.func.id)(**kw)
    except (TypeError, ValueError):
        return None


def welch_psd(x, dt):
    """One-sided PSD of ``x`` sampled every ``dt`` s, in units² s/rad over ω (rad/s), by Welch's
    method (scipy.signal.welch: Hann segments of ~2n/9 samples, a power of two, half overlapping,
    so ~8 of them, the mean removed): S(ω) = S_f(f)/(2π) at ω = 2πf, so ∫ S dω estimates the variance of x.
    Returns (ω, S, the number of segments averaged)."""
    from scipy.signal import welch

    x = np.asarray(x, dtype=float)
    n = len(x)
    nperseg = int(min(n, 2 ** max(4, int(round(np.log2(max(2 * n / 9, 16)))))))
    f, S = welch(x, fs=1.0 / dt, window="hann", nperseg=nperseg, noverlap=nperseg // 2,
                 detrend="constant", scaling="density")
    segments = 1 + (n - nperseg) // (nperseg - nperseg // 2)
    return 2 * np.pi * f, S / (2 * np.pi), segments


def _power_panels(ds):
    """(title, lines in kW, show the mean) for the PTO power: each PTO (panels of at most
    MAX_LINES), and with several PTOs their total first."""
    P = np.asarray(ds.pto_power.values, dtype=float) / 1e3        # W → kW
    names = [str(p) for p in ds.pto.values]
    panels = []
    if len(names) > 1:
        panels.append((f"total of {len(names)} PTOs", [("total", P.sum(axis=1))], True))
    for c in _chunks(names):
        lines = [(names[i], P[:, i]) for i in c]
        panels.append(("" if len(names) <= MAX_LINES else f"{names[c[0]]} … {names[c[-1]]}",
                       lines, len(names) == 1))
    return panels


def plot_simulation(ds, sea=None):
    """A simulation result, one column of panels over time and frequency:

    * the wave elevation η at the origin (m), when the run had a sea;
    * the coordinates q, one panel per unit (m, rad), split into panels of at most
      :data:`MAX_LINES` curves where there are more (:func:`coordinate_panels`);
    * the PTO power in kW, with several PTOs their total first, its mean over the second half of
      the run (the window of `mfm simulate`'s summary) drawn across that window;
    * the spectra over the second half, over the sea's band: for an irregular sea the PSDs
      S(ω) (Welch, :func:`welch_psd`; ∫S dω = variance) of η with the sea's target spectrum over
      it and of the coordinates; for a regular wave or still water the amplitude spectra of the
      coordinates (|FFT| × 2/N, Hann window: a sine of amplitude a → a); the coordinates in the
      panels of their time series.

    Legends sit beside the panels, never over the curves. ``sea``: the hydro sea of the run
    (else rebuilt from the dataset's attribute, :func:`sea_of`). Returns the figure."""
    import matplotlib.pyplot as plt

    sea = sea_of(ds, sea)
    units = _coordinate_units(ds)
    names = [str(c) for c in ds.coordinate.values]
    t = np.asarray(ds.time.values, dtype=float)
    h0 = len(t) // 2
    t_half = t[h0] if len(t) else 0.0
    wave = "eta" in ds and float(np.abs(ds.eta).max()) > 0.0
    irregular = sea is not None and hasattr(sea, "spectrum")
    q_panels = coordinate_panels(names, units)
    p_panels = _power_panels(ds) if "pto_power" in ds else []
    n_spec = int(wave and irregular) + len(q_panels)
    n = int(wave) + len(q_panels) + len(p_panels) + n_spec
    fig, axes = plt.subplots(n, 1, figsize=(10, 2.2 * n), squeeze=False, layout="constrained")
    axes = list(axes[:, 0])
    time_axes = axes[:n - n_spec]
    for a in time_axes[1:]:
        a.sharex(time_axes[0])
    k = 0
    if wave:
        a = axes[k]
        k += 1
        a.plot(t, ds.eta.values, lw=1, color="C9", label="η")
        a.set_ylabel("η [m]")
        a.set_title("wave elevation at the origin", fontsize=9, loc="left")
    for u, idx, title in q_panels:
        a = axes[k]
        k += 1
        for i in idx:
            a.plot(t, ds.q.isel(coordinate=i), lw=1, label=names[i])
        a.set_ylabel(f"q [{u}]")
        if title:
            a.set_title(title, fontsize=9, loc="left")
    for title, lines, mean in p_panels:
        a = axes[k]
        k += 1
        for name, y in lines:
            a.plot(t, y, lw=1, label=name)
        if mean and len(t) > h0:
            y = lines[0][1]
            m = float(np.mean(y[h0:]))
            a.plot([t_half, t[-1]], [m, m], "--", color="k", lw=1.2,
                   label=f"mean {m:.4g} kW (t ≥ {t_half:.4g} s)")
        a.set_ylabel("PTO power [kW]")
        if title:
            a.set_title(title, fontsize=9, loc="left")
    for a in time_axes:
        a.grid(alpha=0.3)
        _legend(a)
    if time_axes:
        time_axes[-1].set_xlabel("time [s]")

    # spectra over the second half (after any start-up transient)
    half = ds.isel(time=slice(h0, None))
    th = t[h0:]
    dt = float(np.median(np.diff(th))) if len(th) > 1 else 1.0
    if irregular:
        band = sea.band
    elif sea is not None:
        band = (0.0, 4.0 * 2 * np.pi / sea.period)        # the wave and its first harmonics
    else:
        band = None
    spec_axes = axes[n - n_spec:]
    j = 0
    if wave and irregular:
        a = spec_axes[j]
        j += 1
        if len(th) >= 16:
            w, S, K = welch_psd(half.eta.values, dt)
            a.plot(w, S, lw=1, color="C9", label=f"η, Welch ({K} segments)")
        wt = np.linspace(band[0], band[1], 400)
        a.plot(wt, sea.spectrum(wt), "--", color="k", lw=1.2, label="target S(ω)")
        a.set_ylabel("S_η [m² s/rad]")
        a.set_title(f"wave spectrum, t ≥ {t_half:.4g} s", fontsize=9, loc="left")
    for u, idx, group in q_panels:
        a = spec_axes[j]
        j += 1
        for i in idx:
            x = np.asarray(half.q.isel(coordinate=i).values, dtype=float)
            if len(x) < 16:
                continue
            if irregular:
                w, S, _ = welch_psd(x, dt)
                a.semilogy(w[1:], np.maximum(S[1:], 1e-30), lw=1, label=names[i])
            else:
                win = np.hanning(len(x))
                w = 2 * np.pi * np.fft.rfftfreq(len(x), dt)
                amp = 2 * np.abs(np.fft.rfft((x - x.mean()) * win)) / win.sum()
                a.semilogy(w[1:], np.maximum(amp[1:], 1e-12), lw=1, label=names[i])
        # six decades below the largest value in the band: the floor of round-off says nothing
        top = [np.max(ln.get_ydata()[(ln.get_xdata() >= (band or (0, np.inf))[0])
                                     & (ln.get_xdata() <= (band or (0, np.inf))[1])], initial=0.0)
               for ln in a.get_lines()]
        if top and max(top) > 0.0:
            a.set_ylim(max(top) * 1e-6, max(top) * 3.0)
        a.set_ylabel(f"PSD of q [{u}² s/rad]" if irregular else f"amplitude of q [{u}]")
        a.set_title(("PSD" if irregular else "amplitude spectrum") + " of the coordinates"
                    + (f" ({group})" if group else "") + f", t ≥ {t_half:.4g} s", fontsize=9,
                    loc="left")
    for a in spec_axes:
        if band is not None:
            a.set_xlim(*band)
        elif len(th) >= 16:
            # still water: up to ten times the strongest response's frequency (its harmonics),
            # not the Nyquist frequency of a fine step
            peaks = [ln.get_xdata()[np.argmax(ln.get_ydata())] for ln in a.get_lines()]
            a.set_xlim(0.0, min(np.pi / dt, 10.0 * max(peaks)) if peaks else np.pi / dt)
        if sea is not None and not irregular:
            a.axvline(2 * np.pi / sea.period, color="C9", ls=":", lw=1.2,
                      label=f"the wave, ω {2 * np.pi / sea.period:.4g} rad/s")
        a.set_xlabel("ω [rad/s]")
        a.grid(alpha=0.3)
        _legend(a)
    title = ds.attrs.get("model", ds.attrs.get("config", "simulation"))
    label = ds.attrs.get("sea_label", str(sea) if sea is not None else "still water")
    fig.suptitle(f"{title}: {label}"[:110], fontsize=10)
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


def save_result_plot(ds, path, *, dpi=120, sea=None) -> str:
    """Draw a result dataset (simulation, RAO or batch; see :func:`result_kind`) into a PNG at
    `path`. ``sea``: a simulation's sea (else rebuilt from its attribute). Returns a few words
    saying what was drawn."""
    import matplotlib

    if matplotlib.get_backend().lower() not in ("agg", "module://matplotlib_inline.backend_inline"):
        matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    kind = result_kind(ds)
    fig = (plot_simulation(ds, sea) if kind == "simulation" else
           {"rao": plot_rao, "batch": plot_batch}[kind](ds))
    fig.savefig(path, dpi=dpi)
    plt.close(fig)
    return {"simulation": "wave elevation, time series, PTO power and spectra", "rao": "RAOs",
            "batch": "mean power per case"}[kind]
