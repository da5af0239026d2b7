"""The compilation options and the persistent compilation cache of the runner.

**Compiled programs kept on disk.** A fresh Python process compiles every program again: for
M4 134 with :func:`mfm.simulate`'s defaults that is most of its first call. mfm therefore turns on
jax's persistent compilation cache (programs that took ≥ 0.1 s to compile, under
``$XDG_CACHE_HOME/mfm/jax``, default ``~/.cache/mfm/jax``, at most :data:`CACHE_BYTES`, the least
recently used dropped first), so a later process with the same model, options, jax and XLA flags
loads them instead. The results are the same bits (the same executable). Set
``MFM_COMPILATION_CACHE`` to a folder to use that one, or to ``off`` to keep no cache; jax's own
setting (``JAX_COMPILATION_CACHE_DIR`` or ``jax.config``) wins over both.

In the folder mfm chooses, each entry is sealed with the sha256 of its content and put in place
whole (written beside, then renamed: :class:`_SealedCache`); jax alone writes in place and never
replaces an entry, so a torn one (a kill, a full disk) was warned about and compiled again on
every run. Now an entry that fails its check is removed, said once, compiled again and replaced.
A folder named by jax's own setting is left in jax's format (other programs may share it).

The cache is turned on by ``mfm.load`` or the runner's first program, whichever comes first
(:func:`compilation_cache`, from :func:`mfm.io.build.load` and :func:`mfm.runner.programs.folder`), not at import: ``import mfm`` makes no folder and changes no jax setting.
"""
from __future__ import annotations

import contextlib
import os
import threading

from ..backend import switched_off

# A program run once per call (a linearisation's Jacobians, the joints' reaction derivatives,
# the moved dofs' samples) is compiled with XLA's backend at its lowest optimisation level: its
# compilation is what the user waits for, its run a few milliseconds. M4 134's jet: 5.0–6.3 ->
# 3.6–4.0 s to compile, 0.5 -> 1.4 ms to run; the same numbers to 1e-15. A time loop keeps
# XLA's default (it runs 8x slower at level 0: benchmarks/RESULTS.md).
ONCE_OPTIONS = {"xla_backend_optimization_level": 0}
ONCE_ENV = "MFM_FAST_COMPILE"


def once_options() -> dict | None:
    """The compiler options of a program run once per call (:data:`ONCE_OPTIONS`) on a CPU, or
    None: on another backend (not measured), where ``XLA_FLAGS`` sets the optimisation level
    itself (yours wins), or with ``MFM_FAST_COMPILE=off``."""
    import jax

    if (switched_off(os.environ.get(ONCE_ENV))
            or "xla_backend_optimization_level" in os.environ.get("XLA_FLAGS", "")
            or jax.default_backend() != "cpu"):
        return None
    return dict(ONCE_OPTIONS)


CACHE_ENV = "MFM_COMPILATION_CACHE"
# the most the cache folder mfm chooses may hold (jax drops the least recently used beyond it)
CACHE_BYTES = 2 * 2**30
# programs that took at least this long to compile are kept (jax's default is 1 s): all of them.
# A first answer still compiles a few small programs of 10–50 ms each (the loads' memories at
# rest, H at q0, the frequency domain's wrench maps) that a later process would compile again;
# read back, each costs ~1 ms
MIN_COMPILE_SECONDS = 0.0


def default_cache_dir() -> str:
    """``$XDG_CACHE_HOME/mfm/jax`` (default ``~/.cache/mfm/jax``)."""
    base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    return os.path.join(base, "mfm", "jax")


def _set_cache() -> str | None:
    """Turn on jax's persistent compilation cache unless jax already has one or
    ``MFM_COMPILATION_CACHE`` is off; returns the folder in use (None: no cache)."""
    import jax

    own = jax.config.jax_compilation_cache_dir
    if own:
        return own
    setting = os.environ.get(CACHE_ENV, "").strip()
    if switched_off(setting):
        return None
    path = setting or default_cache_dir()
    _seal_entries(path)
    jax.config.update("jax_compilation_cache_dir", path)
    _portable_keys()
    if jax.config.jax_persistent_cache_min_compile_time_secs == 1.0:     # jax's default
        # a first run also compiles a dozen programs of 0.01–0.6 s (tables, the memories' start,
        # the radiation's samples): RM3 1.9 s of a cached first call's 7 s
        jax.config.update("jax_persistent_cache_min_compile_time_secs", MIN_COMPILE_SECONDS)
    if jax.config.jax_compilation_cache_max_size == -1:
        try:
            import filelock  # noqa: F401  (jax bounds the cache only with it: a dependency of mfm)
        except ImportError:
            pass
        else:
            jax.config.update("jax_compilation_cache_max_size", CACHE_BYTES)
    return path



def _portable_keys() -> None:
    """Keep the cache's folder out of its entries' keys on a CPU: jax's default
    ``jax_persistent_cache_enable_xla_caches`` puts a GPU autotuning folder inside the cache's
    folder into every compilation's options, and its key hashes them, path and all: a warm cache
    copied or moved to another folder was compiled again, entry by entry (RM3's first run 38.7 s
    there against 5.5 s; issue 54, item 18). A CPU has no autotuning to keep; on a GPU (where it
    saves the autotuning of a program compiled again) and where the setting is yours, it stays."""
    import jax

    try:
        if (jax.config.jax_persistent_cache_enable_xla_caches == _JAX_XLA_CACHES
                and jax.default_backend() == "cpu"):
            jax.config.update("jax_persistent_cache_enable_xla_caches", "none")
    except AttributeError:       # a jax without the setting: no such folder in the options
        pass


# jax's default of jax_persistent_cache_enable_xla_caches (0.4.36 to today)
_JAX_XLA_CACHES = "xla_gpu_per_fusion_autotune_cache_dir"


def _seal_entries(path: str) -> None:
    """Have jax keep its compilation cache at ``path`` (mfm's folder) in :class:`_SealedCache`:
    by wrapping jax's ``get_file_cache``, which makes the cache when jax first compiles. A jax
    without these internals keeps its own cache (mfm's entries then read as damaged there and
    are compiled again: never a wrong answer)."""
    try:
        from jax._src import compilation_cache as cc
        from jax._src.lru_cache import LRUCache
    except Exception:
        return
    if getattr(cc.get_file_cache, "_mfm_sealed", None) is not None:
        cc.get_file_cache._mfm_sealed.add(os.path.abspath(path))
        return
    jax_own = cc.get_file_cache
    sealed_paths = {os.path.abspath(path)}

    def get_file_cache(where):
        made = jax_own(where)
        if (made is not None and type(made[0]) is LRUCache and isinstance(where, str)
                and os.path.abspath(where) in sealed_paths):
            try:
                return _sealed_cache(LRUCache)(where, max_size=made[0].max_size if
                                               made[0].eviction_enabled else -1), made[1]
            except Exception:
                return made
        return made

    get_file_cache._mfm_sealed = sealed_paths
    cc.get_file_cache = get_file_cache


_sealed_class = None


def _sealed_cache(base):
    """jax's :class:`LRUCache` whose entries carry the sha256 of their content
    (:func:`hydro.fitcache.seal`), are written whole (beside, then renamed) and replaced when
    written again, and whose damaged entries are removed with a warning naming the file."""
    global _sealed_class
    if _sealed_class is not None:
        return _sealed_class
    from hydro import fitcache

    what = "jax compilation cache entry"

    class _SealedCache(base):
        def _file(self, key):
            return self.path / f"{key}-cache"

        def get(self, key):
            blob = super().get(key)
            if blob is None:
                return None
            try:
                return fitcache.unseal(blob)
            except fitcache.Damaged as e:
                if not blob.startswith(fitcache.MAGIC) and _jax_readable(blob):
                    return blob            # an entry jax wrote before mfm sealed them
                self._drop(key, str(e))
                return None

        def _drop(self, key, why):
            with self._locked():
                try:
                    os.unlink(self.path / f"{key}-atime")
                except OSError:
                    pass
                fitcache.discard(self._file(key), why, what)

        def _locked(self):
            import contextlib

            if not self.eviction_enabled:
                return contextlib.nullcontext()
            self.lock.acquire(timeout=self.lock_timeout_secs)

            @contextlib.contextmanager
            def held():
                try:
                    yield
                finally:
                    self.lock.release()
            return held()

        def put(self, key, value):
            # jax puts only what it compiled: the entry was missing or damaged, so replace it
            blob = fitcache.seal(value)
            if self.eviction_enabled and len(blob) > self.max_size:
                return super().put(key, value)        # jax's own refusal and warning
            import time

            with self._locked():
                self._evict_if_needed(additional_size=len(blob))
                atime = self.path / f"{key}-atime"
                atime.write_bytes(time.time_ns().to_bytes(8, "little"))
                fitcache.write_whole(self._file(key), lambda f: f.write(blob))

    _sealed_class = _SealedCache
    return _SealedCache


def _jax_readable(blob: bytes) -> bool:
    """Whether an unsealed entry decompresses as jax's (its own check: zlib's adler32)."""
    try:
        from jax._src import compilation_cache as cc

        cc.decompress_executable(blob)
        return True
    except Exception:
        return False


# the folder of jax's persistent cache in use (None: none), once a front door has run
COMPILATION_CACHE: str | None = None
_installed = False
_install_lock = threading.Lock()


def compilation_cache() -> str | None:
    """Turn on the persistent compilation cache (:func:`_set_cache`) the first time a front door
    runs; returns the folder in use (None: no cache). Programs jax compiled before it (a user's
    own, before the first front door) were compiled without a cache: jax is told to look again
    (its ``reset_cache``), so that the programs after it use the folder."""
    global COMPILATION_CACHE, _installed
    if _installed:
        return COMPILATION_CACHE
    with _install_lock:
        if not _installed:
            COMPILATION_CACHE = _set_cache()
            if COMPILATION_CACHE is not None:
                try:
                    from jax._src import compilation_cache as cc

                    if cc._cache_checked and not cc._cache_used:
                        cc.reset_cache()
                except Exception:       # a jax without these internals: its own behaviour
                    pass
            _installed = True
    return COMPILATION_CACHE


# ------------------------------------------------------------------------------ counting programs
class Compilations:
    """What jax did for the programs of a block of code (:func:`counting`), counted from
    :mod:`jax.monitoring`'s events, in every thread of the process while the block runs:

    - ``compiled``: programs XLA compiled (not found in the persistent compilation cache);
    - ``loaded``: programs read back from that cache instead of compiled;
    - ``traced``: functions jax traced to a jaxpr (a program kept on disk by
      :mod:`mfm.runner.programs` is neither traced nor lowered again).

    A counter, not a timer: the same on any machine and at any load."""

    def __init__(self):
        self.backend = 0            # jax's backend compilations: it times a cache hit as one too
        self.loaded = 0
        self.traced = 0

    @property
    def compiled(self) -> int:
        return self.backend - self.loaded

    def __repr__(self):
        return (f"Compilations(compiled={self.compiled}, loaded={self.loaded}, "
                f"traced={self.traced})")


_counters: list = []
_counters_lock = threading.Lock()
_listening = False


def _on_event(event, **_):
    if event == "/jax/compilation_cache/cache_hits":
        with _counters_lock:
            for c in _counters:
                c.loaded += 1


def _on_duration(event, _seconds, **_):
    field = ("backend" if event.endswith("/backend_compile_duration") else
             "traced" if event.endswith("/jaxpr_trace_duration") else None)
    if field is None:
        return
    with _counters_lock:
        for c in _counters:
            setattr(c, field, getattr(c, field) + 1)


@contextlib.contextmanager
def counting():
    """Count jax's compilations while the block runs: ``with counting() as c: ...`` then
    ``c.compiled``, ``c.loaded``, ``c.traced`` (:class:`Compilations`)."""
    import jax.monitoring

    global _listening
    with _counters_lock:
        if not _listening:
            jax.monitoring.register_event_listener(_on_event)
            jax.monitoring.register_event_duration_secs_listener(_on_duration)
            _listening = True
    c = Compilations()
    with _counters_lock:
        _counters.append(c)
    try:
        yield c
    finally:
        with _counters_lock:
            _counters.remove(c)
