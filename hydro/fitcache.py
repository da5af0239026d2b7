"""State-space radiation fits kept by their content: in the process and on disk.

A fit (:func:`hydro.statespace.fit_state_space`) costs seconds (M4 134: ~5 s, Wu & Yuan: ~20 s)
and depends only on the database's arrays, the fit's options and the fitting code. So a fit is
kept under the sha256 of all three (with numpy's version: its linear algebra makes the bits):

- in the process, so that a config loaded twice fits once (and its compiled run, keyed on the
  fit's report, is reused);
- on disk, as a pickle under ``$XDG_CACHE_HOME/mfm/fits`` (default ``~/.cache/mfm/fits``), so
  that a later process reads it in about 0.1 s (M4 134), like jax's compilation cache
  (:mod:`mfm._xla`). ``MFM_FIT_CACHE`` names another folder, or ``off`` for none. The folder
  holds at most :data:`CACHE_BYTES`, the least recently used dropped first. Each file is sealed
  (:func:`seal`): the sha256 of its pickle is written with it, in one file put in place whole
  (written beside, then renamed), and checked before the pickle is read; a file that fails
  (a flipped bit, a torn or foreign file, one of an older format) is removed, said so once (a
  :class:`CacheWarning` naming the file and why) and made again. A folder that cannot be
  written is warned about once and the run goes on without it. Pickles run code when read: the
  folder is the user's own, as jax's is.

A fit read back equals the one written to the last bit; its report gains ``cache``: the file it
came from (``""`` when it was fitted in this process). Smaller values that every process would
make again from a database (its radiation memory T_K, its consistent A∞) are kept the same way
(:func:`cached_value`).

Before the folder, a fit or value is looked for in the database file itself, where ``mfm fits``
stores them (:mod:`hydro.fitstore`): there a first run on a new machine finds them.
"""
from __future__ import annotations

import collections
import contextlib
import hashlib
import os
import pickle
import tempfile
import warnings
from pathlib import Path

import numpy as np

# imported with this module, not on the first stored fit: mfm._programs names a program by the
# settings of the hydro modules loaded (fitstore's GROUP, ...), so a module loaded halfway through
# a process would rename the programs made after it
from . import fitstore
from .contentkey import content_key, database_hash

# the most the default folder may hold; a fit of M4 134 (960 states) is about 8 MB
CACHE_BYTES = 512 * 2**20
# fits kept in the process (the least recently used dropped first)
MEMORY_ITEMS = 16
# the code a fit depends on: a change in any of these files is another key
_SOURCES = ("statespace.py", "vectorfit.py", "passivity.py", "radiation.py", "fitcache.py",
            "prepare.py")

# the first bytes of a sealed cache file (seal()): what follows is the sha256 of the payload, then
# the payload. A file without them (an older format, a foreign or torn file) is not read.
MAGIC = b"mfm-sealed-1\n"
_DIGEST = 32

_memory: collections.OrderedDict = collections.OrderedDict()
_values: dict = {}              # cached_value's, by key (a float or a small array each)
_warned = False


def reads_stored(stored) -> bool:
    """Whether the database file ``stored`` (None: none) is read for stored items: not with
    ``MFM_FIT_CACHE=off``, where every fit, value and mooring table is made in the process (the
    benchmarks that time them need it)."""
    return stored is not None and cache_dir() is not None


def cache_dir() -> Path | None:
    """The folder of the disk cache, or None when ``MFM_FIT_CACHE`` is ``off`` (then fits and
    values stored in a database file, :mod:`hydro.fitstore`, are not read either: every one is
    made in the process, as the benchmarks that time them need)."""
    setting = os.environ.get("MFM_FIT_CACHE", "").strip()
    if setting.lower() in ("off", "0", "false", "no", "none"):
        return None
    if setting:
        return Path(setting).expanduser()
    base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    return Path(base) / "mfm" / "fits"


def fit_key(db, options: dict, *, hashed=None) -> str:
    """sha256 of what a fit depends on: every array, dimension and attribute of ``db`` (the
    database as the fit sees it), the options, the fitting code's source and numpy's version
    (:func:`hydro.contentkey.content_key`; a fit stored in a database file is keyed without
    numpy's version, :mod:`hydro.fitstore`). ``hashed``: the database's
    :func:`hydro.contentkey.database_hash`, where made before."""
    return content_key(db, options, _SOURCES, hashed=hashed)


def clear() -> None:
    """Forget the fits kept in this process (the folder's stay): what a benchmark that times
    fits calls before each."""
    _memory.clear()
    _values.clear()


def _remember(key, fit):
    _memory[key] = fit
    _memory.move_to_end(key)
    while len(_memory) > MEMORY_ITEMS:
        _memory.popitem(last=False)
    return fit


def _with_source(fit, source: str):
    import dataclasses
    from types import MappingProxyType

    return dataclasses.replace(fit, report=MappingProxyType({**fit.report, "cache": source}))


def _to_plain(fit) -> dict:
    """The fit's fields, its report as a dict (a mappingproxy does not pickle)."""
    import dataclasses

    return {f.name: (dict(getattr(fit, f.name)) if f.name == "report" else getattr(fit, f.name))
            for f in dataclasses.fields(fit)}


def _from_plain(fields: dict):
    from types import MappingProxyType

    from .statespace import StateSpaceRadiation

    fit = StateSpaceRadiation(**{**fields, "report": MappingProxyType(fields["report"])})
    for a in (fit.A, fit.B, fit.C, fit.added_mass_inf, *fit.poles, *fit.residues):
        a.setflags(write=False)        # read-only, as fit_state_space makes them
    return fit


class CacheWarning(RuntimeWarning):
    """A cache entry that failed its check (a flipped bit, a torn or foreign file): removed and
    made again. The answer is the one a clean cache gives; only the time differs."""


class Damaged(Exception):
    """A sealed cache entry that fails its check (its message says how)."""


def seal(payload: bytes) -> bytes:
    """``payload`` as a cache file holds it: :data:`MAGIC`, its sha256, then itself."""
    return MAGIC + hashlib.sha256(payload).digest() + bytes(payload)


def unseal(blob: bytes) -> bytes:
    """The payload of a file :func:`seal` made, checked against its sha256; raises
    :class:`Damaged` saying why where it does not match (or the file is not sealed)."""
    head = len(MAGIC) + _DIGEST
    if not blob.startswith(MAGIC):
        raise Damaged("not a sealed mfm cache entry (torn, foreign, or of an older format)"
                      if blob else "empty (a torn write)")
    if len(blob) < head:
        raise Damaged(f"cut short at {len(blob)} bytes (a torn write)")
    payload = blob[head:]
    if hashlib.sha256(payload).digest() != blob[len(MAGIC):head]:
        raise Damaged(f"its content does not match its sha256 ({len(payload)} bytes; a flipped "
                      "bit or a torn write)")
    return payload


_discarded: set = set()


def discard(path: Path, why: str, what: str = "cache entry") -> None:
    """Remove the damaged cache file ``path`` (it is made again by the caller) and say so: once
    for a file and a reason in a process (a file that cannot be removed is not said again on
    every read)."""
    try:
        os.unlink(path)
        removed = "removed and made again"
    except FileNotFoundError:
        removed = "made again"
    except OSError as e:
        removed = f"made again (it could not be removed: {e.strerror})"
    if (str(path), why) not in _discarded:      # where it cannot be removed: said once
        _discarded.add((str(path), why))
        warnings.warn(f"mfm: the {what} {path} is damaged: {why}; {removed}, the answer is "
                      "unchanged", CacheWarning, stacklevel=3)


def read_sealed(path: Path, what: str = "cache entry") -> bytes | None:
    """The checked payload of the sealed file at ``path``; None where there is none, or where it
    is damaged (then it is removed, with a :class:`CacheWarning`)."""
    try:
        blob = path.read_bytes()
    except OSError:              # none, or a folder that cannot be read: made (and its write
        return None              # warned about where the folder cannot be written either)
    try:
        payload = unseal(blob)
    except Damaged as e:
        discard(path, str(e), what)
        return None
    try:
        os.utime(path)                # recently used: dropped last
    except OSError:
        pass
    return payload


def _read(path: Path, convert=_from_plain):
    """``convert`` of what the sealed file at ``path`` holds, or None (no file, or a damaged
    one: removed, with a warning, and made again by the caller)."""
    payload = read_sealed(path, "state-space fit cache entry")
    if payload is None:
        return None
    try:
        return convert(pickle.loads(payload))
    except Exception as e:           # sealed but not ours to read (another code's pickle)
        discard(path, f"its pickle cannot be read ({type(e).__name__}: {e})",
                "state-space fit cache entry")
        return None


def write_whole(path: Path, write) -> None:
    """Write a cache file whole or not at all: ``write(f)`` into a file beside ``path`` (its
    folder made), then renamed onto it (another process may read it now); the aside file is
    removed if anything fails, and the error raised."""
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=path.parent, suffix=".tmp")
    try:
        with os.fdopen(fd, "wb") as f:
            write(f)
        os.replace(tmp, path)
    except BaseException:
        try:
            os.unlink(tmp)
        except OSError:
            pass
        raise


def _write(folder: Path, path: Path, plain) -> None:
    """Pickle ``plain`` into ``path`` whole, then trim ``folder``; a folder that cannot be written
    is warned about once."""
    global _warned
    try:
        blob = seal(pickle.dumps(plain, protocol=pickle.HIGHEST_PROTOCOL))
        write_whole(path, lambda f: f.write(blob))
        trim(folder)
    except Exception as e:            # the cache is a shortcut: never the reason a run fails
        if not _warned:
            warnings.warn(f"the state-space fit cache {folder} cannot be written ({e}); fits are "
                          "kept in this process only. Set MFM_FIT_CACHE to a writable folder, or "
                          "to off", RuntimeWarning, stacklevel=4)
            _warned = True


def trim(folder: Path, limit: int = CACHE_BYTES, pattern: str = "*.pkl") -> None:
    """Drop the least recently used files matching ``pattern`` (the fits by default) until they
    hold at most ``limit`` bytes."""
    files = []
    for p in folder.glob(pattern):
        try:
            st = p.stat()
        except OSError:
            continue
        files.append((st.st_mtime, st.st_size, p))
    total = sum(s for _, s, _ in files)
    for _, size, p in sorted(files):
        if total <= limit:
            break
        try:
            p.unlink()
            total -= size
        except OSError:
            pass


def cached_fit(db, stored=None, **options):
    """:func:`hydro.statespace.fit_state_space` (``db``, ``options``), from the process's fits,
    else the database file ``stored`` (a fit ``mfm fits`` put there, :mod:`hydro.fitstore`), else
    the disk cache, else fitted (and kept in the process and on disk). ``MFM_FIT_CACHE=off``
    reads neither the folder nor the database file."""
    hashed = database_hash(db)              # once for both keys: most of a key's cost
    key = fit_key(db, options, hashed=hashed)
    # `mfm fits` (recording) stores what it makes even where nothing stored is read
    read = reads_stored(stored)
    recording_ = stored is not None and recording_now()
    if key in _memory:
        _memory.move_to_end(key)
        skey = fitstore.fit_key(db, options, hashed=hashed) if recording_ else None
        return record(stored, skey, "fit", _memory[key])
    skey = fitstore.fit_key(db, options, hashed=hashed) if read or recording_ else None
    if read:
        fit = fitstore.read(stored, skey, "fit")
        if fit is not None:
            return record(stored, skey, "fit",
                           _remember(key, _with_source(fit, f"{stored} (stored)")))
    folder = cache_dir()
    path = None if folder is None else folder / f"{key}.pkl"
    fit = None if path is None else _read(path)
    if fit is not None:
        return record(stored, skey, "fit", _remember(key, _with_source(fit, str(path))))
    from .statespace import fit_state_space

    fit = fit_state_space(db, **options)
    if path is not None:
        _write(folder, path, _to_plain(fit))
    return record(stored, skey, "fit", _remember(key, _with_source(fit, "")))


# what :func:`recording` collects: {(database path, stored key): (kind, fit or value)}
_recorder: dict | None = None


@contextlib.contextmanager
def recording():
    """Collect every fit and value asked for with a database file (``stored=``) while the block
    runs: ``with recording() as made: ...`` gives ``made[(path, key)] = (kind, item)``, what
    ``mfm fits`` stores in that file (:func:`hydro.fitstore.store`)."""
    global _recorder
    before, _recorder = _recorder, {}
    try:
        yield _recorder
    finally:
        _recorder = before


def recording_now() -> bool:
    """Whether :func:`recording` is collecting (so that a caller packs an item only then)."""
    return _recorder is not None


def record(stored, skey, kind, item):
    """Note ``item`` (of ``kind``, under the stored key ``skey``, for the database file
    ``stored``) for :func:`recording`, when it records; returns ``item``. Also what makes
    other stored kinds (mfm's mooring tables) call."""
    if _recorder is not None and skey is not None:
        _recorder[(str(stored), skey)] = (kind, item)
    return item


def cached_value(db, name: str, options: dict, compute, stored=None):
    """``compute()``, a value made from ``db`` alone (a float or an array) that every process
    would make again: kept like the fits, in the process and on disk, under :func:`fit_key` of
    ``db`` and ``{"value": name, **options}``. What uses it: the radiation memory T_K and the
    consistent A∞ of :class:`hydro.prepare.HydroSpec` (0.4–0.5 s and 0.2–1.6 s each for M4 134 and
    Wu & Yuan, in every first run before). A value read back equals the one written to the last
    bit; an array comes back read-only. ``stored``: the database file, read first for a value
    ``mfm fits`` stored there (:mod:`hydro.fitstore`)."""
    hashed = database_hash(db)                                 # as in cached_fit
    key = fit_key(db, {"value": name, **options}, hashed=hashed)
    read = reads_stored(stored)
    recording_ = stored is not None and recording_now()
    if key in _values:
        skey = fitstore.value_key(db, name, options, hashed=hashed) if recording_ else None
        return record(stored, skey, "value", _values[key])
    skey = fitstore.value_key(db, name, options, hashed=hashed) if read or recording_ else None
    if read:
        value = fitstore.read(stored, skey, "value")
        if value is not None:
            return record(stored, skey, "value", _keep(key, value))
    folder = cache_dir()
    path = None if folder is None else folder / f"{key}.pkl"
    value = None if path is None else _read(path, _readonly)
    if value is not None:
        return record(stored, skey, "value", _keep(key, value))
    value = _readonly(compute())
    if path is not None:
        _write(folder, path, value)
    return record(stored, skey, "value", _keep(key, value))


def _keep(key, value):
    """Keep a value in the process (apart from the fits: small, and never evicting one)."""
    _values[key] = value
    return value


def _readonly(value):
    if isinstance(value, np.ndarray):
        value = np.array(value)
        value.setflags(write=False)
    return value
