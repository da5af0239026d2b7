"""The mooring tables of :mod:`mfm.loads.catenary`: MoorPy's quasi-static line solved on a grid of
(span, height) about a line's rest position, and the nodal data of its tensor-product cubic
spline, made once on the host (the compiled time loop cannot call MoorPy) and kept:

- in the process, keyed by the table's parameters (lines of one geometry share one table);
- in the database file, where ``mfm fits`` stores a config's tables (:mod:`hydro.fitstore`),
  keyed by the parameters and the digest of the code that makes them (:func:`table_source`);
- on disk beside the radiation fits (:mod:`hydro.fitcache`'s folder, ``mooring-tables``; off with
  ``MFM_FIT_CACHE=off``), named by the sha256 of the parameters, this module's source and the
  MoorPy, numpy and scipy versions.

Host code only (numpy, scipy, MoorPy): the load that interpolates the tables inside jax is
:class:`mfm.loads.catenary.CatenaryLines`.
"""
from __future__ import annotations

import functools

import numpy as np

from hydro import phases

MOORPY_TOL = 1e-10      # m: MoorPy's catenary convergence tolerance for the tables

_TABLE_CACHE: dict = {}
# m: the table's centre is the rest span and height rounded to this (a table reaches tens of
# metres about it, its nodes a metre apart: a shift of half a millimetre changes nothing it
# covers), so that lines of one geometry share a table
CENTRE_QUANTUM = 1e-3


def moorpy_version() -> str:
    from importlib.metadata import version

    return version("moorpy")


def catenary_forces(x, z, length, EA, weight, seabed_friction=0.0):
    """MoorPy's quasi-static line at horizontal span x and height z (fairlead above anchor):
    (H, V) the fairlead's horizontal and vertical tensions, N (the force on the fairlead is
    −H ê_h − V ẑ). Raises ValueError when MoorPy reports no solution."""
    from moorpy.Catenary import catenary

    out = catenary(float(x), float(z), float(length), float(EA), float(weight),
                   CB=float(seabed_friction), Tol=MOORPY_TOL, MaxIter=500)
    if out[4].get("error"):
        raise ValueError(f"MoorPy's catenary found no solution at span {x:.6g} m, height {z:.6g} m "
                         f"(L {length:.6g} m, EA {EA:.6g} N, w {weight:.6g} N/m): "
                         f"{out[4].get('message', '')}")
    return -out[2], -out[3]


def _axis(centre, half, step):
    n = int(np.ceil(2 * half / step - 1e-9)) + 1
    return np.linspace(centre - half, centre + half, max(n, 4))


def build_table(x0, z0, extent, step, length, EA, weight, seabed_friction, stored=None):
    """(xs, zs, coef): the grid axes and the nodal data (nx, nz, 4, 2) of the tensor-product
    not-a-knot cubic spline of (H, V): [f, hx ∂f/∂x, hz ∂f/∂z, hx hz ∂²f/∂x∂z] per node
    (:func:`make_table`). The grid is centred on the rest span and height (x0, z0) rounded to
    :data:`CENTRE_QUANTUM`, and cached on its arguments: lines of one geometry make one table,
    although their spans, computed from fairlead and anchor positions a config gives to 1e-6 m,
    differ in the last digits (Wu & Yuan's six lines: three spans 775.4999997–775.5000010 m, so
    three tables of 2,511 MoorPy solves each, 10 s on a 2-core machine, where one serves).

    Looked for in the process, then in the database file ``stored`` (where ``mfm fits`` stores
    a config's tables beside its radiation fits, :mod:`hydro.fitstore`: a first run on a new
    machine neither imports MoorPy, whose import of matplotlib's pyplot is 1.7 s, nor solves),
    then on disk; else made."""
    from hydro import fitcache, fitstore

    x0, z0 = (round(float(v) / CENTRE_QUANTUM) * CENTRE_QUANTUM for v in (x0, z0))
    key = tuple(round(float(v), 9) for v in (x0, z0, *extent, *step, length, EA, weight,
                                             seabed_friction))
    read = fitcache.reads_stored(stored)       # the fits' switch (MFM_FIT_CACHE=off: not read)
    skey = None if stored is None else stored_table_key(key)

    def kept(table):
        _TABLE_CACHE[key] = table
        if skey is not None and fitcache.recording_now():          # `mfm fits` stores it
            fitcache.record(stored, skey, "table", _packed(table))
        return table

    if key in _TABLE_CACHE:
        return kept(_TABLE_CACHE[key])
    if read:
        packed = fitstore.read(stored, skey, "table")
        if packed is not None:
            return kept(_unpacked(packed))
    path = _table_file(key)
    table = _read_table(path)
    if table is not None:
        return kept(table)
    table = make_table(x0, z0, extent, step, length, EA, weight, seabed_friction)
    _write_table(path, table)
    return kept(table)


def make_table(x0, z0, extent, step, length, EA, weight, seabed_friction):
    """:func:`build_table`'s table made: MoorPy's line (:func:`catenary_forces`) at every node of
    the grid of half-widths ``extent`` and spacing ``step`` about (x0, z0), and the spline's
    nodal derivatives."""
    from scipy.interpolate import CubicSpline

    xs, zs = _axis(x0, extent[0], step[0]), _axis(z0, extent[1], step[1])
    # seconds (Wu & Yuan: 2,511 solves, ~7 s on 2 cores): a display that shows them hears how far
    n, rows, every = len(xs) * len(zs), [], phases.every(len(xs))
    for i, x in enumerate(xs):
        if i % every == 0:
            phases.say(f"mooring table (MoorPy): {i * len(zs):,} of {n:,} solves")
        rows.append([catenary_forces(x, z, length, EA, weight, seabed_friction) for z in zs])
    F = np.array(rows)                                              # (nx, nz, 2)
    Fx = CubicSpline(xs, F, axis=0)(xs, 1)
    Fz = CubicSpline(zs, F, axis=1)(zs, 1)
    Fxz = CubicSpline(zs, Fx, axis=1)(zs, 1)
    hx, hz = xs[1] - xs[0], zs[1] - zs[0]
    coef = np.stack([F, hx * Fx, hz * Fz, hx * hz * Fxz], axis=2)
    return xs, zs, coef


@functools.cache
def table_source() -> str:
    """sha256 of the code that makes a table (:func:`make_table`, :func:`catenary_forces`,
    :func:`_axis`) and of MoorPy's tolerance: a stored table made by other code is not read, and
    ``mfm fits`` drops it (not MoorPy's version: a stored table is a product of the config, the
    same numbers wherever it is read, as a stored fit is)."""
    import hashlib
    import inspect

    h = hashlib.sha256(repr(MOORPY_TOL).encode())
    for f in (make_table, catenary_forces, _axis):
        h.update(inspect.getsource(f).encode())
    return h.hexdigest()


def stored_table_key(key) -> str:
    """The key of the table of ``key`` (:func:`build_table`'s parameters) in a database file."""
    import hashlib

    h = hashlib.sha256(repr(("mooring table", key)).encode())
    h.update(table_source().encode())
    return h.hexdigest()


def _packed(table):
    """(xs, zs, coef) as one float vector: [nx, nz, xs, zs, coef (nx, nz, 4, 2) flat]."""
    xs, zs, coef = table
    return np.concatenate([[len(xs), len(zs)], xs, zs, np.ravel(coef)])


def _unpacked(a):
    nx, nz = int(a[0]), int(a[1])
    xs, zs = a[2:2 + nx], a[2 + nx:2 + nx + nz]
    return xs, zs, a[2 + nx + nz:].reshape(nx, nz, 4, 2)


# the most the tables' folder may hold (Wu & Yuan's table: 81 × 31 × 4 × 2 doubles, 160 kB)
TABLES_BYTES = 64 * 2**20


def _table_file(key):
    """The disk cache's file of the table ``key`` (None when the fit cache is off): named by
    the sha256 of the key, this module's source and the versions that make its numbers."""
    import hashlib
    from importlib.metadata import version
    from pathlib import Path

    from hydro import fitcache

    folder = fitcache.cache_dir()
    if folder is None:
        return None
    h = hashlib.sha256(repr((key, MOORPY_TOL)).encode())
    h.update(Path(__file__).read_bytes())
    for package in ("moorpy", "numpy", "scipy"):
        h.update(f"{package} {version(package)}".encode())
    return folder / "mooring-tables" / f"{h.hexdigest()}.npz"


def _read_table(path):
    """(xs, zs, coef) from ``path``, or None (no cache, no file, or one that cannot be read:
    the table is made again and written anew)."""
    if path is None:
        return None
    try:
        with np.load(path) as f:
            table = (f["xs"], f["zs"], f["coef"])
        path.touch()                   # recently used: dropped last
        return table
    except Exception:
        return None


def _write_table(path, table) -> None:
    if path is None:
        return
    from hydro import fitcache

    xs, zs, coef = table
    try:
        fitcache.write_whole(path, lambda f: np.savez(f, xs=xs, zs=zs, coef=coef))
        fitcache.trim(path.parent, TABLES_BYTES, "*.npz")
    except Exception as e:            # the cache is a shortcut: never the reason a load fails
        import warnings

        warnings.warn(f"the mooring tables' cache {path.parent} cannot be written ({e}); the "
                      "table is kept in this process only. Set MFM_FIT_CACHE to a writable "
                      "folder, or to off", RuntimeWarning, stacklevel=3)
