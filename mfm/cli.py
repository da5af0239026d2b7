"""Command line: ``mfm info | simulate | plot``."""
from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np


def _pairs(items, what):
    out = {}
    for item in items or []:
        if "=" not in item:
            raise SystemExit(f"mfm: {what} {item!r}: expected NAME=VALUE, e.g. float3.angle=0.1")
        k, v = item.split("=", 1)
        try:
            out[k.strip()] = float(v)
        except ValueError:
            raise SystemExit(f"mfm: {what} {item!r}: {v!r} is not a number") from None
    return out


def cmd_info(args):
    import mfm

    model = mfm.load(args.config)
    print(f"{model.name}: {model.n_bodies} bodies, {model.n_coordinates} coordinates, "
          f"gravity {float(model.gravity)} m/s²")
    print("\ntree:")
    children = {}
    for b in model.bodies:
        children.setdefault(b.parent, []).append(b)

    def show(b, depth):
        j = b.joint
        extra = ""
        if j.axis is not None:
            extra += f" axis {np.round(j.axis, 4).tolist()}"
        if j.point is not None:
            extra += f" point {np.round(j.point, 4).tolist()}"
        print(f"  {'  ' * depth}{b.name}  [{j.kind}{extra}]  mass {b.mass:g} kg, "
              f"CoM {np.round(b.com, 4).tolist()} m")
        for c in children.get(b.name, []):
            show(c, depth + 1)

    for root in children[None]:
        show(root, 0)
    print("\ncoordinates:")
    for k, c in enumerate(model.coordinates):
        loads = []
        if float(model.stiffness[k]):
            loads.append(f"spring {float(model.stiffness[k]):g}")
        if float(model.damping[k]):
            loads.append(f"damper {float(model.damping[k]):g}")
        print(f"  q[{k}] {c}" + (f"  ({', '.join(loads)})" if loads else ""))
    print(f"\ntotal mass {float(model.mass.sum()):g} kg")


def cmd_simulate(args):
    import mfm

    model = mfm.load(args.config)
    t0 = time.perf_counter()
    ds = mfm.simulate(model, duration=args.duration, dt=args.dt, integrator=args.integrator,
                      q0=_pairs(args.initial, "--initial"),
                      qd0=_pairs(args.initial_velocity, "--initial-velocity"),
                      save_every=args.save_every)
    wall = time.perf_counter() - t0
    ds.attrs["config"] = str(args.config)
    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    ds.to_netcdf(out)
    n = int(round(args.duration / args.dt))
    print(f"{model.name}: {n} steps of {args.dt} s with {args.integrator} in {wall:.2f} s "
          f"(including compilation) -> {out}")
    last = ds.isel(time=-1)
    for c in model.coordinates:
        print(f"  {c:>24s} at t = {float(last.time):g} s: {float(last.q.sel(coordinate=c)):+.6g}")


def cmd_plot(args):
    import matplotlib

    matplotlib.use("Agg")
    import mfm
    from mfm.plotting import plot_layout

    model = mfm.load(args.config)
    fig = plot_layout(model)
    out = Path(args.out or Path(args.config).with_suffix(".png").name)
    out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out, dpi=args.dpi)
    print(f"layout of {model.name} -> {out}")


def main(argv=None):
    ap = argparse.ArgumentParser(prog="mfm", description="Floating multi-body systems by the Moving "
                                 "Frame Method.")
    sub = ap.add_subparsers(dest="command", required=True)
    p = sub.add_parser("info", help="print the tree, coordinates and masses of a config")
    p.add_argument("config")
    p.set_defaults(func=cmd_info)
    p = sub.add_parser("simulate", help="simulate a config and write the results as NetCDF")
    p.add_argument("config")
    p.add_argument("--duration", type=float, default=10.0, help="s (default 10)")
    p.add_argument("--dt", type=float, default=0.01, help="time step, s (default 0.01)")
    p.add_argument("--integrator", default="rk4", choices=["rk4", "beeman", "semi_implicit", "newmark"])
    p.add_argument("--initial", action="append", metavar="NAME=VALUE",
                   help="initial coordinate (m or rad), repeatable, e.g. --initial upper.angle=0.3")
    p.add_argument("--initial-velocity", action="append", metavar="NAME=VALUE",
                   help="initial rate (m/s or rad/s), repeatable")
    p.add_argument("--save-every", type=int, default=1, help="keep every k-th step")
    p.add_argument("--out", default="out/simulation.nc", help="NetCDF output (default out/simulation.nc)")
    p.set_defaults(func=cmd_simulate)
    p = sub.add_parser("plot", help="plan and side view of a config's layout (PNG)")
    p.add_argument("config")
    p.add_argument("--out", help="PNG file (default: the config's name in the current directory)")
    p.add_argument("--dpi", type=int, default=120)
    p.set_defaults(func=cmd_plot)
    args = ap.parse_args(argv)
    try:
        args.func(args)
    except Exception as e:  # config and simulation errors: one clear line, exit code 2
        from mfm import ConfigError, SimulationError

        if isinstance(e, (ConfigError, SimulationError, ValueError, KeyError)):
            print(f"mfm {args.command}: error: {e}", file=sys.stderr)
            return 2
        raise
    return 0


if __name__ == "__main__":
    sys.exit(main())
