"""Command line: ``mfm info | simulate | optimize | rao | hydro | fits | plot``: the commands.

The parser and the entry point are in the top-level module :mod:`mfm_cli` (importing this module
imports the ``mfm`` package, and with it jax): it calls the commands here, and nothing here
imports it back. Each command imports the rest of what it needs (xarray, matplotlib, hydro)
itself.
"""
from __future__ import annotations

import math
import os
import re
import sys
import time
import warnings
from pathlib import Path

from .. import results
from ..errors import SimulationError
from ..runner.frequency import frequency_response, natural_frequencies
from ..frequency.rest import no_restoring
from ..runner.simulation import simulate
from .bemgen import generate
from .build import load
from .config import load_config


# every usage, config and input error of the command line exits with this status: argparse's own
# (mfm_cli.EXIT_USAGE, the same number; mfm_cli imports nothing of mfm before the arguments parse)
EXIT_USAGE = 2


class UsageError(SystemExit):
    """A command-line mistake the parser cannot see (an option that needs another, a NAME=VALUE
    without its '='): exit status :data:`EXIT_USAGE`, argparse's; ``str()`` is the message, which
    :func:`mfm_cli.main` prints as one ``mfm COMMAND: error: ...`` line."""

    def __init__(self, message: str):
        super().__init__(message)
        self.code = EXIT_USAGE


def _grid_remedy(lo: str, hi: str, args) -> str:
    """What a command-line user does about a sea whose frequencies leave the database's grid
    [lo, hi] rad/s (the numbers as the message printed them)."""
    wave = getattr(args, "wave", None)
    extend = ("or extend the database over a wider band ([hydro.bem] omega_min and omega_max in "
              "the config, then mfm hydro CONFIG)")
    if wave == "regular":
        return (f"give a --period whose frequency 2π/T lies in the grid (T from "
                f"{2 * math.pi / float(hi):.4g} to {2 * math.pi / float(lo):.4g} s), {extend}")
    flags = [f"--omega-min {lo}", f"--omega-max {hi}"]
    if wave == "jonswap" and getattr(args, "tp", None):
        # only the end that leaves the grid (or both, a band wholly outside it)
        from hydro.waves import DEFAULT_BAND

        wp = 2.0 * math.pi / args.tp
        b_lo = getattr(args, "omega_min", None) or DEFAULT_BAND[0] * wp
        b_hi = getattr(args, "omega_max", None) or DEFAULT_BAND[1] * wp
        if float(lo) <= b_lo < float(hi):
            flags.remove(f"--omega-min {lo}")
        if float(lo) < b_hi <= float(hi):
            flags.remove(f"--omega-max {hi}")
        flags = flags or [f"--omega-min {lo}", f"--omega-max {hi}"]
    return (f"give the spectrum a band inside the grid with --omega-min/--omega-max (rad/s), "
            f"e.g. {' '.join(flags)} (a band that keeps less than 90 % of the spectrum's variance "
            f"warns), {extend}")


_NUM = r"[-+0-9.eE]+"
# the Python arguments a remedy of mfm or hydro may name, as the command line's options (a name
# is rewritten only for a command that has the option: args has its dest); NAME= only, so a
# sea's repr (Jonswap(hs=2.0, ...)) keeps its fields
_PYTHON_NAMES = (("save_every", "--save-every", "save_every"),
                 ("n_components", "--components", "components"),
                 ("qd0", "--initial-velocity", "initial_velocity"),
                 ("q0", "--initial", "initial"))


def cli_text(message, args=None) -> str:
    """A message of mfm or hydro (an error's or a warning's) as a command-line user reads it: the
    remedies it names in Python (``omega_range``, ``components.band(...)``, ``save_every=``,
    ``q0=``) as the command's options (``--omega-min/--omega-max``, ``--save-every``,
    ``--initial``). The rest of the text is kept as it is."""
    text = str(message)
    # a sea outside the database's grid: the time domain (hydro.excitation) and the frequency
    # domain (mfm.validation.check_sea_in_grid)
    text = re.sub(rf"lies outside the database's omega grid \[({_NUM}), ({_NUM})\] rad/s: pass "
                  r"omega_range inside the grid to the sea state, use components\.band\(\.\.\.\), "
                  r"or extend the database",
                  lambda m: (f"lies outside the database's omega grid [{m[1]}, {m[2]}] rad/s: "
                             + _grid_remedy(m[1], m[2], args)), text)
    text = re.sub(rf"Give the sea omega_range=\(ω_min, ω_max\) inside \[({_NUM}), ({_NUM})\], or "
                  r"regenerate the database over a wider band",
                  lambda m: _grid_remedy(m[1], m[2], args)[0].upper()
                  + _grid_remedy(m[1], m[2], args)[1:], text)
    # frequencies outside the grid in the frequency domain (mfm.loads.water): a sea's (optimize)
    # or the RAOs' own (rao: --omega-min/--omega-max)
    def grid(m):
        if getattr(args, "wave", None) is not None:
            return (f"the sea's frequencies [{m[1]}, {m[2]}] rad/s lie outside the database's grid "
                    f"[{m[3]}, {m[4]}] rad/s: " + _grid_remedy(m[3], m[4], args))
        if hasattr(args, "omega_min"):
            return (f"--omega-min {m[1]} to --omega-max {m[2]} rad/s lies outside the database's "
                    f"grid [{m[3]}, {m[4]}] rad/s: give frequencies inside it, e.g. --omega-min "
                    f"{m[3]} --omega-max {m[4]}, or extend the database over a wider band "
                    "([hydro.bem] omega_min and omega_max in the config, then mfm hydro CONFIG)")
        return m[0]
    text = re.sub(rf"omega: \[({_NUM}), ({_NUM})\] rad/s lies outside the database's \[({_NUM}), "
                  rf"({_NUM})\] rad/s; choose frequencies inside it or regenerate the database",
                  grid, text)
    # a band that keeps too little of the spectrum (hydro.waves, a SeaStateWarning)
    text = re.sub(rf"^\w+: omega_range=\(({_NUM}), ({_NUM})\) rad/s keeps",
                  r"the band --omega-min \1 --omega-max \2 (rad/s) keeps", text)
    text = text.replace("Widen omega_range to cover the spectrum (the default band does)",
                        "Widen --omega-min/--omega-max to cover the spectrum (without them the "
                        "default band, 0.5 to 5 times the peak frequency, does)")
    # a run too large for the memory (mfm.runner.checks.refuse_impossible)
    if hasattr(args, "duration") and hasattr(args, "dt"):
        text = re.sub(r"^duration: ", f"--duration {args.duration:g} s at --dt {args.dt:g} s: ", text)
    text = re.sub(r"keep fewer samples \(save_every=k keeps every k-th\), split it into runs from "
                  r"the last state \(q0=, qd0=, t0=\), or record fewer outputs "
                  r"\(simulate_batch\(outputs=\.\.\.\)\)",
                  "keep fewer samples (--save-every K keeps every K-th), or take a longer time "
                  "step (--dt)", text)
    # what is left: a Python argument by its option, where the command has it
    if args is not None:
        if hasattr(args, "omega_min"):
            text = re.sub(r"(?<![\w.])omega_range\b(=\([^)]*\))?", "--omega-min/--omega-max", text)
        for name, flag, dest in _PYTHON_NAMES:
            if hasattr(args, dest):
                text = re.sub(rf"(?<![\w.-]){name}=(['\"]?)([^\s,;)'\"]*)\1",
                              lambda m, flag=flag: f"{flag} {m[2]}" if m[2] else flag, text)
    return text


def cli_warning(message, args=None) -> str:
    """A warning as the command line prints it: ``mfm: warning: <message>``, one line (no Python
    category, source file or line), its Python names as options (:func:`cli_text`)."""
    return "mfm: warning: " + " ".join(cli_text(message, args).split())


def say(line: str):
    """Print one line on stderr, on a line of its own where a progress bar (tqdm) is drawn there:
    the bar is cleared, the line written, the bar drawn again below it."""
    try:
        from tqdm import tqdm
    except ImportError:
        print(line, file=sys.stderr, flush=True)
    else:
        tqdm.write(line, file=sys.stderr)
        sys.stderr.flush()


def format_warnings(args):
    """A ``warnings.formatwarning`` that writes each warning as :func:`cli_warning` (and a
    newline). Python's own printing writes it; a recorder (``warnings.catch_warnings(record=True)``,
    ``pytest.warns``) still gets the warning itself."""
    def fmt(message, category, filename, lineno, line=None):
        return cli_warning(message, args) + "\n"
    return fmt


LENGTH_SUFFIXES = ("surge", "sway", "heave", "stroke")

def _unit(coordinate: str) -> str:
    """SI unit of a coordinate from its name: root surge/sway/heave and prismatic strokes are
    lengths, everything else (roll, pitch, yaw, revolute angles) angles."""
    return "m" if coordinate.rsplit(".", 1)[-1] in LENGTH_SUFFIXES else "rad"


def _writable(path, what="--out", suffixes=(".nc",)) -> Path:
    """Check an output path before the run: its suffix, and that its folder can be made and
    written to. A path that cannot be written costs the whole run otherwise."""
    path = Path(path)
    if suffixes and path.suffix not in suffixes:
        raise ValueError(f"{what} {str(path)!r}: give a file ending in {' or '.join(suffixes)}")
    if path.is_dir():
        raise ValueError(f"{what} {str(path)!r} is a directory; give a file name, e.g. "
                         f"{path / ('run' + suffixes[0])}")
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
    except OSError as e:
        raise ValueError(f"{what} {str(path)!r}: cannot create its folder ({e.strerror}); choose "
                         "another path") from None
    existed = path.exists()
    try:
        with open(path, "ab"):
            pass
    except OSError as e:
        raise ValueError(f"{what} {str(path)!r} is not writable ({e.strerror}); choose another "
                         "path or fix the permissions") from None
    if not existed:
        path.unlink()
    return path


def _pairs(items, what):
    out = {}
    for item in items or []:
        if "=" not in item:
            raise UsageError(f"{what} {item!r}: expected NAME=VALUE, e.g. float3.angle=0.1")
        k, v = item.split("=", 1)
        try:
            out[k.strip()] = float(v)
        except ValueError:
            raise UsageError(f"{what} {item!r}: {v!r} is not a number") from None
    return out


def cmd_info(args):
    import numpy as np


    options, _ = load_config(args.config)
    wet = "hydro" in options and not args.no_hydro
    model = load(args.config, hydro=wet, progress=getattr(args, "progress", False))
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
            extra += f" point {np.round(j.point, 4).tolist()} m"
        print(f"  {'  ' * depth}{b.name}  [{j.kind}{extra}]  mass {b.mass:g} kg, "
              f"CoM {np.round(b.com, 4).tolist()} m")
        for c in children.get(b.name, []):
            show(c, depth + 1)

    for root in children[None]:
        show(root, 0)
    print("\ncoordinates:")
    for k, c in enumerate(model.coordinates):
        u = _unit(c)
        loads = []
        if float(model.stiffness[k]):
            loads.append(f"spring {float(model.stiffness[k]):g} N{' m' if u == 'rad' else ''}/{u}")
        if float(model.damping[k]):
            loads.append(f"damper {float(model.damping[k]):g} N{' m' if u == 'rad' else ''} s/{u}")
        print(f"  q[{k}] {c} [{u}]" + (f"  ({', '.join(loads)})" if loads else ""))
    print(f"\ntotal mass {float(model.mass.sum()):g} kg")
    if wet and model.hydro is not None:
        from hydro.database import known_data_issues

        print(f"\nhydro database {model.hydro.source}")
        if model.hydro.stored_in is not None:
            from hydro import fitstore

            kinds = list(fitstore.stored(model.hydro.stored_in).values())
            tables = f", {kinds.count('table')} mooring table(s)" if "table" in kinds else ""
            print(f"  stores {kinds.count('fit')} radiation fit(s) and {kinds.count('value')} "
                  f"value(s) made from it{tables} (`mfm fits`)" if kinds else
                  "  stores no radiation fit (`mfm fits` stores the config's)")
        spec = model.hydro
        for k, name in enumerate(spec.db_names):
            # what the database floats, beside what the config's body weighs (a mesh placed at
            # the wrong draft, or a database made for another body, shows here first)
            b = model.bodies[int(spec.body_index[k])]
            cob = np.asarray(spec.db["center_of_buoyancy"].values[k], dtype=float)
            print(f"  {name}: displaced volume {spec.volume[k]:.6g} m³ (ρV {spec.rho * spec.volume[k]:.6g}"
                  f" kg against the body's mass {b.mass:.6g} kg), centre of buoyancy "
                  f"{np.round(cob, 4).tolist()} m against its CoM {np.round(b.com, 4).tolist()} m")
        if "mean_drift" in spec.db:
            md = spec.db["mean_drift"].attrs
            use = getattr(spec, "drift", "off")
            print(f"  mean wave drift: {md.get('method', '?')}, motions {md.get('motions', '?')}, "
                  f"dofs {md.get('dofs', '?')}; " + (f"applied ([hydro] drift = {use!r})"
                                                    if use != "off" else "not applied ([hydro] "
                                                    "drift = \"mean\" or \"newman\" would)"))
        if "kochin_radiation" in spec.db:
            print(f"  Kochin functions of the layout on {spec.db.sizes['theta']} directions: "
                  "mfm.equilibrium(model, sea=...) takes the far-field drift of the model's own "
                  "motions (mfm.frequency.drift.model_mean_drift)")
        issues = known_data_issues(model.hydro.source)
        print("  known data issues (not warned at load; every computation uses the symmetric "
              "part of A, B, A∞):" if issues else "  no known data issues")
        for line in issues:
            print("    " + line)
    if args.no_restoring:
        return

    print("\nrestoring at q0 = 0, where `mfm simulate` starts without --initial (" +
          ("with the water" if wet else "mechanics only: no [hydro] table" if "hydro" not in options
           else "mechanics only (--no-hydro)") + "):", flush=True)
    print("  " + _restoring_text(", ".join(no_restoring(model))))


def _sea(args, command="simulate"):
    import numpy as np

    import hydro

    band = [(f"--omega-{e}", getattr(args, f"omega_{e}", None)) for e in ("min", "max")]
    band_given = [flag for flag, v in band if v is not None]
    if args.wave is None:
        for flag in ("height", "period", "hs", "tp"):
            if getattr(args, flag) is not None:
                raise UsageError(f"--{flag} needs --wave regular or --wave jonswap")
        if band_given:
            raise UsageError(f"{band_given[0]} sets the band of --wave jonswap; give the sea")
        return None
    deg = args.heading
    if abs(deg) > 360.0:
        # a heading beyond a turn: the same direction as its remainder; said here in degrees
        # (hydro's own warning is in radians and names Python's math.radians)
        deg = math.fmod(deg, 360.0)
        warnings.warn(f"--heading {args.heading:g}° is beyond ±360°: taken as {deg:g}° (the same "
                      "direction; --heading is in degrees, 0 = waves travelling towards +x)",
                      UserWarning, stacklevel=2)
    heading = float(np.deg2rad(deg))
    if args.wave == "regular":
        if band_given:
            raise UsageError(f"{band_given[0]} sets the band of --wave jonswap, not of a regular "
                             "wave (one frequency: 2π/--period)")
        if args.height is None or args.period is None:
            raise UsageError("--wave regular needs --height (m) and --period (s)")
        return hydro.Regular(height=args.height, period=args.period, heading=heading)
    if args.hs is None or args.tp is None:
        raise UsageError("--wave jonswap needs --hs (m) and --tp (s)")
    kw = {}
    if args.components is not None:
        kw["n_components"] = args.components
    if band_given:
        # one end given: the other is the default band's (hydro.waves.DEFAULT_BAND × ωp)
        from hydro.waves import DEFAULT_BAND

        wp = 2.0 * math.pi / args.tp
        lo = band[0][1] if band[0][1] is not None else DEFAULT_BAND[0] * wp
        hi = band[1][1] if band[1][1] is not None else DEFAULT_BAND[1] * wp
        if not lo < hi:
            raise UsageError(f"the band --omega-min {lo:.6g} to --omega-max {hi:.6g} rad/s is "
                             "empty; give --omega-min < --omega-max"
                             + ("" if len(band_given) == 2 else
                                f" (without --omega-max the band ends at {DEFAULT_BAND[1]:g} × "
                                f"the peak frequency, {hi:.4g} rad/s for --tp {args.tp:g} s)"
                                if band[1][1] is None else
                                f" (without --omega-min the band starts at {DEFAULT_BAND[0]:g} × "
                                f"the peak frequency, {lo:.4g} rad/s for --tp {args.tp:g} s)"))
        kw["omega_range"] = (lo, hi)
    return hydro.Jonswap(hs=args.hs, tp=args.tp, gamma=args.gamma, seed=args.seed, heading=heading,
                         **kw)


def _save_result(ds, out):
    """Write a result to ``out`` (:func:`mfm.results.save_netcdf`: whole or not at all; a partial
    run never over a complete file, but beside it). Returns (the path written or None, the
    :class:`mfm.results.ResultNotSaved` to raise once the summary is printed, or None); a failed
    write is said on stderr at once, with where the result went."""
    def say(text):
        print(f"mfm: {text}", file=sys.stderr)
    try:
        return results.save_netcdf(ds, out, announce=say), None
    except results.ResultNotSaved as e:
        say(str(e))
        return e.saved, e


def cmd_simulate(args):
    out = _writable(args.out)              # before the run, not after it
    png = out.with_suffix(".png")
    if not args.no_plot:
        _writable(png, "the figure beside --out", (".png",))
    if args.ramp > args.duration:
        raise ValueError(f"--ramp {args.ramp:g} s is longer than --duration {args.duration:g} s: "
                         "the waves would never reach full height; shorten the ramp")

    # the run's bar options for the load too: seconds of MoorPy tables where the cache is empty
    model = load(args.config, body_coupling=False if args.no_body_coupling else None,
                 progress=args.progress)
    sea = _sea(args)

    command = "mfm " + " ".join(sys.argv[1:]) if sys.argv[1:] else "mfm simulate"
    t0 = time.perf_counter()
    try:
        ds = simulate(model, sea, duration=args.duration, dt=args.dt, integrator=args.integrator,
                          q0=_pairs(args.initial, "--initial"),
                          qd0=_pairs(args.initial_velocity, "--initial-velocity"),
                          save_every=args.save_every, ramp=args.ramp, radiation=args.radiation,
                          progress=args.progress,
                          compile="fast" if getattr(args, "fast_compile", False) else "default")
    except SimulationError as e:
        # keep what was computed: the run up to the last finite sample, marked incomplete
        if e.dataset is not None:
            results.with_command(e.dataset, command)
            written, failed = _save_result(e.dataset, out)     # never over a complete file
            if written is not None:
                print(f"mfm simulate: the run stopped; the {e.dataset.time.size} samples up to "
                      f"t = {float(e.dataset.time[-1]):g} s are in {written} (attribute complete "
                      "= false)", file=sys.stderr)
        raise
    wall = time.perf_counter() - t0
    ds = results.with_command(ds, command)
    written, failed = _save_result(ds, out)
    n = int(round(args.duration / args.dt))
    print(f"{model.name}: {n} steps of {args.dt:g} s with {args.integrator} in {wall:.2f} s "
          f"(including compilation) -> {written or 'nowhere (not saved)'}")
    half = ds.isel(time=slice(len(ds.time) // 2, None))
    t_half = float(half.time[0])
    print(f"  over the second half (t ≥ {t_half:g} s):")
    for c in model.coordinates:
        q = half.q.sel(coordinate=c)
        u = _unit(c)
        print(f"  {c:>24s}: std {float(q.std()):.5g} {u}, mean {float(q.mean()):+.5g} {u}, "
              f"last {float(q[-1]):+.5g} {u}")
    if "pto_power" in ds:
        for p in ds.pto.values:
            print(f"  mean power of {p}: {float(half.pto_power.sel(pto=p).mean()):.6g} W")
        if ds.sizes["pto"] > 1:
            print(f"  mean power of all {ds.sizes['pto']} PTOs: "
                  f"{float(half.pto_power.sum('pto').mean()):.6g} W")
    print("  " + _restoring_text(ds.attrs.get("no_restoring", "not checked")))
    if sea is None and _at_rest(ds):
        print("  " + _at_rest_text(model, args))
    if failed is not None:
        raise failed                 # the summary is above; the file is where the error says
    if not args.no_plot:
        from .plotting import save_result_plot

        save_result_plot(ds, png, sea=sea)
        print(f"  figure -> {png}")


def _bounds(items, model):
    """``--param NAME[=LO:HI]`` items as optimize's parameters: name (or a tuple of names,
    comma-separated: one shared value) → (lower, upper); NAME alone spans half to twice the
    model's value (a positive one: a damping, a mass, a stiffness of the config)."""
    from ..studies.design import _targets, _unknown, _value_of
    from ..frequency.rest import system_loads

    table, static = _targets(model, system_loads(model))
    out = {}
    for item in items:
        key, sep, span = item.partition("=")
        names = tuple(n.strip() for n in key.split(","))
        for n in names:
            if n not in table:
                raise KeyError(f"--param {item!r}: " + _unknown(n, table))
        if sep:
            lo, colon, hi = span.partition(":")
            try:
                bounds = (float(lo), float(hi))
            except ValueError:
                raise ValueError(f"--param {item!r}: {span!r} is not LO:HI (two numbers, e.g. "
                                 f"{names[0]}=0:30)") from None
            if not colon:
                raise ValueError(f"--param {item!r}: give the bounds as LO:HI, e.g. {names[0]}=0:30")
        else:
            v = _value_of(model, static, table[names[0]][0])
            if not v > 0:
                raise ValueError(f"--param {item!r}: the model's value is {v:g}, so half to twice "
                                 f"it is no span; give bounds, e.g. {names[0]}=LO:HI")
            bounds = (0.5 * v, 2.0 * v)
        out[names[0] if len(names) == 1 else names] = bounds
    return out


def _constraints(items):
    """``--constraint QUANTITY.KIND=LIMIT`` items as optimize's constraints."""
    out = {}
    for item in items or []:
        key, sep, lim = item.partition("=")
        quantity, dot, kind = key.strip().rpartition(".")
        if not sep or not dot:
            raise ValueError(f"--constraint {item!r}: expected QUANTITY.KIND=LIMIT, e.g. "
                             "float1.pitch.rms=0.03 (KIND rms, significant or, of a line's "
                             "tension, peak)")
        try:
            value = float(lim)
        except ValueError:
            raise ValueError(f"--constraint {item!r}: {lim!r} is not a number") from None
        out.setdefault(quantity, {})[kind] = value
    return out


def cmd_optimize(args):
    import numpy as np

    from ..studies.optimize import optimize

    out = _writable(args.out)
    model = load(args.config, progress=getattr(args, "progress", False))
    sea = _sea(args, "optimize")
    parameters = _bounds(args.param, model)
    constraints = _constraints(args.constraint)
    t0 = time.perf_counter()
    ds = optimize(model, sea, parameters, constraints=constraints or None, max_iter=args.max_iter)
    wall = time.perf_counter() - t0
    command = "mfm " + " ".join(sys.argv[1:]) if sys.argv[1:] else "mfm optimize"
    ds = results.with_command(ds, command)
    results.save_netcdf(ds, out)           # whole, or an error naming where it went
    print(f"{model.name}: optimum of the mean absorbed power in {sea!r} in {wall:.1f} s "
          f"({int(ds.iterations)} iterations, including compilation) -> {out}")
    for k, name in enumerate(ds.parameter.values):
        bound = str(ds.at_bound.values[k])
        value = float(ds.optimum[k])
        if bound in ("lower", "upper"):
            # at its bound the optimiser's value is the bound to round-off (1.66533e-15 for 0)
            value = float(ds[bound][k])
        off = bound == "lower" and value == 0.0 and "damping" in str(name)
        print(f"  {name:>32s}: {value:.6g} {ds.parameter_unit.values[k]} (model's "
              f"{float(ds.baseline[k]):.6g}; bounds {float(ds.lower[k]):g}:{float(ds.upper[k]):g}"
              + (f", at the {bound} bound" if bound else "")
              + ("; switched off: the device absorbs more without this damper)" if off else ")"))
    gain = (f"gain {float(ds.gain):+.2%}" if float(ds.objective_baseline) else
            "the model's own values absorb nothing")
    print(f"  mean absorbed power {float(ds.objective):.6g} W (model's "
          f"{float(ds.objective_baseline):.6g} W): {gain}")
    for k, c in enumerate(ds.constraint.values):
        state = "active" if bool(ds.constraint_active[k]) else "inactive"
        print(f"  {c}: {float(ds.constraint_value[k]):.6g} ≤ {float(ds.constraint_limit[k]):.6g} "
              f"({state}; model's {float(ds.constraint_value_baseline[k]):.6g})")
    if ds.sizes["constraint"] and not np.any(ds.constraint_active.values):
        print("  no constraint active at the optimum")


# a run whose every coordinate and rate stays within this of zero (m, rad, m/s, rad/s) stayed at
# rest: float64 round-off about an exact equilibrium is ~1e-16, the smallest motion a user asks
# for (a mm, a mrad) is ~1e-3
AT_REST = 1e-9


def _at_rest(ds) -> bool:
    """Whether a run never left its start at rest (q and q̇ within :data:`AT_REST` of zero)."""
    import numpy as np

    return bool(np.nanmax(np.abs(ds.q.values), initial=0.0) < AT_REST
                and np.nanmax(np.abs(ds.qd.values), initial=0.0) < AT_REST)


def _at_rest_text(model, args) -> str:
    """Why a still-water run printed zeros, and the option that makes it move."""
    given = "--initial/--initial-velocity of 0" if (args.initial or args.initial_velocity) else \
        "no --initial or --initial-velocity"
    c = model.coordinates[0]
    return (f"the run stayed at rest (every coordinate within {AT_REST:g} of 0): still water, "
            f"{given}, and q0 = 0 is an equilibrium of this config; start it away from rest, "
            f"e.g. --initial {c}=0.5 ({_unit(c)}), or give a sea (--wave)")


def _restoring_text(no_restoring: str) -> str:
    """The line on free drift of ``mfm info`` and of the ``mfm simulate`` summary, from the
    coordinates :func:`mfm.frequency.rest.no_restoring` names (comma-separated, as in a result's
    ``no_restoring`` attribute)."""
    if no_restoring == "not checked":
        return "restoring not checked (check_stability=False)"
    if not no_restoring:
        return "every coordinate has restoring (at q0)"
    one = "," not in no_restoring
    it, they = ("it", "it drifts") if one else ("them", "they drift")
    return (f"no restoring in {no_restoring} (at q0): nothing pulls {it} back, so {they} after the "
            f"start-up transient (wave drift, any mean load) and a run's mean and last values of "
            f"{it} are that drift, not an offset; add a mooring ([[moorings]]) or a joint spring "
            f"if {it} must stay bounded")


def _peak_text(omega, a, unit):
    """The largest |RAO| and where, or that there is no peak inside the grid: a maximum at
    the first or last frequency is where the grid stops, not a resonance."""
    import numpy as np

    k = int(np.argmax(a))
    if k == 0 or k == len(a) - 1:
        edge = "lowest" if k == 0 else "highest"
        return (f"no peak inside the grid (largest |RAO| {a[k]:.4g} {unit} at its {edge} "
                f"frequency {omega[k]:.4g} rad/s; widen --omega-min/--omega-max to see more)")
    return f"peak |RAO| {a[k]:.4g} {unit} at {omega[k]:.4g} rad/s (period {2 * np.pi / omega[k]:.4g} s)"


def cmd_rao(args):
    if args.omega_max <= args.omega_min:
        raise ValueError(f"--omega-max {args.omega_max:g} must be > --omega-min {args.omega_min:g} "
                         "(rad/s)")
    out = _writable(args.out)
    import numpy as np

    from hydro.database import split_complex

    model = load(args.config, body_coupling=False if args.no_body_coupling else None,
                 progress=getattr(args, "progress", False))
    omega = np.linspace(args.omega_min, args.omega_max, args.n)
    ds = frequency_response(model, omega, heading=float(np.deg2rad(args.heading)),
                                radiation=args.radiation)
    nat = natural_frequencies(model)
    ds = results.with_natural_frequencies(ds, nat, args.config)
    results.save_netcdf(split_complex(ds), out)     # whole, or an error naming where it went
    print(f"{model.name}: RAOs at {args.n} frequencies {args.omega_min:g}–{args.omega_max:g} rad/s "
          f"-> {out}")
    print(f"  natural frequencies (eigen): {np.round(nat['eigen'].values, 4).tolist()} rad/s")
    print(f"  natural frequencies (min |det|): {np.round(nat['min_det'].values, 4).tolist()} rad/s")
    for c in model.coordinates:
        a = np.abs(ds.rao.sel(coordinate=c).values)
        print(f"  {c:>24s}: {_peak_text(omega, a, _unit(c) + '/m')}")


def cmd_hydro(args):
    """``mfm hydro CONFIG``: solve the config's hulls into its NetCDF database (capytaine).
    ``--format bemio``: write the config's database as a BEMIO HDF5 file (WEC-Sim's and
    SEA-Stack's, :func:`hydro.bemio.write_bemio`) at ``--out`` (default ``out/<config>.h5``): a
    config with ``[hydro.bem]`` gets its NetCDF database made (or kept when up to date) first; any
    other config's database (WAMIT, NEMOH, a .nc, a .h5) is converted as it is read."""
    if getattr(args, "format", "netcdf") != "bemio":
        generate(args.config, out=args.out, force=args.force, n_threads=args.threads)
        return
    from hydro.bemio import solver_code, write_bemio
    from hydro.prepare import open_any_database

    config = Path(args.config)
    out = _writable(args.out or Path("out") / (config.stem + ".h5"), "--out", (".h5",))
    options, _ = load_config(config)
    hydro = options.get("hydro")
    if hydro is None:
        raise ValueError(f"{config}: no [hydro] table, so no database to write as BEMIO; add "
                         "[hydro] database = \"<file>\" (relative to the config)")
    if hydro.get("bem") is not None:
        source = generate(config, force=args.force, n_threads=args.threads)
    else:
        source = Path(hydro["database"])
        source = source if source.is_absolute() else Path(os.path.normpath(config.parent / source))
    db = open_any_database(source, names=hydro.get("names"), rho=hydro.get("rho"), g=hydro.get("g"))
    write_bemio(db, out, code=solver_code(db))
    print(f"mfm hydro: {out}: BEMIO HDF5 of {source} ({db.sizes['body']} bodies, "
          f"{db.sizes['omega']} frequencies, {db.sizes['wave_direction']} headings)")


def cmd_fits(args):
    """Store in each config's database file what its runs make from the database and nothing
    else: the default state-space fit (every ``radiation`` route through a fit uses it), the
    radiation memory T_K and the consistent A∞ (:mod:`hydro.fitstore`); ``--values-only`` those
    two alone (a frequency-domain study fits nothing). Items made before, in this process or the
    disk cache, are taken from there; the rest are made now."""
    import os

    from hydro import fitcache, fitstore

    from ..loads.catenary_tables import table_source

    for config in args.config:
        options, _ = load_config(config)
        if "hydro" not in options:
            raise ValueError(f"{config}: no [hydro] table, so no database to store fits in")
        t0 = time.perf_counter()
        with fitcache.recording() as made:
            # recorded from the load on: it makes the config's mooring tables
            # (mfm.loads.catenary) and may ask for the values below first
            model = load(config, progress=getattr(args, "progress", False))
            spec = model.hydro
            path = spec.stored_in
            if path is None:
                raise ValueError(f"{config}: its database {spec.source!r} is not a NetCDF file "
                                 "(.nc); fits are stored in NetCDF databases only")
            spec.memory()
            spec.added_mass_inf()
            fit = None if args.values_only else spec.state_space()
        items = {key: item for (p, key), item in made.items() if p == path}
        before = os.path.getsize(path)
        kinds = list(fitstore.store(path, items, sources={"table": table_source()}).values())
        this = ("" if fit is None else
                f"; this config's fit: {fit.report['n_states']} states, band error "
                f"{fit.report['overall_error']:.3g}, passive {fit.report['passive']}")
        if fit is not None:
            # the judgement radiation="auto" makes before a run uses the fit (a decay: every
            # mode; mfm.frequency.fitcheck), said here where the fit is stored
            from ..runner.choices import judge_radiation

            verdict = judge_radiation(model)
            this += (f"; {verdict.summary}" + ("" if verdict.ok else
                     " (radiation='auto' takes the convolution for runs that excite it)"))
        tables = f", {kinds.count('table')} mooring table(s)" if "table" in kinds else ""
        print(f"{config}: {os.path.normpath(path)} stores {kinds.count('fit')} fit(s) and "
              f"{kinds.count('value')} value(s){tables}{this}; {time.perf_counter() - t0:.1f} s, "
              f"file {before / 1e6:.2f} -> {os.path.getsize(path) / 1e6:.2f} MB", flush=True)


def cmd_plot(args):
    import matplotlib

    matplotlib.use("Agg")
    src = Path(args.config)
    if src.suffix == ".nc":
        out = _writable(args.out or src.with_suffix(".png"), "--out", (".png",))
        from .plotting import save_result_plot

        if not src.exists():
            raise FileNotFoundError(f"result file {str(src)!r} not found")
        from hydro.checks import check_netcdf_file

        from hydro.database import read_netcdf

        ds = read_netcdf(check_netcdf_file(src))
        kind = save_result_plot(ds, out, dpi=args.dpi)
        print(f"{kind} of {src} -> {out}")
        return
    out = _writable(args.out or Path(src.with_suffix(".png").name), "--out", (".png",))
    from .plotting import plot_layout

    model = load(args.config, hydro=False)
    fig = plot_layout(model)
    fig.savefig(out, dpi=args.dpi)
    print(f"layout of {model.name} -> {out}")


