"""Bit-for-bit check of a change: every shipped config run briefly in two trees and compared.

Results identical to the bit before and after each step of a change (a restructuring): every
shipped config (``configs/*.toml``, not ``configs/sensitivity/``) run briefly in two trees, each
result saved as NetCDF, every variable, coordinate and attribute compared.

What runs (the probe, one Python subprocess per tree, ``PYTHONPATH`` and working directory the
tree, so each tree runs its own ``mfm`` and ``hydro``), for each config, each call in try/except (a
failure is recorded as its error string and the others go on):

* ``m = mfm.load(config)``;
* with water (``m.hydro is not None``): the wave period T = 2π/ω_c, ω_c = √(g/L) the Froude
  frequency of the database's largest displaced volume (L its cube root; clipped to the database's
  ω range): ~1 s for the M4 lab models, 6–8 s at full scale;
  ``simulate``: ``mfm.simulate(m, hydro.Regular(height=0.02 T², period=T), duration=20 dt,
  dt=T/40, ramp=5 dt, radiation="convolution", memory=T/2)`` (20 RK4 steps);
  ``frequency_response``: ``mfm.frequency_response(m, ω)``, ω 3 frequencies geometrically spaced
  over [0.7 ω_c, 1.4 ω_c] ∩ the database's range;
  ``simulate_chunked``: the ``simulate`` call (the convolution) with a progress bar (drawn nowhere),
  the command line's path: the run in chunks, their own start and programs;
  for rm3 and m4_111 also ``simulate_state_space`` (the same run with ``radiation="state_space"``
  and no ``memory``)
  and ``frequency_response_state_space`` (``radiation="state_space"``);
* without water (double_pendulum): ``simulate``: ``mfm.simulate(m, None, duration=0.5, dt=0.01,
  q0=0.5 rad on every coordinate)`` (50 RK4 steps).

Each dataset goes to ``<dir>/<config>.<call>.nc`` (``<config>.load.nc``: the model's coordinates,
as attributes) and ``<dir>/summary.json`` holds per call its file, seconds, error (null or
"Type: message", with its traceback) and warnings (shown beside the comparison where they differ,
not counted as a difference: hydro says some only once a process). The probe's environment:
``XLA_FLAGS="--xla_backend_optimization_level=0 --xla_llvm_disable_expensive_passes=true"`` (fast
compiles; both trees get the same flags, so the bits are comparable, but they are not the bits of
a default run; ``--xla-flags ''`` runs at XLA's defaults, where a change to compile options
shows), jax's and mfm's caches off (``MFM_COMPILATION_CACHE=off``, ``MFM_FIT_CACHE=off``,
``XDG_CACHE_HOME`` a fresh temporary folder, ``JAX_COMPILATION_CACHE_DIR`` removed),
``JAX_PLATFORMS=cpu``, ``PYTHONHASHSEED=0``.

What is compared, per config and call: the set of data variables and of coordinates, and for each
its dims, shape, dtype and values, exactly by default: the same bits (so -0.0 ≠ 0.0), every NaN
equal to a NaN at the same place; with ``--rtol r``: NaN at the same places and
max |new − ref| ≤ r · max |ref| per variable (strings and integers always exactly). Attributes of
the dataset and of every variable are compared too (numbers under the same rule), except:

* excluded by name (:func:`excluded`): provenance that legitimately changes between commits,
  trees or runs: ``git_commit`` (the commit, "+dirty" for uncommitted work), ``created`` (the time
  of the run), ``mfm_version`` and every ``*_version`` (jax, numpy, xarray, MoorPy: the
  environment, not the code), measured durations (``*_seconds``: the state-space fit's
  ``fit_fit_seconds``; any ``*wall*``: wall-clock times), and the file paths ``config``,
  ``database``, ``source`` (as given, relative to the working directory; what they name is checked
  by ``config_sha256`` and ``database_sha256``, which are compared);
* masked inside every other string attribute (:func:`normalise`): file paths (``a/b/c.ext``:
  e.g. ``wind_*_ct_source`` names the bundled table under the tree's ``mfm/data/``), dotted module
  paths ``mfm.x.y`` (a class repr that names its module moves with it) and object addresses
  (``0x7f…``), each replaced by a placeholder, so the rest of the string is still compared.

A config or call that fails in one tree and not in the other is a difference; one that fails in
both with the same (masked) error string is shown as "same error" and is not.

Runtime (this 2-core machine, measured at 7ace823): the probe takes 8–11 minutes per tree (494 s
on a quiet machine, 626 and 667 s with the test suite and another probe running beside it; 18
configs, 57 calls; the six Wu & Yuan configs with 18 coordinates 34–53 s each (to 72 s loaded),
the others 2–35 s; ``--only`` runs a few), the comparison a few seconds. With the chunked
calls (2026-11-29: 21 configs, 87 calls) a whole check against HEAD took ~14 minutes on the
quiet machine. So a check against a
commit takes ~15–22 minutes, one against a saved reference (``--reference``) half that; the
datasets take 3 MB. A saved reference compares only under the same environment and machine (the
jax/XLA versions, the flags and the CPU decide the bits).

Usage (from the repository root, with mfm installed; the script does not touch sys.path):

    python tools/regression_check.py                        # this tree (uncommitted work included)
                                                            # against HEAD, in a temporary worktree
    python tools/regression_check.py --commit REV           # against another commit
    python tools/regression_check.py --write DIR            # only this tree's datasets, into DIR
    python tools/regression_check.py --reference DIR        # this tree against datasets saved
                                                            # before (one reference, many steps)
    options: --rtol R (default 0: bitwise), --keep DIR (keep both trees' datasets under
    DIR/reference and DIR/current), --only NAME [NAME ...] (config stems, e.g. rm3 m4_134)

Prints a table (config/call, variables compared, largest |difference| and relative to the largest
|reference|, status) and a final line; exits 1 on any difference (or, with --write, on any failed
call), 0 otherwise.
"""
from __future__ import annotations

import argparse
import json
import math
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent

XLA_FLAGS = "--xla_backend_optimization_level=0 --xla_llvm_disable_expensive_passes=true"

# provenance attributes not compared (see the module docstring): they change with the commit, the
# time, the environment, the machine's load or where the tree lies, not with what the code computes
EXCLUDED_ATTRS = {"git_commit", "created", "mfm_version", "config", "database", "source"}
EXCLUDED_SUFFIXES = ("_version", "_seconds")      # versions; measured durations (fit_fit_seconds)
EXCLUDED_SUBSTRINGS = ("wall",)                   # wall-clock times (wall_time_s, sweep_wall_s)

# configs that also run the state-space radiation (simulate and frequency_response)
STATE_SPACE_CONFIGS = ("rm3", "m4_111")

PROBE = r'''
import json, math, os, sys, time, traceback, warnings
from pathlib import Path

import numpy as np

import hydro
import mfm

out = Path(sys.argv[1])
out.mkdir(parents=True, exist_ok=True)
state_space_configs = set(sys.argv[2].split(","))
configs = sys.argv[3:]
summary = {"tree": os.getcwd(), "xla_flags": os.environ.get("XLA_FLAGS", ""), "calls": {}}
# a bar drawn nowhere: the run in chunks, as the command line makes it
BAR = {"file": open(os.devnull, "w")}


def record(key, fn):
    """Run fn() (returning a Dataset), save it as <key>.nc; the outcome into summary["calls"]."""
    entry = {"file": None, "seconds": None, "error": None, "warnings": []}
    t = time.perf_counter()
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            ds = fn()
            ds.to_netcdf(out / f"{key}.nc", engine="netcdf4", auto_complex=True)
            entry["file"] = f"{key}.nc"
        except Exception as e:
            entry["error"] = f"{type(e).__name__}: {e}"
            entry["traceback"] = traceback.format_exc()
    entry["seconds"] = round(time.perf_counter() - t, 3)
    entry["warnings"] = sorted({f"{w.category.__name__}: {w.message}" for w in caught})
    summary["calls"][key] = entry
    (out / "summary.json").write_text(json.dumps(summary, indent=1))
    print(f"  {key:45s} {entry['seconds']:7.1f} s" + (f"  FAILED {entry['error']}" if entry["error"]
          else ""), flush=True)
    return entry


t_all = time.perf_counter()
for path in configs:
    name = Path(path).stem
    model = {}

    def load():
        model["m"] = mfm.load(path)
        import xarray as xr
        return xr.Dataset(attrs={"n_coordinates": model["m"].n_coordinates,
                                 "coordinates": ", ".join(model["m"].coordinates),
                                 "has_water": str(model["m"].hydro is not None)})

    if record(f"{name}.load", load)["error"]:
        continue
    m = model["m"]
    if m.hydro is None:
        record(f"{name}.simulate", lambda: mfm.simulate(
            m, None, duration=0.5, dt=0.01, q0=np.full(m.n_coordinates, 0.5)))
        record(f"{name}.simulate_chunked", lambda: mfm.simulate(
            m, None, duration=0.5, dt=0.01, q0=np.full(m.n_coordinates, 0.5), progress=BAR))
        continue
    om = np.asarray(m.hydro.db["omega"].values, dtype=float)
    wc = math.sqrt(m.hydro.g / float(np.max(m.hydro.volume)) ** (1.0 / 3.0))
    wc = min(max(wc, float(om[0])), float(om[-1]))
    T = 2.0 * math.pi / wc
    dt = T / 40.0
    sea = hydro.Regular(height=0.02 * T**2, period=T)
    omega = np.geomspace(max(0.7 * wc, float(om[0])), min(1.4 * wc, float(om[-1])), 3)
    radiations = ["convolution"] + (["state_space"] if name in state_space_configs else [])
    for rad in radiations:
        suffix = "" if rad == "convolution" else "_" + rad
        # a memory length for the convolution only (a state space has none: mfm refuses one
        # given to it since 61f6a6d's strategies, where it ignored it before)
        record(f"{name}.simulate{suffix}", lambda: mfm.simulate(
            m, sea, duration=20 * dt, dt=dt, ramp=5 * dt, radiation=rad,
            memory=T / 2 if rad == "convolution" else None))
    # the command line's path: a progress bar, the run in chunks (their own start and programs)
    record(f"{name}.simulate_chunked", lambda: mfm.simulate(
        m, sea, duration=20 * dt, dt=dt, ramp=5 * dt, radiation="convolution", memory=T / 2,
        progress=BAR))
    record(f"{name}.frequency_response", lambda: mfm.frequency_response(m, omega))
    if name in state_space_configs:
        record(f"{name}.frequency_response_state_space",
               lambda: mfm.frequency_response(m, omega, radiation="state_space"))
summary["seconds"] = round(time.perf_counter() - t_all, 1)
(out / "summary.json").write_text(json.dumps(summary, indent=1))
'''


# ------------------------------------------------------------------------------- running
def configs(only=None) -> list[str]:
    """The shipped configs (relative paths, as the probe runs them from a tree's root)."""
    found = sorted(p.relative_to(ROOT).as_posix() for p in (ROOT / "configs").glob("*.toml"))
    if only:
        missing = sorted(set(only) - {Path(p).stem for p in found})
        if missing:
            raise SystemExit(f"--only: no configs/{{{','.join(missing)}}}.toml")
        found = [p for p in found if Path(p).stem in only]
    return found


def probe(tree: Path, out: Path, paths: list[str], flags: str = XLA_FLAGS) -> dict:
    """Run the probe in ``tree`` (its own mfm), datasets and summary.json into ``out``, with
    ``XLA_FLAGS`` = ``flags``."""
    out.mkdir(parents=True, exist_ok=True)
    print(f"running {len(paths)} configs in {tree} → {out}", flush=True)
    t = time.perf_counter()
    with tempfile.TemporaryDirectory(prefix="regression-cache-") as cache:
        env = dict(os.environ, PYTHONPATH=str(tree), XLA_FLAGS=flags, JAX_PLATFORMS="cpu",
                   MFM_COMPILATION_CACHE="off", MFM_FIT_CACHE="off", XDG_CACHE_HOME=cache,
                   MFM_BEM_CACHE=str(Path(cache) / "bem"), PYTHONHASHSEED="0")
        env.pop("JAX_COMPILATION_CACHE_DIR", None)
        proc = subprocess.run([sys.executable, "-c", PROBE, str(out), ",".join(STATE_SPACE_CONFIGS),
                               *paths], cwd=tree, env=env, check=False)
    print(f"probe of {tree}: {time.perf_counter() - t:.0f} s, exit status {proc.returncode}",
          flush=True)
    return read_summary(out)


def read_summary(folder: Path) -> dict:
    f = folder / "summary.json"
    if not f.is_file():
        return {"calls": {}}
    return json.loads(f.read_text())


def probe_commit(rev: str, out: Path, paths: list[str], flags: str = XLA_FLAGS) -> dict:
    """The probe in a temporary detached worktree of ``rev`` (removed afterwards)."""
    with tempfile.TemporaryDirectory(prefix="regression-tree-") as tmp:
        tree = Path(tmp) / "tree"
        subprocess.run(["git", "-C", str(ROOT), "worktree", "add", "--detach", str(tree), rev],
                       check=True, capture_output=True)
        try:
            return probe(tree, out, paths, flags)
        finally:
            subprocess.run(["git", "-C", str(ROOT), "worktree", "remove", "--force", str(tree)],
                           capture_output=True, check=False)


# ------------------------------------------------------------------------------- comparing
# a file path: a token with a slash and a file extension (configs/../hydro/data/rm3.nc), or an
# absolute one of two segments or more (/work/tree/mfm/data); units such as m/s2 or W/m2 are kept
_PATH = re.compile(r"(?<![\w/])(?:~|\.{1,2})?/?(?:[\w.+-]+/)+[\w+-]+\.[A-Za-z]\w*"
                   r"|(?<![\w/])~?/[\w.+-]+(?:/[\w.+-]+)+")
_MODULE = re.compile(r"\bmfm(?:\.[A-Za-z_]\w*)+")
_ADDRESS = re.compile(r"\b0x[0-9a-fA-F]+\b")


def normalise(s: str) -> str:
    """A string attribute (or error message) with file paths, mfm module paths and object
    addresses replaced by placeholders."""
    s = _ADDRESS.sub("0x…", s)
    s = _PATH.sub("<path>", s)
    return _MODULE.sub("mfm.<module>", s)


def excluded(name: str) -> bool:
    """Whether the attribute ``name`` is left out of the comparison."""
    return (name in EXCLUDED_ATTRS or name.endswith(EXCLUDED_SUFFIXES)
            or any(s in name for s in EXCLUDED_SUBSTRINGS))


def value_difference(a, b, rtol: float):
    """(same?, largest |b − a|, that over max |a|) of two arrays. Floats (complex: their real and
    imaginary parts) need NaN at the same places and, elsewhere, with ``rtol`` 0 the same bits,
    else max |b − a| ≤ rtol · max |a|; other kinds equality. A difference in dtype, shape or NaN
    places is (False, inf, inf)."""
    import numpy as np

    a, b = np.ascontiguousarray(a), np.ascontiguousarray(b)
    if a.shape != b.shape or a.dtype != b.dtype:
        return False, math.inf, math.inf
    if a.dtype.kind not in "fciu":
        same = bool(np.array_equal(a, b))
        return same, (0.0 if same else math.inf), (0.0 if same else math.inf)
    if a.dtype.kind in "iu":
        d = float(np.max(np.abs(b.astype(float) - a.astype(float)))) if a.size else 0.0
        scale = float(np.max(np.abs(a.astype(float)))) if a.size else 0.0
        return d == 0, d, (d / scale if scale > 0 else (0.0 if d == 0 else math.inf))
    # floats as real numbers (a complex as its two parts), NaN where either has one
    ra = a.view(a.real.dtype) if a.dtype.kind == "c" else a
    rb = b.view(b.real.dtype) if b.dtype.kind == "c" else b
    nan = np.isnan(ra)
    if not np.array_equal(nan, np.isnan(rb)):
        return False, math.inf, math.inf
    x, y = ra[~nan], rb[~nan]
    if x.size == 0:
        return True, 0.0, 0.0
    with np.errstate(invalid="ignore", over="ignore"):
        d = float(np.max(np.where(x == y, 0.0, np.abs(y - x))))   # inf − inf: equal, not NaN
        scale = float(np.max(np.abs(x)))
    d = math.inf if math.isnan(d) else d
    rel = d / scale if 0 < scale < math.inf and d < math.inf else (0.0 if d == 0 else math.inf)
    if rtol == 0:
        same = bool(np.array_equal(x.view(f"u{x.dtype.itemsize}"), y.view(f"u{y.dtype.itemsize}")))
    else:
        same = rel <= rtol
    return same, d, rel


def attr_problems(where: str, ref: dict, new: dict, rtol: float) -> list[str]:
    """The attributes (not excluded) that differ between ``ref`` and ``new``."""
    import numpy as np

    out = []
    for k in sorted(set(ref) | set(new)):
        if excluded(k):
            continue
        if k not in ref or k not in new:
            out.append(f"{where}attribute {k!r} only in {'current' if k in new else 'reference'}")
            continue
        a, b = ref[k], new[k]
        if isinstance(a, str) or isinstance(b, str):
            same = isinstance(a, str) and isinstance(b, str) and normalise(a) == normalise(b)
        else:
            same = value_difference(np.asarray(a), np.asarray(b), rtol)[0]
        if not same:
            out.append(f"{where}attribute {k!r}: {a!r} → {b!r}")
    return out


def compare_files(ref_path: Path, new_path: Path, rtol: float):
    """(variables compared, largest |diff|, largest relative, problems) of two datasets."""
    import xarray as xr

    opts = {"engine": "netcdf4", "auto_complex": True, "decode_times": False,
            "decode_timedelta": False}
    with xr.open_dataset(ref_path, **opts) as r, xr.open_dataset(new_path, **opts) as n:
        r, n = r.load(), n.load()
    problems = attr_problems("", dict(r.attrs), dict(n.attrs), rtol)
    names_r, names_n = set(r.variables), set(n.variables)
    for k in sorted(names_r ^ names_n):
        problems.append(f"variable {k!r} only in {'current' if k in names_n else 'reference'}")
    for k in sorted(set(r.coords) ^ set(n.coords)):
        problems.append(f"{k!r} a coordinate in {'current' if k in n.coords else 'reference'} only")
    worst = worst_rel = 0.0
    common = sorted(names_r & names_n)
    for k in common:
        a, b = r.variables[k], n.variables[k]
        if a.dims != b.dims:
            problems.append(f"{k}: dims {a.dims} → {b.dims}")
            worst = worst_rel = math.inf
            continue
        same, d, rel = value_difference(a.values, b.values, rtol)
        if not same:
            note = " (equal values, other bits: a signed zero)" if d == 0 else ""
            problems.append(f"{k}: {a.dtype}{a.shape} → {b.dtype}{b.shape}, "
                            f"largest |diff| {d:.3g} (relative {rel:.3g}){note}")
        worst, worst_rel = max(worst, d), max(worst_rel, rel)
        problems += attr_problems(f"{k}: ", dict(a.attrs), dict(b.attrs), rtol)
    return len(common), worst, worst_rel, problems


def compare(ref_dir: Path, new_dir: Path, rtol: float, only=None, label=None) -> int:
    """Compare the datasets of ``new_dir`` (``label``: how to name it) with ``ref_dir``'s; prints
    the table, returns the exit status."""
    ref, new = read_summary(ref_dir)["calls"], read_summary(new_dir)["calls"]
    keys = list(ref) + [k for k in new if k not in ref]     # the probe's order
    if only:
        keys = [k for k in keys if k.split(".")[0] in only]
    if not keys:
        print("nothing to compare (no summary.json in either folder?)")
        return 1
    n_diff = n_same = 0
    print(f"\n{'config.call':46s} {'vars':>5s} {'max |diff|':>11s} {'relative':>10s} {'s':>6s}"
          "  status")
    details = []
    for key in keys:
        e_r, e_n = ref.get(key), new.get(key)
        secs = f"{e_n['seconds']:6.1f}" if e_n and e_n.get("seconds") is not None else " " * 6
        if e_r is None or e_n is None:
            status, nvar, d, rel = f"only in {'current' if e_r is None else 'reference'}", 0, "", ""
            ok = False
        elif e_r["error"] or e_n["error"]:
            nvar, d, rel = 0, "", ""
            if e_r["error"] and e_n["error"]:
                ok = normalise(e_r["error"]) == normalise(e_n["error"])
                status = "same error" if ok else "different errors"
                details.append(f"{key}: reference {e_r['error']}\n{' ' * len(key)}  current   "
                               f"{e_n['error']}")
            else:
                ok = False
                which, e = ("current", e_n) if e_n["error"] else ("reference", e_r)
                status = f"fails in {which} only"
                details.append(f"{key}: {which}: {e['error']}")
        elif not (ref_dir / e_r["file"]).is_file() or not (new_dir / e_n["file"]).is_file():
            ok, status, nvar, d, rel = False, "dataset file missing", 0, "", ""
        else:
            nvar, dd, rr, problems = compare_files(ref_dir / e_r["file"], new_dir / e_n["file"],
                                                   rtol)
            ok = not problems
            status = "identical" if ok and dd == 0 else ("same within rtol" if ok else
                                                         f"{len(problems)} differences")
            d, rel = f"{dd:11.3g}", f"{rr:10.3g}"
            details += [f"{key}: {p}" for p in problems]
        if e_r is not None and e_n is not None:
            w_r = {normalise(w) for w in e_r.get("warnings", [])}
            w_n = {normalise(w) for w in e_n.get("warnings", [])}
            if w_r != w_n:   # shown, not counted: a warning is said once per process
                details += [f"{key}: note (not counted): warning only in {which}: {w}"
                            for which, ws in (("reference", w_r - w_n), ("current", w_n - w_r))
                            for w in sorted(ws)]
        n_diff += not ok
        n_same += ok
        print(f"{key:46s} {nvar:5d} {d:>11s} {rel:>10s} {secs}  {status}")
    if details:
        print("\ndetails:")
        for line in details:
            print("  " + line)
    rule = "bitwise" if rtol == 0 else f"rtol {rtol:g}"
    print(f"\n{n_same} of {len(keys)} calls the same ({rule}), {n_diff} differ: "
          + ("IDENTICAL" if n_diff == 0 else "DIFFERENT")
          + f"  [reference {ref_dir}, current {label or new_dir}]")
    return 0 if n_diff == 0 else 1


# ------------------------------------------------------------------------------- main
def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--commit", default=None,
                    help="the commit to compare against (default HEAD: uncommitted work vs the "
                         "last commit), run in a temporary git worktree")
    ap.add_argument("--reference", type=Path, default=None,
                    help="a folder of datasets written before (--write or --keep DIR/reference) "
                         "to compare against instead of running a commit")
    ap.add_argument("--write", type=Path, default=None,
                    help="only write this tree's datasets into this folder (no comparison)")
    ap.add_argument("--keep", type=Path, default=None,
                    help="keep the datasets under DIR/reference and DIR/current")
    ap.add_argument("--rtol", type=float, default=0.0,
                    help="relative tolerance, max |new − ref| ≤ rtol · max |ref| per variable "
                         "(default 0: the same bits)")
    ap.add_argument("--only", nargs="+", default=None, metavar="NAME",
                    help="only these configs (stems, e.g. rm3 m4_134)")
    ap.add_argument("--xla-flags", default=XLA_FLAGS, metavar="FLAGS",
                    help="the probe's XLA_FLAGS (default: level 0, fast compiles); '' for XLA's "
                         "defaults, the bits a user's run has (a change to compile options "
                         "shows only there; slower: both trees ~20 minutes with the test suite "
                         "beside them, 2026-11-29)")
    args = ap.parse_args(argv)
    if args.reference is not None and args.commit is not None:
        ap.error("--reference and --commit are alternatives")
    if args.write is not None and (args.reference is not None or args.commit is not None):
        ap.error("--write runs this tree only: no --reference or --commit")
    paths = configs(args.only)

    if args.write is not None:
        if args.write.exists() and any(args.write.iterdir()):
            ap.error(f"--write {args.write}: the folder is not empty")
        calls = probe(ROOT, args.write, paths, args.xla_flags)["calls"]
        failed = [k for k, e in calls.items() if e["error"]]
        for k in failed:
            print(f"  failed: {k}: {calls[k]['error']}")
        print(f"wrote {len(calls) - len(failed)} datasets of {len(paths)} configs into {args.write}"
              + (f"; {len(failed)} calls failed" if failed else ""))
        return 1 if failed or not calls else 0

    with tempfile.TemporaryDirectory(prefix="regression-") as tmp:
        base = args.keep if args.keep is not None else Path(tmp)
        if args.keep is not None:
            for sub in ("reference", "current"):
                if args.reference is None or sub == "current":
                    shutil.rmtree(base / sub, ignore_errors=True)
        if args.reference is not None:
            if not (args.reference / "summary.json").is_file():
                ap.error(f"--reference {args.reference}: no summary.json there")
            ref_dir = args.reference
        else:
            ref_dir = base / "reference"
            rev = args.commit or "HEAD"
            full = subprocess.run(["git", "-C", str(ROOT), "rev-parse", "--short", rev],
                                  capture_output=True, text=True, check=True).stdout.strip()
            print(f"reference: commit {rev} ({full})")
            probe_commit(full, ref_dir, paths, args.xla_flags)
        new_dir = base / "current"
        probe(ROOT, new_dir, paths, args.xla_flags)
        label = new_dir if args.keep is not None else f"this tree, {ROOT}"
        return compare(ref_dir, new_dir, args.rtol, args.only, label)


if __name__ == "__main__":
    sys.exit(main())
