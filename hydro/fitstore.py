"""Radiation fits stored in the database file itself, so that a first run on any machine reads
them instead of fitting (WEC-Sim's BEMIO keeps its state-space realisation in its ``.h5`` the
same way).

A state-space fit costs seconds to tens of seconds (M4 134 ~2–4 s, Wu & Yuan's 75 dofs ~14 s on
2 cores) and the disk cache of :mod:`hydro.fitcache` only helps a machine that has made it once.
``mfm fits CONFIG`` (:func:`mfm.io.cli.cmd_fits`) makes what a config's runs use, the default
fit and the values its water needs (the memory T_K, the consistent A∞), and stores each in a
NetCDF group of the database file::

    /                      the database, untouched (its content, hence every key, is unchanged)
    /mfm_fits/k<sha256>    one fit, value or mooring table each (``kind``), with the digest of
                           the code that made it (``source``) and, for a fit, its report

(mfm's mooring tables, :func:`mfm.loads.catenary_tables.build_table`, are stored the same way:
their code is mfm's, so ``mfm fits`` gives :func:`store` its digest.)

A stored item is found by its key: the sha256 of the database as the fit sees it, the options and
the source of the code that makes it (:data:`FIT_SOURCES`, :data:`VALUE_SOURCES`), but not
numpy's version (unlike the disk cache, whose files promise the bits this machine would make):
a stored fit is a product of the database, the same bits on every machine that reads it, as the
BEM coefficients themselves are. A change to that code makes other keys, so the item is no longer
found and the run fits again, as it would without it (``tests/test_fitstore.py`` fails for the
shipped databases until ``mfm fits`` is run again).

Arrays are stored as they are (A and B by their nonzero entries, exactly; complex numbers as real
and imaginary parts), so a fit read back equals the stored one to the last bit.
"""
from __future__ import annotations

import functools
import hashlib
import os
from pathlib import Path

import numpy as np

from .contentkey import content_key

GROUP = "mfm_fits"
# the code each kind of item depends on (hydro/ files): another source is another key
FIT_SOURCES = ("statespace.py", "vectorfit.py", "passivity.py", "radiation.py")
VALUE_SOURCES = ("radiation.py", "prepare.py")
_ENCODING = {"zlib": True, "complevel": 4}


def source_digest(kind: str) -> str:
    """sha256 of the source files that make items of ``kind`` ("fit" or "value"; the code that
    stores other kinds, such as mfm's mooring tables, gives their digest to :func:`store`)."""
    if kind not in ("fit", "value"):
        raise ValueError(f"kind {kind!r}: hydro knows the code of 'fit' and 'value' items; give "
                         "the digest of another kind's code to store(sources=)")
    h = hashlib.sha256()
    here = Path(__file__).parent
    for name in FIT_SOURCES if kind == "fit" else VALUE_SOURCES:
        h.update((here / name).read_bytes())
    return h.hexdigest()


def fit_key(db, options: dict, *, hashed=None) -> str:
    """The key of a fit of ``db`` (the database as the fit sees it) with ``options``
    (``hashed``: :func:`hydro.contentkey.database_hash` of ``db``, where made before)."""
    return content_key(db, options, FIT_SOURCES, numpy_version=False, hashed=hashed)


def value_key(db, name: str, options: dict, *, hashed=None) -> str:
    """The key of the value ``name`` made from ``db`` with ``options`` (as the disk cache names
    it, :mod:`hydro.fitcache`)."""
    return content_key(db, {"value": name, **options}, VALUE_SOURCES, numpy_version=False,
                       hashed=hashed)


# -- reading

def _stamp(path) -> tuple | None:
    try:
        st = os.stat(path)
    except OSError:
        return None
    return (str(path), st.st_mtime_ns, st.st_size)


@functools.lru_cache(maxsize=16)
def _index(stamp) -> dict:
    """{key: kind} of the items stored in the file ``stamp`` names (its path, mtime and size:
    a file written again is read again)."""
    import netCDF4

    try:
        data = Path(stamp[0]).read_bytes()
        with netCDF4.Dataset("stored-fits", mode="r", memory=data) as nc:
            g = nc.groups.get(GROUP)
            if g is None:
                return {}
            return {name[1:]: str(g.groups[name].getncattr("kind")) for name in g.groups
                    if name.startswith("k")}
    except Exception:           # not a NetCDF-4 file, or damaged: nothing stored to read
        return {}


def stored(path) -> dict:
    """{key: kind} of what the database file at ``path`` stores ({} for none, or not NetCDF)."""
    stamp = _stamp(path)
    return {} if stamp is None else dict(_index(stamp))


def _group(path, key):
    from .database import read_netcdf

    return read_netcdf(path, group=f"{GROUP}/k{key}")


def read(path, key: str, kind: str):
    """The fit (a :class:`hydro.statespace.StateSpaceRadiation`) or value (a float or a read-only
    float array: kinds other than "fit") stored under ``key`` in the database file at ``path``,
    or None when it holds none (or it cannot be read)."""
    if stored(path).get(key) != kind:
        return None
    try:
        ds = _group(path, key)
        return _fit_from(ds) if kind == "fit" else _value_from(ds)
    except Exception:           # a damaged group: made again, as without it
        return None


# -- the stored form

def _sparse(name, a, out, dims):
    """A 2-d array by its entries whose bits are not zero (so -0.0 is kept): rows, columns,
    values and its shape."""
    r, c = np.nonzero(a.view(np.uint64))
    out[f"{name}_row"] = (dims, r.astype(np.int32))
    out[f"{name}_col"] = (dims, c.astype(np.int32))
    out[f"{name}_value"] = (dims, a[r, c])
    out[f"{name}_shape"] = ((f"{name}_axis",), np.asarray(a.shape, dtype=np.int64))


def _dense(ds, name):
    a = np.zeros(tuple(int(n) for n in ds[f"{name}_shape"].values))
    a[ds[f"{name}_row"].values, ds[f"{name}_col"].values] = ds[f"{name}_value"].values
    return a


def _encode(x):
    """The fit's report as JSON values, exactly: tuples and dicts with keys other than strings
    tagged, so that :func:`_decode` gives back equal Python values (floats by their repr, NaN
    included). JSON, not a repr read by ``ast.literal_eval``: Wu & Yuan's report (two entries per
    fitted pair, 5,593 pairs) reads in milliseconds instead of 0.26 s."""
    if isinstance(x, np.generic):
        x = x.item()
    if isinstance(x, dict):
        if all(isinstance(k, str) for k in x):
            return {k: _encode(v) for k, v in x.items()}
        return {"__items__": [[_encode(k), _encode(v)] for k, v in x.items()]}
    if isinstance(x, tuple):
        return {"__tuple__": [_encode(v) for v in x]}
    if isinstance(x, list):
        return [_encode(v) for v in x]
    if x is None or isinstance(x, (bool, int, float, str)):
        return x
    raise ValueError(f"the fit's report holds a {type(x).__name__} ({x!r}), which is not stored")


def _decode(d):
    if "__tuple__" in d and len(d) == 1:
        return tuple(d["__tuple__"])
    if "__items__" in d and len(d) == 1:
        return {_hashable(k): v for k, v in d["__items__"]}
    return d


def _hashable(k):
    return tuple(_hashable(v) for v in k) if isinstance(k, list) else k


def _report_text(report: dict) -> str:
    import json

    report = {k: v for k, v in report.items() if k != "cache"}
    text = json.dumps(_encode(report))
    # equal as JSON again (NaN is not equal to itself as a float)
    if json.dumps(_encode(_report_from(text))) != text:
        raise ValueError("the fit's report does not read back equal from JSON; not stored")
    return text


def _report_from(text: str) -> dict:
    import json

    return json.loads(text, object_hook=_decode)


def _shared(arrays):
    """Arrays by content: the distinct ones, and which of them each one is (common poles: one
    set for every entry; a symmetric fit: the residues of (i, j) are those of (j, i))."""
    index, distinct, which = {}, [], []
    for a in arrays:
        a = np.asarray(a)
        k = index.setdefault(a.tobytes(), len(distinct))
        if k == len(distinct):
            distinct.append(a)
        which.append(k)
    return distinct, np.asarray(which, dtype=np.int64)


def _ragged(name, arrays, v):
    """Complex arrays of several lengths as one real and one imaginary vector, the distinct
    arrays' offsets, and each item's distinct array."""
    distinct, which = _shared(arrays)
    cat = np.concatenate(distinct) if distinct else np.zeros(0, complex)
    v[f"{name}_real"] = ((name,), cat.real)
    v[f"{name}_imag"] = ((name,), cat.imag)
    v[f"{name}_offsets"] = ((f"{name}_edge",),
                            np.cumsum([0] + [len(a) for a in distinct]).astype(np.int64))
    v[f"{name}_of_entry"] = (("entry",), which)


def _unragged(ds, name):
    z = ds[f"{name}_real"].values + 1j * ds[f"{name}_imag"].values
    o = ds[f"{name}_offsets"].values
    distinct = [z[o[k]:o[k + 1]] for k in range(len(o) - 1)]
    return tuple(distinct[int(k)].copy() for k in ds[f"{name}_of_entry"].values)


def _fit_dataset(fit, made: dict):
    import xarray as xr

    v = {}
    _sparse("A", np.asarray(fit.A, float), v, ("A_nonzero",))
    _sparse("B", np.asarray(fit.B, float), v, ("B_nonzero",))
    v["C"] = (("C_row", "C_col"), np.asarray(fit.C, float))
    v["added_mass_inf"] = (("dof_i", "dof_j"), np.asarray(fit.added_mass_inf, float))
    v["dofs"] = (("dof",), np.asarray([str(d) for d in fit.dofs]))
    v["entries"] = (("entry", "pair"), np.asarray(fit.entries, dtype=np.int64).reshape(-1, 2))
    _ragged("poles", fit.poles, v)
    _ragged("residues", fit.residues, v)
    return xr.Dataset(v, attrs={"kind": "fit", "report": _report_text(dict(fit.report)), **made})


def _fit_from(ds):
    from types import MappingProxyType

    from .statespace import StateSpaceRadiation

    fit = StateSpaceRadiation(
        _dense(ds, "A"), _dense(ds, "B"), np.array(ds["C"].values, dtype=float),
        np.array(ds["added_mass_inf"].values, dtype=float),
        tuple(str(d) for d in ds["dofs"].values),
        tuple((int(i), int(j)) for i, j in ds["entries"].values),
        _unragged(ds, "poles"), _unragged(ds, "residues"),
        MappingProxyType(_report_from(ds.attrs["report"])))
    for a in (fit.A, fit.B, fit.C, fit.added_mass_inf, *fit.poles, *fit.residues):
        a.setflags(write=False)          # read-only, as fit_state_space makes them
    return fit


def _value_dataset(value, made: dict, kind: str = "value"):
    import xarray as xr

    a = np.asarray(value)
    if a.dtype.kind != "f":
        raise ValueError(f"a stored value must be a float or an array of floats, not {a.dtype}")
    dims = tuple(f"axis_{k}" for k in range(a.ndim))
    return xr.Dataset({"value": (dims, a)},
                      attrs={"kind": kind, "scalar": int(np.ndim(value) == 0), **made})


def _value_from(ds):
    a = np.array(ds["value"].values, dtype=float)
    if int(ds.attrs.get("scalar", 0)):
        return float(a)
    a.setflags(write=False)
    return a


# -- writing

def store(path, items: dict, sources: dict | None = None) -> dict:
    """Store ``items`` ({key: (kind, fit or value)}) in the database file at ``path``, keeping
    the items it already stores whose code is current (``source`` attribute) and dropping the
    others. ``sources``: the digest of the code of each kind other than "fit" and "value" (an
    item of a kind it does not name is dropped: its code cannot be judged). The file is written
    anew beside ``path`` and renamed over it, after checking that its database (the root group)
    reads back identical. Returns {key: kind} of what it stores."""
    import xarray as xr

    from .database import read_netcdf

    path = Path(path)
    if path.suffix != ".nc":
        raise ValueError(f"{str(path)!r}: fits are stored in a NetCDF database (.nc); convert the "
                         "database first (hydro.prepare.open_any_database, then "
                         "hydro.database.to_netcdf) and point the config at it")
    root = read_netcdf(path)
    current = {"fit": source_digest("fit"), "value": source_digest("value"), **(sources or {})}
    # the file's own order first (an item stored again keeps its place), then the new items by
    # key: storing the same items again writes the same bytes, whatever order they were made in
    groups = {}
    for key, kind in stored(path).items():
        if key in items:
            groups[key] = None
            continue
        ds = _group(path, key)
        if kind in current and ds.attrs.get("source") == current[kind]:
            groups[key] = ds
    import scipy

    for key, (kind, obj) in sorted(items.items()):
        if kind not in current:
            raise ValueError(f"store: no digest of the code that makes {kind!r} items; give it "
                             f"in sources=")
        made = {"source": current[kind], "made_with": f"numpy {np.__version__}, "
                f"scipy {scipy.__version__}", "made_by": "mfm fits (hydro.fitstore.store)"}
        groups[key] = (_fit_dataset(obj, made) if kind == "fit"
                       else _value_dataset(obj, made, kind))
    tmp = path.with_name(f".{path.name}.tmp{os.getpid()}")
    try:
        root.to_netcdf(tmp, engine="netcdf4")
        for key, ds in groups.items():
            enc = {name: dict(_ENCODING) for name, da in ds.variables.items()
                   if da.ndim and da.dtype.kind in "fiu"}
            ds.to_netcdf(tmp, mode="a", group=f"{GROUP}/k{key}", engine="netcdf4", encoding=enc)
        xr.testing.assert_identical(read_netcdf(tmp), root)
        os.replace(tmp, path)
    finally:
        if tmp.exists():
            tmp.unlink()
    return stored(path)
