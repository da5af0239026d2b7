"""Issue 54 item 13: a damaged cache entry is found by its checksum, removed, said once and made
again, and the answer is a clean cache's to the bit. Every kind of entry mfm keeps:

- the state-space fit cache's fits and values (hydro.fitcache, ``MFM_FIT_CACHE``);
- the traced programs (mfm.runner.programs, ``<compilation cache>/mfm-programs``);
- jax's compilation cache in the folder mfm chooses (mfm.runner.xla: the entries jax writes there).

Before: a flipped bit in a fit's pickle changed the answer silently on every later run; in a
traced program every later run crashed ("Failed to deserialize StableHLO"); a torn compilation
entry was warned about and compiled again on every run, never replaced (jax writes in place and
never overwrites). Independent reference: the same call on a clean cache, compared bit for bit.
"""
from __future__ import annotations

import os
import pickle
import subprocess
import sys
import warnings
import zlib
from pathlib import Path

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from conftest import CONFIGS, ROOT, fresh_programs

import mfm
from hydro import fitcache as FC
from mfm.runner import programs as _programs, xla as _xla

pytestmark = pytest.mark.filterwarnings("ignore::hydro.database.HydroDatabaseWarning")


def flip(path: Path, where: float = 2 / 3) -> None:
    """Flip one bit of the file at ``path`` (in its payload, past the seal's header)."""
    b = bytearray(path.read_bytes())
    b[int(len(b) * where)] ^= 0x10
    path.write_bytes(bytes(b))


def sealed(path: Path) -> bool:
    try:
        FC.unseal(path.read_bytes())
        return True
    except FC.Damaged:
        return False


def damaged_warnings(record, path) -> list:
    return [w for w in record if issubclass(w.category, FC.CacheWarning)
            and str(path) in str(w.message)]


def test_the_seal_finds_every_flipped_bit_and_every_cut():
    payload = bytes(range(256)) * 4
    blob = FC.seal(payload)
    assert FC.unseal(blob) == payload
    for i in range(len(blob)):
        for bit in (0x01, 0x80):
            b = bytearray(blob)
            b[i] ^= bit
            with pytest.raises(FC.Damaged):
                FC.unseal(bytes(b))
    for n in (0, 5, len(FC.MAGIC) + 10, len(blob) - 1):
        with pytest.raises(FC.Damaged):
            FC.unseal(blob[:n])


def test_a_flipped_bit_in_a_stored_fit_is_fitted_again_to_the_bit(sphere_db, fit_cache):
    clean = FC.cached_fit(sphere_db)
    (path,) = fit_cache.glob("*.pkl")
    assert sealed(path)
    flip(path)
    FC.clear()
    with warnings.catch_warnings(record=True) as record:
        warnings.simplefilter("always")
        again = FC.cached_fit(sphere_db)
    assert len(damaged_warnings(record, path)) == 1, [str(w.message) for w in record]
    assert "sha256" in str(damaged_warnings(record, path)[0].message)
    assert again.report["cache"] == ""               # fitted, not read
    for name in ("A", "B", "C", "added_mass_inf"):
        np.testing.assert_array_equal(getattr(again, name), getattr(clean, name))
    assert sealed(path)                              # repaired: the next process reads it
    FC.clear()
    assert FC.cached_fit(sphere_db).report["cache"] == str(path)


def test_a_flipped_bit_in_a_stored_value_is_made_again(fit_cache):
    spec = mfm.load(CONFIGS / "sphere.toml").hydro
    T_K, A_inf = spec.memory(), np.array(spec.added_mass_inf())
    files = sorted(fit_cache.glob("*.pkl"))
    assert len(files) == 2
    for p in files:
        flip(p)
    FC.clear()
    with warnings.catch_warnings(record=True) as record:
        warnings.simplefilter("always")
        spec = mfm.load(CONFIGS / "sphere.toml").hydro
        assert spec.memory() == T_K
        np.testing.assert_array_equal(spec.added_mass_inf(), A_inf)
    for p in files:
        assert len(damaged_warnings(record, p)) == 1
        assert sealed(p)


def test_an_unsealed_or_torn_entry_is_made_again_never_read(sphere_db, fit_cache):
    # an entry of the format before the seal (a bare pickle), even one that unpickles into a
    # plausible fit, is not trusted: removed and fitted again; a torn one likewise
    clean = FC.cached_fit(sphere_db)
    (path,) = fit_cache.glob("*.pkl")
    path.write_bytes(pickle.dumps(FC._to_plain(clean)))
    FC.clear()
    with pytest.warns(FC.CacheWarning, match="not a sealed"):
        assert FC.cached_fit(sphere_db).report["cache"] == ""
    assert sealed(path)
    path.write_bytes(path.read_bytes()[:40])
    FC.clear()
    with pytest.warns(FC.CacheWarning, match="torn"):
        assert FC.cached_fit(sphere_db).report["cache"] == ""
    assert sealed(path)


@jax.jit
def _affine(p, x):
    return {"y": p["a"] @ x + p["b"], "n": jnp.sum(x)}


def test_a_flipped_bit_in_a_traced_program_is_made_anew(monkeypatch, tmp_path):
    fresh_programs(monkeypatch, tmp_path)
    monkeypatch.setattr(FC, "_discarded", set())
    p = {"a": jnp.arange(9.0).reshape(3, 3), "b": jnp.ones(3)}
    x = jnp.arange(3.0)
    _programs.program(_affine, "affine", (p, x))
    (path,) = tmp_path.glob("affine-*.bin")
    assert sealed(path)
    flip(path, 0.8)               # in the StableHLO bytecode: it deserialised, then failed later
    monkeypatch.setattr(_programs, "_MADE", {})
    before = dict(_programs.COUNTS)
    with pytest.warns(FC.CacheWarning, match="traced program"):
        again = _programs.program(_affine, "affine", (p, x))
    assert _programs.COUNTS["saved"] == before["saved"] + 1
    assert _programs.COUNTS["loaded"] == before["loaded"]
    np.testing.assert_array_equal(again(p, x)["y"], _affine(p, x)["y"])
    assert sealed(path)
    monkeypatch.setattr(_programs, "_MADE", {})
    _programs.program(_affine, "affine", (p, x))
    assert _programs.COUNTS["loaded"] == before["loaded"] + 1


def _sealed_jax_cache(path):
    from jax._src.lru_cache import LRUCache

    return _xla._sealed_cache(LRUCache)(str(path), max_size=2**30)


def test_jax_entries_in_mfms_folder_are_sealed_replaced_and_repaired(tmp_path, monkeypatch):
    monkeypatch.setattr(FC, "_discarded", set())
    cache = _sealed_jax_cache(tmp_path)
    value = zlib.compress(np.random.default_rng(0).bytes(4000))     # 4 kB, as an executable
    cache.put("k", value)
    entry = tmp_path / "k-cache"
    assert sealed(entry) and cache.get("k") == value
    assert not list(tmp_path.glob("*.tmp"))
    # a flipped bit: removed with a warning naming the file, then compiled again and replaced
    flip(entry)
    with pytest.warns(FC.CacheWarning, match="k-cache"):
        assert cache.get("k") is None
    assert not entry.exists()
    cache.put("k", value)
    assert cache.get("k") == value
    # a torn entry (written in place by jax alone, cut by a kill or a full disk): jax's put
    # never replaced it; here it is removed on reading and the next put replaces it
    entry.write_bytes(entry.read_bytes()[:100])
    with pytest.warns(FC.CacheWarning):
        assert cache.get("k") is None
    cache.put("k", value)
    assert cache.get("k") == value
    # an entry jax wrote before mfm sealed them is still read (it passes jax's own zlib check)
    (tmp_path / "old-cache").write_bytes(value)
    (tmp_path / "old-atime").write_bytes((1).to_bytes(8, "little"))
    assert cache.get("old") == value
    # ... unless it is damaged
    (tmp_path / "bad-cache").write_bytes(value[:-3])
    (tmp_path / "bad-atime").write_bytes((1).to_bytes(8, "little"))
    with pytest.warns(FC.CacheWarning, match="bad-cache"):
        assert cache.get("bad") is None
    assert not (tmp_path / "bad-cache").exists()


def test_mfms_compilation_cache_folder_is_the_sealed_one(tmp_path):
    # the folder mfm chooses gets the sealed cache; one named by jax's own setting stays jax's
    code = (
        "import mfm, jax, jax.numpy as jnp\n"
        "assert mfm.runner.xla.COMPILATION_CACHE is None  # none at import\n"
        "mfm.runner.xla.compilation_cache()               # the first front door's\n"
        "jax.config.update('jax_persistent_cache_min_compile_time_secs', 0)\n"
        "jax.jit(lambda x: jnp.sin(x) * 2)(jnp.arange(3.0)).block_until_ready()\n"
        "from jax._src import compilation_cache as cc\n"
        "print(type(cc._cache).__name__, mfm.runner.xla.COMPILATION_CACHE)\n")
    env = {k: v for k, v in os.environ.items() if k != "JAX_COMPILATION_CACHE_DIR"}
    env.update(PYTHONPATH=str(ROOT), MFM_COMPILATION_CACHE=str(tmp_path / "mine"))
    out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True,
                         timeout=300, cwd=ROOT)
    assert out.returncode == 0, out.stderr
    assert out.stdout.split() == ["_SealedCache", str(tmp_path / "mine")]
    entries = list((tmp_path / "mine").glob("*-cache"))
    assert entries and all(sealed(p) for p in entries)
    env["JAX_COMPILATION_CACHE_DIR"] = str(tmp_path / "jaxs")
    out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True,
                         timeout=300, cwd=ROOT)
    assert out.returncode == 0, out.stderr
    assert out.stdout.split()[0] == "LRUCache"


def _snapshot(to: Path) -> Path:
    """mfm, hydro (its sphere database alone), mfm_cli.py and configs/sphere.toml copied."""
    import shutil

    skip = shutil.ignore_patterns("__pycache__", "*.pyc")
    shutil.copytree(ROOT / "mfm", to / "mfm", ignore=skip)
    shutil.copytree(ROOT / "hydro", to / "hydro", ignore=shutil.ignore_patterns(
        "__pycache__", "*.pyc", "data"))
    (to / "hydro" / "data").mkdir()
    shutil.copy2(ROOT / "hydro" / "data" / "sphere.nc", to / "hydro" / "data")
    shutil.copy2(ROOT / "mfm_cli.py", to)
    (to / "configs").mkdir()
    shutil.copy2(CONFIGS / "sphere.toml", to / "configs")
    return to


def test_every_damaged_entry_of_a_run_is_repaired_and_the_run_is_the_clean_ones(tmp_path):
    """The command line on fresh caches; one bit flipped in every entry each cache holds (fits
    and values, traced programs, jax's compilations); the next run gives the clean run's numbers
    bit for bit, names each damaged file once, and leaves every entry sealed and sound."""
    import xarray as xr

    # the runs use a copy of the source: a program's key holds the hash of every .py file, so an
    # edit in the working tree between two runs would name other programs
    src = _snapshot(tmp_path / "src")
    env = {k: v for k, v in os.environ.items() if k != "JAX_COMPILATION_CACHE_DIR"}
    env.update(PYTHONPATH=str(src), MFM_COMPILATION_CACHE=str(tmp_path / "jax"),
               MFM_FIT_CACHE=str(tmp_path / "fits"), PYTHONWARNINGS="default")

    def run(name):
        out = subprocess.run(
            [sys.executable, "-m", "mfm_cli", "simulate", str(src / "configs" / "sphere.toml"),
             "--duration", "2", "--wave", "regular", "--height", "1", "--period", "6",
             "--radiation", "state_space", "--no-plot", "--progress", "off",
             "--out", str(tmp_path / f"{name}.nc")],
            env=env, capture_output=True, text=True, timeout=600, cwd=src)
        assert out.returncode == 0, out.stderr
        return xr.load_dataset(tmp_path / f"{name}.nc"), out.stderr

    clean, _ = run("clean")
    kinds = {"fits": sorted((tmp_path / "fits").glob("*.pkl")),
             "programs": sorted((tmp_path / "jax" / "mfm-programs").glob("*.bin")),
             "compilations": sorted((tmp_path / "jax").glob("*-cache"))}
    assert all(kinds.values()), kinds
    for files in kinds.values():
        for p in files:
            assert sealed(p), p
            flip(p)
    again, stderr = run("again")
    for name in clean.data_vars:
        if np.issubdtype(clean[name].dtype, np.number):
            np.testing.assert_array_equal(again[name].values, clean[name].values, err_msg=name)
    for kind, files in kinds.items():
        for p in files:
            assert stderr.count(str(p)) == 1, (kind, p, stderr[-3000:])
            # made again and sealed; a compilation jax made faster this time than its threshold
            # for keeping one (jax_persistent_cache_min_compile_time_secs) is left removed
            assert sealed(p) if kind != "compilations" or p.exists() else True, (kind, p)
    assert sum(p.exists() for p in kinds["compilations"]) >= len(kinds["compilations"]) // 2
    _, stderr = run("third")
    assert "CacheWarning" not in stderr and "damaged" not in stderr, stderr[-3000:]
