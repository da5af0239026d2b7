"""XLA settings mfm needs before jax starts its CPU backend (imported first by ``mfm/__init__``).

**Time loops compiled as one function.** XLA on a CPU runs a compiled program as a sequence of
kernels, and pays about a quarter of a microsecond to dispatch each (benchmarks/RESULTS.md, "Where
the M4 134 step's time goes"). A time step of M4 134 is ~140 such kernels of a few hundred flops
each, so dispatch, not arithmetic, set its cost. XLA can instead compile a while loop whose
iteration touches few bytes as one native function (its ``small_while_loop_hoisting`` pass, keyed
by the backend option ``xla_cpu_small_while_loop_byte_threshold``, default 1 kB). mfm raises that
threshold to :data:`LOOP_BYTES` so that the time loops of its rollouts qualify (M4 134 with exact
radiation reads ~0.5 MB per step): M4 134's step 33 → 17 µs, its mechanics alone 16.5 → 4.3 µs
(``python benchmarks/step_profile.py``). The numbers are the same to round-off (the same HLO, one
emitter instead of another). RM3 in a regular wave, 2,000 steps: RK4 with convolution 241 → 93 ms,
with state space 82 → 18 ms, Verlet with exact radiation 26 → 7 ms. Loops that read more than
16 MiB per iteration keep the kernel-by-kernel runtime, whose library matrix products pay for large
operands. The price is compile time: LLVM optimises the loop as one function (M4 134: Verlet
8.4 → 8.8 s, RK4 14 → 31 s).

The whole-loop compilation refuses scatters, library (LAPACK) calls and library fusions, so the
time step avoids the first two (static 0/1 sums, unrolled elimination) and mfm also turns off
XLA's experimental YNNPACK fusions (``--xla_cpu_experimental_ynn_fusion_type=``), into which XLA
rewrote some small multiply–reduces (this also made batches of 4–128 cases 20–35 % faster).

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

XLA reads ``XLA_FLAGS`` once, when jax starts its backend: mfm adds the option there at import,
unless ``XLA_FLAGS`` already names it (yours wins; ``=1024`` restores XLA's default). If jax's
backend is already running when mfm is imported (jax used before ``import mfm``), the option cannot
take effect any more: :data:`LOOPS_COMPILED_WHOLE` is then False, a :class:`PerformanceWarning`
says so, and results record it (``xla_time_loop`` in their provenance).
"""
from __future__ import annotations

import os
import re
import warnings

OPTION = "xla_cpu_small_while_loop_byte_threshold"
YNN_OPTION = "xla_cpu_experimental_ynn_fusion_type"
# bytes one loop iteration may read and still be compiled whole: above M4 134's ~0.5 MB with room
# for larger trees, below the tens of MB where library matrix products pay (convolution histories,
# batches of many cases)
LOOP_BYTES = 16 * 2**20


class PerformanceWarning(UserWarning):
    """A setting that makes mfm slower than it could be, without changing its results."""


def _backend_running() -> bool:
    try:
        from jax._src import xla_bridge
        return bool(xla_bridge.backends_are_initialized())
    except Exception:   # a jax without this private helper: assume not started
        return False


def with_loop_option(flags: str, threshold: int = LOOP_BYTES) -> str:
    """XLA_FLAGS ``flags`` with the option added (into an existing ``--xla_backend_extra_options``,
    which holds all extra options comma-separated); unchanged if it already names the option."""
    if OPTION in flags:
        return flags
    m = re.search(r"--xla_backend_extra_options=(\S*)", flags)
    if m:
        value = f"{m.group(1)},{OPTION}={threshold}" if m.group(1) else f"{OPTION}={threshold}"
        return flags[:m.start()] + f"--xla_backend_extra_options={value}" + flags[m.end():]
    return f"{flags} --xla_backend_extra_options={OPTION}={threshold}".strip()


def without_library_fusions(flags: str) -> str:
    """XLA_FLAGS ``flags`` with XLA's experimental YNNPACK fusions off (unless they name the
    option): XLA may rewrite a small multiply–reduce of a time step into one (Stansby & Li's HᵀA∞H,
    Wu & Yuan's radiation output), and the whole-loop compilation refuses library fusions, so one
    such product would send the whole loop back to kernel-by-kernel dispatch."""
    if YNN_OPTION in flags:
        return flags
    return f"{flags} --{YNN_OPTION}=".strip()


def _set_flags() -> tuple[bool, str]:
    """Add the option to XLA_FLAGS if absent; (whether it is in effect, the threshold in bytes)."""
    flags = os.environ.get("XLA_FLAGS", "")
    given = re.search(OPTION + r"=(\d+)", flags)
    if given:
        return int(given.group(1)) > 1024, given.group(1)
    if _backend_running():
        warnings.warn(
            "mfm was imported after jax started its backend, so XLA cannot compile mfm's time loops "
            f"as one function any more ({OPTION}; see mfm._xla): rollouts of small models run up "
            "to ~2x slower, with the same results. Import mfm before using jax, or set XLA_FLAGS="
            f"'--xla_backend_extra_options={OPTION}={LOOP_BYTES}' before starting Python.",
            PerformanceWarning, stacklevel=3)
        return False, "1024"
    os.environ["XLA_FLAGS"] = without_library_fusions(with_loop_option(flags))
    return True, str(LOOP_BYTES)


LOOPS_COMPILED_WHOLE, LOOP_THRESHOLD = _set_flags()


# what turns one of mfm's environment switches off (MFM_COMPILATION_CACHE, MFM_PROGRAM_CACHE,
# MFM_GC_FREEZE, MFM_FAST_COMPILE; hydro's MFM_FIT_CACHE reads the same words in
# hydro/fitcache.py, which never imports mfm)
OFF_VALUES = ("off", "0", "false", "no", "none")


def switched_off(setting: str | None) -> bool:
    """Whether an environment variable's value (None: unset) says off."""
    return (setting or "").strip().lower() in OFF_VALUES


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
# programs that took at least this long to compile are kept (jax's default is 1 s)
MIN_COMPILE_SECONDS = 0.1


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
    if jax.config.jax_persistent_cache_min_compile_time_secs == 1.0:     # jax's default
        # a first run also compiles a dozen programs of 0.1–0.6 s (tables, the memories' start,
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


COMPILATION_CACHE = _set_cache()
