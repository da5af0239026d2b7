"""Where mooring tables are kept (:meth:`mfm.runner.door.RunnerHost.mooring_table`): a catenary
line's table (:func:`mfm.loads.catenary_tables.make_table`, MoorPy on a grid) is looked for

- in the process, keyed by the table's parameters (lines of one geometry share one table);
- in the database file, where ``mfm fits`` stores a config's tables (:mod:`hydro.fitstore`),
  keyed by the parameters and the digest of the code that makes them
  (:func:`~mfm.loads.catenary_tables.table_source`);
- on disk beside the radiation fits (:mod:`hydro.fitcache`'s folder, ``mooring-tables``; off with
  ``MFM_FIT_CACHE=off``), named by the sha256 of the parameters, the maker's source and the
  MoorPy, numpy and scipy versions;

and made only where none of them has it.
"""
from __future__ import annotations

import numpy as np

from ..loads import catenary_tables
from ..loads.catenary_tables import make_table, packed, stored_table_key, table_centre, unpacked

_TABLE_CACHE: dict = {}


def mooring_table(x0, z0, extent, step, length, EA, weight, seabed_friction, stored=None,
                  make=make_table):
    """(xs, zs, coef): the grid axes and the nodal data (nx, nz, 4, 2) of the tensor-product
    not-a-knot cubic spline of (H, V): [f, hx ∂f/∂x, hz ∂f/∂z, hx hz ∂²f/∂x∂z] per node
    (``make``: :func:`~mfm.loads.catenary_tables.make_table`). The grid is centred on the rest span and
    height (:func:`~mfm.loads.catenary_tables.table_centre`), and kept on its arguments: lines of
    one geometry make one table (Wu & Yuan's six lines: one table of 2,511 MoorPy solves, not
    three).

    Looked for in the process, then in the database file ``stored`` (where ``mfm fits`` stores
    a config's tables beside its radiation fits, :mod:`hydro.fitstore`: a first run on a new
    machine neither imports MoorPy, whose import of matplotlib's pyplot is 1.7 s, nor solves),
    then on disk; else made."""
    from hydro import fitcache, fitstore

    x0, z0 = table_centre(x0, z0)
    key = tuple(round(float(v), 9) for v in (x0, z0, *extent, *step, length, EA, weight,
                                             seabed_friction))
    read = fitcache.reads_stored(stored)       # the fits' switch (MFM_FIT_CACHE=off: not read)
    skey = None if stored is None else stored_table_key(key)

    def kept(table):
        _TABLE_CACHE[key] = table
        if skey is not None and fitcache.recording_now():          # `mfm fits` stores it
            fitcache.record(stored, skey, "table", packed(table))
        return table

    if key in _TABLE_CACHE:
        return kept(_TABLE_CACHE[key])
    if read:
        kept_packed = fitstore.read(stored, skey, "table")
        if kept_packed is not None:
            return kept(unpacked(kept_packed))
    path = _table_file(key)
    table = _read_table(path)
    if table is not None:
        return kept(table)
    table = make(x0, z0, extent, step, length, EA, weight, seabed_friction)
    _write_table(path, table)
    return kept(table)




# the most the tables' folder may hold (Wu & Yuan's table: 81 × 31 × 4 × 2 doubles, 160 kB)
TABLES_BYTES = 64 * 2**20


def _table_file(key):
    """The disk cache's file of the table ``key`` (None when the fit cache is off): named by
    the sha256 of the key, the source of the module that makes it and the versions that make its
    numbers."""
    import hashlib
    from importlib.metadata import version
    from pathlib import Path

    from hydro import fitcache

    folder = fitcache.cache_dir()
    if folder is None:
        return None
    h = hashlib.sha256(repr((key, catenary_tables.MOORPY_TOL)).encode())
    h.update(Path(catenary_tables.__file__).read_bytes())
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
