"""Command line: ``mfm info | simulate | rao | hydro | plot``."""
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

    model = mfm.load(args.config, hydro=False)
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


def _sea(args):
    import hydro

    if args.wave is None:
        for flag in ("height", "period", "hs", "tp"):
            if getattr(args, flag) is not None:
                raise SystemExit(f"mfm simulate: --{flag} needs --wave regular or --wave jonswap")
        return None
    heading = float(np.deg2rad(args.heading))
    if args.wave == "regular":
        if args.height is None or args.period is None:
            raise SystemExit("mfm simulate: --wave regular needs --height (m) and --period (s)")
        return hydro.Regular(height=args.height, period=args.period, heading=heading)
    if args.hs is None or args.tp is None:
        raise SystemExit("mfm simulate: --wave jonswap needs --hs (m) and --tp (s)")
    kw = {}
    if args.components is not None:
        kw["n_components"] = args.components
    return hydro.Jonswap(hs=args.hs, tp=args.tp, gamma=args.gamma, seed=args.seed, heading=heading,
                         **kw)


def cmd_simulate(args):
    import mfm

    model = mfm.load(args.config, body_coupling=False if args.no_body_coupling else None)
    sea = _sea(args)
    t0 = time.perf_counter()
    ds = mfm.simulate(model, sea, duration=args.duration, dt=args.dt, integrator=args.integrator,
                      q0=_pairs(args.initial, "--initial"),
                      qd0=_pairs(args.initial_velocity, "--initial-velocity"),
                      save_every=args.save_every, ramp=args.ramp, radiation=args.radiation)
    wall = time.perf_counter() - t0
    ds.attrs["config"] = str(args.config)
    ds.attrs["command"] = "mfm " + " ".join(sys.argv[1:]) if sys.argv[1:] else "mfm simulate"
    if sea is not None:
        ds.attrs["sea"] = repr(sea)
    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    ds.to_netcdf(out)
    n = int(round(args.duration / args.dt))
    print(f"{model.name}: {n} steps of {args.dt} s with {args.integrator} in {wall:.2f} s "
          f"(including compilation) -> {out}")
    half = ds.isel(time=slice(len(ds.time) // 2, None))
    for c in model.coordinates:
        q = half.q.sel(coordinate=c)
        print(f"  {c:>24s}: std over the second half {float(q.std()):.5g}, last {float(q[-1]):+.5g}")
    if "pto_power" in ds:
        for p in ds.pto.values:
            print(f"  mean power of {p} over the second half: {float(half.pto_power.sel(pto=p).mean()):.6g} W")


def cmd_rao(args):
    import mfm
    from hydro.database import split_complex

    model = mfm.load(args.config, body_coupling=False if args.no_body_coupling else None)
    omega = np.linspace(args.omega_min, args.omega_max, args.n)
    ds = mfm.frequency_response(model, omega, heading=float(np.deg2rad(args.heading)),
                                radiation=args.radiation)
    nat = mfm.natural_frequencies(model)
    ds["natural_frequency"] = (("mode",), nat["eigen"].values, {"units": "rad/s",
                                                         "long_name": "undamped, generalised eigenproblem"})
    ds.attrs["natural_frequencies_min_det"] = np.array2string(nat["min_det"].values, precision=5)
    ds.attrs["config"] = str(args.config)
    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    split_complex(ds).to_netcdf(out)
    print(f"{model.name}: RAOs at {args.n} frequencies {args.omega_min}–{args.omega_max} rad/s -> {out}")
    print(f"  natural frequencies (eigen): {np.round(nat['eigen'].values, 4).tolist()} rad/s")
    print(f"  natural frequencies (min |det|): {np.round(nat['min_det'].values, 4).tolist()} rad/s")
    for c in model.coordinates:
        a = np.abs(ds.rao.sel(coordinate=c).values)
        print(f"  {c:>24s}: peak |RAO| {a.max():.4g} at {omega[a.argmax()]:.4g} rad/s")


def cmd_hydro(args):
    from mfm.bemgen import generate

    generate(args.config, out=args.out, force=args.force, n_threads=args.threads)


def cmd_plot(args):
    import matplotlib

    matplotlib.use("Agg")
    import mfm
    from mfm.plotting import plot_layout

    model = mfm.load(args.config, hydro=False)
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
    p.add_argument("--wave", choices=["regular", "jonswap"], help="sea state (default: still water)")
    p.add_argument("--height", type=float, help="regular wave height H, m")
    p.add_argument("--period", type=float, help="regular wave period T, s")
    p.add_argument("--hs", type=float, help="JONSWAP significant wave height, m")
    p.add_argument("--tp", type=float, help="JONSWAP peak period, s")
    p.add_argument("--gamma", type=float, default=3.3, help="JONSWAP peak enhancement (default 3.3)")
    p.add_argument("--seed", type=int, default=0, help="random phases seed (default 0)")
    p.add_argument("--components", type=int, help="number of wave components")
    p.add_argument("--heading", type=float, default=0.0, help="wave heading, degrees (0 = towards +x)")
    p.add_argument("--ramp", type=float, default=0.0, help="start-up ramp of the excitation, s")
    p.add_argument("--radiation", default="convolution", choices=["convolution", "state_space", "none"])
    p.add_argument("--no-body-coupling", action="store_true",
                   help="drop the hydrodynamic interaction between bodies")
    p.add_argument("--out", default="out/simulation.nc", help="NetCDF output (default out/simulation.nc)")
    p.set_defaults(func=cmd_simulate)
    p = sub.add_parser("rao", help="frequency-domain RAOs and natural frequencies (NetCDF)")
    p.add_argument("config")
    p.add_argument("--omega-min", type=float, required=True, help="rad/s")
    p.add_argument("--omega-max", type=float, required=True, help="rad/s")
    p.add_argument("--n", type=int, default=100, help="number of frequencies (default 100)")
    p.add_argument("--heading", type=float, default=0.0, help="degrees")
    p.add_argument("--radiation", default="database", choices=["database", "convolution", "state_space"])
    p.add_argument("--no-body-coupling", action="store_true")
    p.add_argument("--out", default="out/rao.nc")
    p.set_defaults(func=cmd_rao)
    p = sub.add_parser("hydro", help="generate the config's hydro database with capytaine")
    p.add_argument("config")
    p.add_argument("--out", help="NetCDF path (default: the config's [hydro] database)")
    p.add_argument("--force", action="store_true", help="solve again even if cached")
    p.add_argument("--threads", type=int, help="threads per BEM solve (default: all cores)")
    p.set_defaults(func=cmd_hydro)
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

        if isinstance(e, (ConfigError, SimulationError, ValueError, KeyError, FileNotFoundError)):
            print(f"mfm {args.command}: error: {e}", file=sys.stderr)
            return 2
        raise
    return 0


if __name__ == "__main__":
    sys.exit(main())
