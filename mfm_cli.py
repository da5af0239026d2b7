"""The ``mfm`` command's entry point: argument parsing, ``--help`` and ``--version``.

It is a top-level module, outside the ``mfm`` package, because importing anything inside ``mfm``
runs ``mfm/__init__``, which imports jax (about 2 s) and switches it to float64 before any
submodule can use it. Here only the standard library is imported, so ``mfm --help``,
``mfm --version`` and a mistyped argument answer at once; :func:`main` imports the commands
(:mod:`mfm.io.cli`) once the arguments are known to be good.
"""
from __future__ import annotations

import argparse
import math
import sys


def _number(kind, *, minimum=None, strict=True, integer=False):
    """argparse type: a finite number (> or ≥ minimum); the error names the value and the range."""
    def parse(text):
        try:
            v = int(text) if integer else float(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"{text!r} is not {'a whole number' if integer else 'a number'}") from None
        if not math.isfinite(v):
            raise argparse.ArgumentTypeError(f"{text!r} is not a finite number")
        if minimum is not None and (v <= minimum if strict else v < minimum):
            raise argparse.ArgumentTypeError(f"{text!r} is out of range; give {kind}")
        return v
    parse.__name__ = kind               # argparse names the type in some messages
    return parse


# the exit status of every usage, config and input error: argparse's own for a bad option, and
# the same for what only the command finds (a config that is not there, a sea outside the
# database's grid, a run too large); mfm.io.cli.EXIT_USAGE is this number
EXIT_USAGE = 2
EPILOG = (f"exit status: 0 done; {EXIT_USAGE} a usage, config or input error, or a run that "
          "cannot be done as asked (a bad option or value, a missing or bad config, a sea outside the database's frequency grid, a run "
          f"too large for the memory, a run gone non-finite): one line 'mfm COMMAND: error: ...' "
          "on stderr, naming the option to change; any other status is a fault of mfm (a "
          "traceback: please report it). Warnings print as one line 'mfm: warning: ...'.")

POSITIVE = _number("a positive number", minimum=0.0)
NONNEGATIVE = _number("a number ≥ 0", minimum=0.0, strict=False)
FINITE = _number("a finite number")


# the bar of `mfm simulate --progress auto`: a short run shows none, a log gets a line a while
PROGRESS_DELAY_TTY, PROGRESS_DELAY_LOG, PROGRESS_INTERVAL_LOG = 2.0, 5.0, 10.0


def progress_option(choice: str, stream=None):
    """``mfm simulate --progress`` as the ``progress`` argument of :func:`mfm.simulate`."""
    if choice == "off":
        return False
    if choice == "on":
        return True
    if choice != "auto":
        raise ValueError(f"--progress {choice!r}; accepted: auto, on, off")
    stream = sys.stderr if stream is None else stream
    if getattr(stream, "isatty", lambda: False)():
        return {"delay": PROGRESS_DELAY_TTY}
    return {"delay": PROGRESS_DELAY_LOG, "mininterval": PROGRESS_INTERVAL_LOG}


def _count(minimum):
    return _number(f"a whole number ≥ {minimum}", minimum=minimum, strict=False, integer=True)


def _version() -> str:
    from importlib.metadata import PackageNotFoundError, version

    def v(pkg):
        try:
            return version(pkg)
        except PackageNotFoundError:
            return "not installed"

    return (f"mfm {v('mfm')} (python {sys.version.split()[0]}, jax {v('jax')}, capytaine "
            f"{v('capytaine')}: the BEM extra, only for `mfm hydro`)")



def _band_options(p):
    """``--omega-min/--omega-max``: the JONSWAP's discretised band (the Python sea's
    ``omega_range``), e.g. to keep it inside the hydro database's frequency grid."""
    p.add_argument("--omega-min", type=POSITIVE, metavar="RAD_S",
                   help="JONSWAP: lowest frequency of the discretised band, rad/s (default 0.5 × "
                   "the peak frequency 2π/Tp); keep the band inside the hydro database's grid")
    p.add_argument("--omega-max", type=POSITIVE, metavar="RAD_S",
                   help="JONSWAP: highest frequency of the band, rad/s (default 5 × the peak "
                   "frequency); a band keeping < 90 %% of the spectrum's variance warns")


def build_parser():
    ap = argparse.ArgumentParser(prog="mfm", description="Floating multi-body systems by the Moving "
                                 "Frame Method. Units are SI (m, rad, s, kg, N, W); headings in "
                                 "degrees on the command line.", epilog=EPILOG)
    ap.add_argument("--version", action="version", version=_version())
    sub = ap.add_subparsers(dest="command", required=True, metavar="COMMAND")
    p = sub.add_parser("info", help="print the tree, coordinates, masses and which coordinates "
                       "have no restoring")
    p.add_argument("config")
    p.add_argument("--no-hydro", action="store_true", help="mechanics only (skip the database)")
    p.add_argument("--no-restoring", action="store_true",
                   help="skip the static-stiffness check (it compiles the model: ~10-30 s)")
    p.set_defaults(func="cmd_info")
    p = sub.add_parser("simulate", help="simulate a config; write the results as NetCDF and a "
                       "figure beside them (PNG)")
    p.add_argument("config")
    p.add_argument("--duration", type=POSITIVE, default=10.0, help="s (default 10)")
    p.add_argument("--dt", type=POSITIVE, default=0.01, help="time step, s (default 0.01)")
    p.add_argument("--integrator", default="rk4", choices=["rk4", "beeman", "semi_implicit", "newmark", "verlet"])
    p.add_argument("--initial", action="append", metavar="NAME=VALUE",
                   help="initial coordinate (m or rad), repeatable, e.g. --initial upper.angle=0.3")
    p.add_argument("--initial-velocity", action="append", metavar="NAME=VALUE",
                   help="initial rate (m/s or rad/s), repeatable")
    p.add_argument("--save-every", type=_count(1), default=1, help="keep every k-th step")
    p.add_argument("--fast-compile", action="store_true",
                   help="compile the run at XLA's lowest optimisation level: a cheaper first "
                        "answer (about a third of the compilation), slower steps, other last bits "
                        "(mfm.simulate's compile='fast')")
    p.add_argument("--wave", choices=["regular", "jonswap"], help="sea state (default: still water)")
    p.add_argument("--height", type=POSITIVE, help="regular wave height H, m")
    p.add_argument("--period", type=POSITIVE, help="regular wave period T, s")
    p.add_argument("--hs", type=POSITIVE, help="JONSWAP significant wave height, m")
    p.add_argument("--tp", type=POSITIVE, help="JONSWAP peak period, s")
    p.add_argument("--gamma", type=_number("a number ≥ 1", minimum=1.0, strict=False), default=3.3,
                   help="JONSWAP peak enhancement (default 3.3)")
    p.add_argument("--seed", type=_count(0), default=0, help="random phases seed (default 0)")
    p.add_argument("--components", type=_count(1), help="number of wave components")
    _band_options(p)
    p.add_argument("--heading", type=FINITE, default=0.0, help="wave heading, degrees (0 = towards +x)")
    p.add_argument("--ramp", type=NONNEGATIVE, default=0.0, help="start-up ramp of the excitation, s")
    p.add_argument("--radiation", default="auto", choices=["auto", "convolution", "state_space", "state_space_exact", "none"])
    p.add_argument("--no-body-coupling", action="store_true",
                   help="drop the hydrodynamic interaction between bodies")
    p.add_argument("--out", default="out/simulation.nc", help="NetCDF output (default out/simulation.nc)")
    p.add_argument("--no-plot", action="store_true",
                   help="do not draw the figure (PNG beside --out: q, PTO power, spectra)")
    p.add_argument("--progress", choices=["auto", "on", "off"], default="auto",
                   help="progress bar on stderr; auto (default): on a terminal once the run has "
                   f"taken {PROGRESS_DELAY_TTY:g} s, elsewhere (a log, a pipe) once it has taken "
                   f"{PROGRESS_DELAY_LOG:g} s, refreshed every {PROGRESS_INTERVAL_LOG:g} s")
    p.set_defaults(func="cmd_simulate")
    p = sub.add_parser("optimize", help="tune PTO, mooring, mass or controller parameters to "
                       "maximise the mean absorbed power in a sea (spectral level, exact "
                       "derivatives); print the optimum, write it as NetCDF")
    p.add_argument("config")
    p.add_argument("--param", action="append", required=True, metavar="NAME[=LO:HI]",
                   help="a tunable parameter and its bounds, repeatable, e.g. "
                   "--param float3.angle.damping=0:30; NAME alone: from half to twice the model's "
                   "value; NAME1,NAME2=LO:HI: one value shared by them. The names: "
                   "mfm.studies.optimize.tunable_parameters(model)")
    p.add_argument("--constraint", action="append", metavar="QUANTITY.KIND=LIMIT",
                   help="a limit to hold, repeatable: KIND rms or significant of a coordinate or a "
                   "PTO stroke (m or rad), or peak of '<line>.tension' (N), e.g. "
                   "--constraint float1.pitch.rms=0.03")
    for flag, kw in (("--wave", dict(choices=["regular", "jonswap"], required=True,
                                     help="sea state")),
                     ("--height", dict(type=POSITIVE, help="regular wave height H, m")),
                     ("--period", dict(type=POSITIVE, help="regular wave period T, s")),
                     ("--hs", dict(type=POSITIVE, help="JONSWAP significant wave height, m")),
                     ("--tp", dict(type=POSITIVE, help="JONSWAP peak period, s")),
                     ("--gamma", dict(type=_number("a number ≥ 1", minimum=1.0, strict=False),
                                      default=3.3, help="JONSWAP peak enhancement (default 3.3)")),
                     ("--seed", dict(type=_count(0), default=0, help="random phases seed")),
                     ("--components", dict(type=_count(1), help="number of wave components")),
                     ("--heading", dict(type=FINITE, default=0.0, help="wave heading, degrees"))):
        p.add_argument(flag, **kw)
    _band_options(p)
    p.add_argument("--max-iter", type=_count(1), default=100, help="SLSQP iterations (default 100)")
    p.add_argument("--out", default="out/optimum.nc", help="NetCDF output (default out/optimum.nc)")
    p.set_defaults(func="cmd_optimize")
    p = sub.add_parser("rao", help="frequency-domain RAOs and natural frequencies (NetCDF)")
    p.add_argument("config")
    p.add_argument("--omega-min", type=POSITIVE, required=True, help="rad/s, > 0")
    p.add_argument("--omega-max", type=POSITIVE, required=True, help="rad/s, > omega-min")
    p.add_argument("--n", type=_count(2), default=100, help="number of frequencies, ≥ 2 (default 100)")
    p.add_argument("--heading", type=FINITE, default=0.0, help="degrees")
    p.add_argument("--radiation", default="database", choices=["database", "convolution", "state_space"])
    p.add_argument("--no-body-coupling", action="store_true")
    p.add_argument("--out", default="out/rao.nc")
    p.set_defaults(func="cmd_rao")
    p = sub.add_parser("hydro", help="generate the config's hydro database with capytaine "
                       "(the 'bem' extra: pip install -e \".[bem]\")")
    p.add_argument("config")
    p.add_argument("--out", help="NetCDF path (default: the config's [hydro] database); with "
                   "--format bemio, the .h5 path (default: out/<config name>.h5)")
    p.add_argument("--format", choices=["netcdf", "bemio"], default="netcdf",
                   help="netcdf (default): the config's database; bemio: also write it as a BEMIO "
                   "HDF5 file for WEC-Sim and SEA-Stack (a config without [hydro.bem] has its "
                   "database, e.g. WAMIT's, converted without a solve)")
    p.add_argument("--force", action="store_true", help="solve again even if up to date")
    p.add_argument("--threads", type=_count(1), help="threads per BEM solve (default: all cores)")
    p.set_defaults(func="cmd_hydro")
    p = sub.add_parser("fits", help="make the radiation fits and values a config's runs use and "
                       "store them in its NetCDF database, so a first run on any machine reads "
                       "them instead of fitting (hydro.fitstore)")
    p.add_argument("config", nargs="+", help="one or more .toml configs with a [hydro] database")
    p.add_argument("--values-only", action="store_true",
                   help="store the radiation memory and the consistent A∞ alone, not the "
                   "state-space fit (what a frequency-domain study uses)")
    p.set_defaults(func="cmd_fits")
    p = sub.add_parser("plot", help="a config's layout (plan and side view), or a result file: "
                       "time series and spectra (simulate), RAOs (rao), mean power per case "
                       "(batch); PNG")
    p.add_argument("config", metavar="CONFIG_OR_RESULT", help="a .toml config or a .nc result")
    p.add_argument("--out", help="PNG file (default: beside a result, or the config's name in the "
                   "current directory)")
    p.add_argument("--dpi", type=_count(10), default=120)
    p.set_defaults(func="cmd_plot")
    for p in sub.choices.values():      # `mfm COMMAND --help` says the exit status too
        p.epilog = EPILOG
    return ap


def main(argv=None):
    """Parse ``argv`` (default: ``sys.argv[1:]``) and run the command; returns the exit code: 0,
    or :data:`EXIT_USAGE` (2) with one ``mfm COMMAND: error: ...`` line for a config, input or
    simulation error. A usage error raises ``SystemExit`` with that code, as argparse's own: a
    bad option (argparse) or an option that needs another (:class:`mfm.io.cli.UsageError`, whose
    ``str()`` is the message). Warnings print as one ``mfm: warning: ...`` line; errors and
    warnings name the command's options, not the Python arguments behind them."""
    args = build_parser().parse_args(argv)
    if getattr(args, "progress", None) is not None:
        args.progress = progress_option(args.progress)     # simulate's progress= argument
    else:
        # a command without --progress still says what a long load does (its MoorPy tables:
        # seconds where the cache is empty), as --progress auto would
        args.progress = progress_option("auto")
    import warnings

    from mfm.io import cli   # the commands, and with them mfm and jax: only now that there is work
    from mfm.runner import collector as _gc

    # the command owns its process: the libraries' objects out of the collector's walks now, and
    # the command's at its exit (mfm/runner/collector.py)
    _gc.freeze()
    _gc.freeze_at_exit()

    formatwarning = warnings.formatwarning
    warnings.formatwarning = cli.format_warnings(args)    # one line, no source path
    try:
        try:
            getattr(cli, args.func)(args)
        except cli.UsageError as e:     # exit status EXIT_USAGE, as argparse's
            cli.say(f"mfm {args.command}: error: {cli.cli_text(e, args)}")
            raise
        except SystemExit as e:         # a command's own exit with a message: a usage error too
            if e.code is None or isinstance(e.code, int):
                raise
            text = str(e.code).removeprefix("mfm: ")
            cli.say(f"mfm {args.command}: error: {cli.cli_text(text, args)}")
            raise cli.UsageError(text) from None
        except Exception as e:  # config and simulation errors: one clear line, exit EXIT_USAGE
            from mfm import ConfigError, SimulationError

            if isinstance(e, (ConfigError, SimulationError, ValueError, KeyError, OSError,
                              ImportError)):
                msg = e.args[0] if isinstance(e, KeyError) and e.args else e
                cli.say(f"mfm {args.command}: error: {cli.cli_text(msg, args)}")
                return EXIT_USAGE
            raise
    finally:
        warnings.formatwarning = formatwarning
    return 0


if __name__ == "__main__":
    sys.exit(main())
