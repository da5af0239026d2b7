import os

# One BLAS thread: the state-space fits and small solves are faster and steadier that way on the
# 2-core CI machine (threaded BLAS measured up to 10× slower on first calls under load).
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("MPLBACKEND", "Agg")
# the command line freezes the collector's objects (mfm/runner/collector.py: it owns its process);
# tests call it inside their own process, whose objects must stay collectable
os.environ.setdefault("MFM_GC_FREEZE", "off")
# XLA's cheapest optimisation (set before jax starts): compiling is most of most tests' time and
# their runs are short; the numbers agree to round-off. Measured on tests/test_device_ptos.py, both
# runs side by side on the same loaded machine: 229 s -> 211 s; the README blocks' subprocess
# 114 s -> 71 s. The notebook kernels get the same flags (test_cli_notebooks.run_in_smoke_mode).
XLA_FAST_COMPILE = "--xla_backend_optimization_level=0 --xla_llvm_disable_expensive_passes=true"
if "xla_backend_optimization_level" not in os.environ.get("XLA_FLAGS", ""):
    os.environ["XLA_FLAGS"] = (os.environ.get("XLA_FLAGS", "") + " " + XLA_FAST_COMPILE).strip()

# One persistent XLA compilation cache for the whole run, shared by both pytest workers, the
# notebook kernels and the subprocesses (they inherit the environment): the same model's
# linearisation or rollout compiled in several processes is compiled once. Made fresh for each run
# by the controller (before the workers start) and removed at its end, so a run never reads an
# earlier run's compilations and times as CI does; a cache dir given from outside is kept as given.
# Measured: hallak_wec's first linear_system 37 s -> 12 s in a second process.
# The state-space fits likewise (hydro.fitcache): one folder for the run, so a config fitted in
# one worker or notebook is read back in the others, and never an earlier run's fits.
if "PYTEST_XDIST_WORKER" not in os.environ:
    import atexit
    import shutil
    import tempfile

    for _VAR, _PREFIX in (("JAX_COMPILATION_CACHE_DIR", "mfm-jax-cache-"),
                          ("MFM_FIT_CACHE", "mfm-fit-cache-")):
        if _VAR not in os.environ:
            os.environ[_VAR] = tempfile.mkdtemp(prefix=_PREFIX)
            atexit.register(shutil.rmtree, os.environ[_VAR], ignore_errors=True)
# cache the small compilations too (the default keeps only those over 1 s)
os.environ.setdefault("JAX_PERSISTENT_CACHE_MIN_COMPILE_TIME_SECS", "0.05")
os.environ.setdefault("JAX_PERSISTENT_CACHE_MIN_ENTRY_SIZE_BYTES", "0")

import jax  # noqa: E402

jax.config.update("jax_enable_x64", True)

from pathlib import Path  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
CONFIGS = ROOT / "configs"


import pytest  # noqa: E402


@pytest.fixture(autouse=True, scope="module")
def _fresh_jax_caches():
    """A worker past RSS_LIMIT after a module drops the compiled functions it holds: the frequency
    domain's compiled linearisations are cached per model structure, and a worker that runs dozens
    of modules would otherwise keep every model's (and its database's) compilation (5.6 GB seen).
    Below the limit the next module reuses them: clearing after every module recompiled the same
    models module after module."""
    yield
    if _resident_bytes() > RSS_LIMIT:
        jax.clear_caches()


RSS_LIMIT = 3 * 2**30


def _resident_bytes() -> int:
    """This process's resident memory (Linux /proc; elsewhere unknown: treated as over the limit)."""
    try:
        with open("/proc/self/statm") as f:
            return int(f.read().split()[1]) * os.sysconf("SC_PAGE_SIZE")
    except (OSError, ValueError, IndexError, AttributeError):
        return RSS_LIMIT + 1


# ---------------------------------------------------------------------- fixtures shared by files
import collections  # noqa: E402


@pytest.fixture(scope="module")
def sphere_db():
    """The sphere's database as its loaded model's water sees it (configs/sphere.toml)."""
    import mfm

    return mfm.load(CONFIGS / "sphere.toml", hydro=True).hydro.database()


def fresh_programs(monkeypatch, folder):
    """A traced-program folder of the test's own (mfm.runner.programs) and its empty in-process
    tables, as a new process finds them."""
    from mfm.runner import programs

    monkeypatch.setattr(programs, "folder", lambda: folder)
    monkeypatch.setattr(programs, "_MADE", {})
    monkeypatch.setattr(programs, "_ORDINARY_ONCE", {})


@pytest.fixture
def fit_cache(tmp_path, monkeypatch):
    """An empty fit-cache folder (MFM_FIT_CACHE, not made yet) and empty in-process caches of
    hydro.fitcache: its fits, its values and the damaged entries it has already reported."""
    from hydro import fitcache

    monkeypatch.setenv("MFM_FIT_CACHE", str(tmp_path / "fits"))
    monkeypatch.setattr(fitcache, "_memory", collections.OrderedDict())
    monkeypatch.setattr(fitcache, "_values", {})
    monkeypatch.setattr(fitcache, "_discarded", set())
    return tmp_path / "fits"
