"""Plots of a float tree and of results (matplotlib; imported lazily by the CLI)."""
from __future__ import annotations

import numpy as np

from .kinematics import kinematics
from .model import Model


def plot_layout(model: Model, q=None, *, ax=None, title=None):
    """Plan (x–y) and side (x–z) views of a tree at configuration q (default q = 0): CoMs sized by
    mass, links from each parent CoM through the joint point to the child CoM, joint axes as arrows.
    Returns the matplotlib figure."""
    import matplotlib.pyplot as plt

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
    fig.suptitle(title or f"{model.name}: {model.n_bodies} bodies, {model.n_coordinates} coordinates "
                 "(■ hinge, ◆ slider, arrow = joint axis)")
    fig.tight_layout()
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
