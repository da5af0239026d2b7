"""The key of what is made from a database (a radiation fit, its memory T_K, its consistent A∞):
the sha256 of the database's content, the options and the source of the code that makes it. The
disk cache (:mod:`hydro.fitcache`) and the fits stored in a database file (:mod:`hydro.fitstore`)
name their items by it; it imports neither."""
from __future__ import annotations

import hashlib
from pathlib import Path

import numpy as np


def update(h, x) -> None:
    """Hash ``x`` into ``h``: containers item by item, arrays by their bytes (a repr elides the
    middle of a large array: two arrays could hash alike)."""
    if isinstance(x, dict):
        h.update(f"dict{len(x)}".encode())
        for k in sorted(x, key=repr):
            update(h, k)
            update(h, x[k])
        return
    if isinstance(x, (list, tuple)):
        h.update(f"{type(x).__name__}{len(x)}".encode())
        for item in x:
            update(h, item)
        return
    a = None if isinstance(x, (str, bytes)) else np.asarray(x)
    if a is not None and a.dtype.kind in "fciub":
        h.update(f"{a.dtype.str}{a.shape}".encode())
        h.update(np.ascontiguousarray(a).tobytes())
    elif a is not None and a.ndim:
        h.update(repr(a.tolist()).encode())        # labels: every item
    else:
        h.update(repr(x).encode())


def database_hash(db):
    """The sha256 state after every array, dimension and attribute of ``db`` (its ``date_read``
    attribute aside): the start of every :func:`content_key` of ``db``. Hashing a database is
    most of a key's cost (M4 134 4.4 ms, Wu & Yuan's time domain 6.4 ms, a key from it 0.3 ms,
    on the 2-core project machine), so a caller that keys
    several items of one database hashes it once and passes this as ``hashed=``."""
    h = hashlib.sha256()
    for name in sorted(map(str, db.variables)):
        v = db.variables[name]
        update(h, (name, v.dims, v.values, dict(v.attrs)))
    update(h, {k: v for k, v in db.attrs.items() if k != "date_read"})
    return h


def content_key(db, options: dict, sources, *, numpy_version: bool = True, hashed=None) -> str:
    """sha256 of every array, dimension and attribute of ``db`` (its ``date_read`` attribute
    aside), ``options``, the bytes of the hydro/ files ``sources`` and, if ``numpy_version``,
    numpy's version (its linear algebra makes the last bits of a fit). ``hashed``:
    :func:`database_hash` of ``db``, made before (copied here, not changed)."""
    h = (database_hash(db) if hashed is None else hashed).copy()
    update(h, dict(options))
    here = Path(__file__).parent
    for name in sources:
        h.update((here / name).read_bytes())
    if numpy_version:
        h.update(np.__version__.encode())
    return h.hexdigest()
