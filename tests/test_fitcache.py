"""The state-space fit cache (hydro.fitcache): a fit read back from disk equals the fit made by
fit_state_space itself to the last bit; the key follows the data, the options and the code; a
damaged file is fitted again; ``off`` writes nothing; a folder that cannot be written warns once
and the fit is still returned; the folder is trimmed least recently used first.

Independent reference: hydro.statespace.fit_state_space called directly (no cache)."""
import collections
import dataclasses
import os
import warnings
from pathlib import Path

import numpy as np
import pytest

import mfm
from hydro import fitcache as FC
from hydro import statespace as S

CONFIGS = Path(__file__).resolve().parents[1] / "configs"
pytestmark = pytest.mark.filterwarnings("ignore::hydro.database.HydroDatabaseWarning")
ARRAYS = ("A", "B", "C", "added_mass_inf")


def _same_fit(a, b):
    for name in ARRAYS:
        np.testing.assert_array_equal(getattr(a, name), getattr(b, name), err_msg=name)
    assert a.dofs == b.dofs and a.entries == b.entries
    for pa, pb in zip(a.poles + a.residues, b.poles + b.residues):
        np.testing.assert_array_equal(pa, pb)


def test_a_fit_read_back_equals_the_fit(sphere_db, fit_cache):
    ref = S.fit_state_space(sphere_db)
    made = FC.cached_fit(sphere_db)
    files = list(fit_cache.glob("*.pkl"))
    assert len(files) == 1 and made.report["cache"] == ""
    _same_fit(made, ref)
    assert FC.cached_fit(sphere_db) is made              # the process keeps it
    FC.clear()                                   # a later process: from the file
    read = FC.cached_fit(sphere_db)
    assert read.report["cache"] == str(files[0])
    _same_fit(read, ref)
    assert {k: v for k, v in read.report.items() if k != "cache"} == \
        {k: v for k, v in made.report.items() if k != "cache"}
    assert not read.A.flags.writeable and not read.poles[0].flags.writeable
    # through the spec: HydroSpec.state_space uses it
    FC.clear()
    spec_fit = mfm.load(CONFIGS / "sphere.toml").hydro.state_space(omega_fit=(0.3, 3.0))
    assert len(list(fit_cache.glob("*.pkl"))) == 2 and spec_fit.report["cache"] == ""


def test_the_key_follows_data_options_and_code(sphere_db, monkeypatch):
    k = FC.fit_key(sphere_db, {})
    assert FC.fit_key(sphere_db.copy(deep=True), {}) == k
    assert FC.fit_key(sphere_db, {"order": 4}) != k
    db = sphere_db.copy(deep=True)
    B = db["radiation_damping"].values
    B.flat[np.flatnonzero(B)[0]] *= 1 + 1e-15           # one value, one ulp
    assert FC.fit_key(db, {}) != k
    # an array option differing in the middle (its repr would elide it): another key
    w = np.linspace(0.1, 10.0, 5000)
    w2 = w.copy()
    w2[2500] += 1e-9
    assert repr(w) == repr(w2)
    assert FC.fit_key(sphere_db, {"passivity_omega": w}) != \
        FC.fit_key(sphere_db, {"passivity_omega": w2})
    monkeypatch.setattr(FC, "_SOURCES", FC._SOURCES[:-1])  # other code: another key
    assert FC.fit_key(sphere_db, {}) != k


def test_a_database_hashed_once_keys_as_hashed_each_time(sphere_db):
    # cached_fit and cached_value hash the database once for their two keys (the disk cache's
    # and the database file's): the keys are those each would make alone, and the hash they
    # share is copied, not advanced, by each
    from hydro import contentkey, fitstore

    hashed = contentkey.database_hash(sphere_db)
    before = hashed.hexdigest()
    for _ in range(2):
        assert (FC.fit_key(sphere_db, {"order": 4}, hashed=hashed)
                == FC.fit_key(sphere_db, {"order": 4}))
        assert fitstore.fit_key(sphere_db, {}, hashed=hashed) == fitstore.fit_key(sphere_db, {})
        assert (fitstore.value_key(sphere_db, "memory", {"rtol": 1e-3}, hashed=hashed)
                == fitstore.value_key(sphere_db, "memory", {"rtol": 1e-3}))
    assert hashed.hexdigest() == before
    other = sphere_db.copy(deep=True)
    other.attrs["note"] = "another"
    assert FC.fit_key(other, {}) != FC.fit_key(sphere_db, {}, hashed=hashed)


def test_a_damaged_file_is_fitted_again(sphere_db, fit_cache):
    fit_cache.mkdir()
    path = fit_cache / f"{FC.fit_key(sphere_db, {})}.pkl"
    path.write_bytes(b"not a pickle")
    fit = FC.cached_fit(sphere_db)
    assert fit.report["cache"] == ""
    _same_fit(fit, S.fit_state_space(sphere_db))
    FC.clear()
    assert FC.cached_fit(sphere_db).report["cache"] == str(path)   # written anew


def test_off_writes_nothing(sphere_db, tmp_path, monkeypatch):
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path))
    monkeypatch.setenv("MFM_FIT_CACHE", "off")
    monkeypatch.setattr(FC, "_memory", collections.OrderedDict())
    assert FC.cache_dir() is None
    FC.cached_fit(sphere_db)
    assert not any(tmp_path.rglob("*.pkl"))
    monkeypatch.setenv("MFM_FIT_CACHE", "")
    assert FC.cache_dir() == tmp_path / "mfm" / "fits"


def test_a_folder_that_cannot_be_written_warns_once(sphere_db, tmp_path, monkeypatch):
    blocker = tmp_path / "file"
    blocker.write_text("a file where the folder would be")
    monkeypatch.setenv("MFM_FIT_CACHE", str(blocker / "fits"))
    monkeypatch.setattr(FC, "_memory", collections.OrderedDict())
    monkeypatch.setattr(FC, "_warned", False)
    with pytest.warns(RuntimeWarning, match="MFM_FIT_CACHE"):
        fit = FC.cached_fit(sphere_db)
    assert fit.report["cache"] == ""
    FC.clear()
    with warnings.catch_warnings():
        warnings.simplefilter("error", RuntimeWarning)
        FC.cached_fit(sphere_db, order=4)                # the second failure is silent
    assert not list(tmp_path.glob("**/*.tmp"))


def test_the_folder_is_trimmed_least_recently_used_first(tmp_path):
    for k, name in enumerate(("old", "middle", "new")):
        p = tmp_path / f"{name}.pkl"
        p.write_bytes(b"x" * 100)
        os.utime(p, (1000 + k, 1000 + k))
    (tmp_path / "other.txt").write_bytes(b"x" * 1000)     # not a fit: left alone
    FC.trim(tmp_path, limit=250)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["middle.pkl", "new.pkl", "other.txt"]


def test_plain_form_round_trips_every_field(sphere_db):
    fit = S.fit_state_space(sphere_db)
    back = FC._from_plain(FC._to_plain(fit))
    assert [f.name for f in dataclasses.fields(back)] == [f.name for f in dataclasses.fields(fit)]
    _same_fit(back, fit)
    assert dict(back.report) == dict(fit.report)


def test_memory_and_consistent_added_mass_read_back_equal_what_is_made(fit_cache, monkeypatch):
    # HydroSpec.memory() and its consistent A∞ (hydro.fitcache.cached_value): made once, then
    # read from the folder by a later process (a fresh spec, the process's values forgotten)
    # equal to the last bit without being made again; another rtol is another value
    from hydro import prepare, radiation

    def made():
        spec = mfm.load(CONFIGS / "sphere.toml").hydro
        return spec, spec.memory(), spec.added_mass_inf()

    spec, T_K, A_inf = made()
    ref_T = radiation.impulse_response_memory(spec.database(), np.arange(0.0, 400.0, 0.05),
                                              rtol=1e-3)
    assert T_K == ref_T
    np.testing.assert_array_equal(A_inf, spec._consistent_added_mass_inf())
    assert not A_inf.flags.writeable
    assert len(list(fit_cache.glob("*.pkl"))) == 2
    FC.clear()

    def never(*a, **k):
        raise AssertionError("made again, not read back")
    monkeypatch.setattr(radiation, "impulse_response_memory", never)
    monkeypatch.setattr(prepare.HydroSpec, "_consistent_added_mass_inf", never)
    _, T_K2, A_inf2 = made()
    assert T_K2 == T_K
    np.testing.assert_array_equal(A_inf2, A_inf)
    with pytest.raises(AssertionError, match="made again"):
        mfm.load(CONFIGS / "sphere.toml").hydro.memory(rtol=1e-2)
