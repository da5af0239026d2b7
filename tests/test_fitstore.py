"""Fits stored in the database file (hydro.fitstore, ``mfm fits``): a fit and the values read
back from the file equal what fit_state_space and the spec make to the last bit; the database
itself reads back identical; a fresh process finds them without fitting; a database whose
content differs finds none and fits; items made by other code are dropped when storing again;
the shipped databases' stored items are current.

Independent reference: hydro.statespace.fit_state_space called directly (no cache, no file)."""
import collections
import shutil
from pathlib import Path

import netCDF4
import numpy as np
import pytest
import xarray as xr

import mfm
from hydro import fitcache as FC
from hydro import fitstore as FS
from hydro import statespace as S
from hydro.database import read_netcdf
from mfm_cli import main

ROOT = Path(__file__).resolve().parents[1]
CONFIGS = ROOT / "configs"
pytestmark = pytest.mark.filterwarnings("ignore::hydro.database.HydroDatabaseWarning")


@pytest.fixture
def fresh(monkeypatch, tmp_path):
    """A process that has fitted nothing with an empty disk cache: what a new machine is."""
    monkeypatch.setenv("MFM_FIT_CACHE", str(tmp_path / "empty-fit-cache"))
    monkeypatch.setattr(FC, "_memory", collections.OrderedDict())
    monkeypatch.setattr(FC, "_values", {})


@pytest.fixture
def sphere(tmp_path):
    """The sphere's config and a copy of its database in tmp_path."""
    shutil.copy(ROOT / "hydro" / "data" / "sphere.nc", tmp_path / "sphere.nc")
    text = (CONFIGS / "sphere.toml").read_text()
    cfg = tmp_path / "sphere.toml"
    cfg.write_text(text.replace('"../hydro/data/sphere.nc"', '"sphere.nc"'))
    assert '"sphere.nc"' in cfg.read_text()
    return cfg, tmp_path / "sphere.nc"


def _same_fit(a, b, drop=("cache", "fit_seconds")):
    for name in ("A", "B", "C", "added_mass_inf"):
        x, y = getattr(a, name), getattr(b, name)
        assert x.dtype == y.dtype and np.array_equal(x.view(np.uint64), y.view(np.uint64)), name
    assert a.dofs == b.dofs and a.entries == b.entries
    assert len(a.poles) == len(b.poles) and len(a.residues) == len(b.residues)
    for pa, pb in zip(a.poles + a.residues, b.poles + b.residues):
        assert np.array_equal(pa.view(np.uint64), pb.view(np.uint64))
    assert {k: v for k, v in a.report.items() if k not in drop} == \
        {k: v for k, v in b.report.items() if k not in drop}


def test_stored_fit_and_values_read_back_to_the_bit(sphere, fresh, capsys, tmp_path):
    cfg, db_path = sphere
    root_before = read_netcdf(db_path)
    assert main(["fits", str(cfg)]) == 0
    assert "stores 1 fit(s) and 2 value(s)" in capsys.readouterr().out
    xr.testing.assert_identical(read_netcdf(db_path), root_before)     # the database untouched
    kinds = sorted(FS.stored(db_path).values())
    assert kinds == ["fit", "value", "value"]

    made = FC._memory.copy()                     # what the command made in this process
    FC.clear()                                   # a new process: from the file
    shutil.rmtree(tmp_path / "empty-fit-cache")  # on another machine
    spec = mfm.load(cfg).hydro
    fit = spec.state_space()
    assert fit.report["cache"] == f"{db_path} (stored)"
    options = dict(dofs=tuple(spec.dofs[k] for k in spec.moving), pole_sharing="entry",
                   omega_fit=spec.wave_band())
    ref = S.fit_state_space(spec.database(), **options)
    _same_fit(fit, ref)
    assert not fit.A.flags.writeable and not fit.poles[0].flags.writeable
    (first,) = made.values()
    assert first.report["cache"] == ""
    _same_fit(fit, first, drop=("cache",))       # its report too, the time it took included
    # the values: as the spec makes them without a file
    T_K, A_inf = spec.memory(), spec.added_mass_inf()
    bare = mfm.load(cfg).hydro
    bare.source = "elsewhere.nc"                 # no such file: nothing stored to read
    assert not (tmp_path / "empty-fit-cache").exists()   # all read from the database file
    FC.clear()
    assert T_K == bare.memory()
    assert np.array_equal(A_inf, bare.added_mass_inf()) and not A_inf.flags.writeable


def test_another_database_finds_nothing_and_fits(sphere, fresh):
    cfg, db_path = sphere
    assert main(["fits", str(cfg)]) == 0
    FC.clear()
    spec = mfm.load(cfg).hydro
    db = spec.database().copy(deep=True)
    db["radiation_damping"] = db["radiation_damping"] * (1 + 1e-9)   # other data, other key
    options = dict(dofs=tuple(spec.dofs[k] for k in spec.moving), pole_sharing="entry",
                   omega_fit=spec.wave_band())
    fit = FC.cached_fit(db, stored=str(db_path), **options)
    assert fit.report["cache"] == ""             # fitted, not read
    _same_fit(fit, S.fit_state_space(db, **options))


def test_items_of_other_code_are_dropped_when_storing_again(sphere, fresh, capsys):
    cfg, db_path = sphere
    assert main(["fits", str(cfg)]) == 0
    keys = set(FS.stored(db_path))
    # an item whose code has changed since: its source digest is another
    with netCDF4.Dataset(db_path, "a") as nc:
        g = nc.groups[FS.GROUP].groups["k" + sorted(keys)[0]]
        g.setncattr("source", "0" * 64)
    FS._index.cache_clear()
    assert main(["fits", str(cfg)]) == 0
    assert set(FS.stored(db_path)) == keys       # the stale one made and stored again
    with netCDF4.Dataset(db_path) as nc:
        for name, g in nc.groups[FS.GROUP].groups.items():
            assert g.getncattr("source") == FS.source_digest(g.getncattr("kind")), name
    # a foreign stale key (not this config's) is dropped
    with netCDF4.Dataset(db_path, "a") as nc:
        g = nc.groups[FS.GROUP].createGroup("k" + "f" * 64)
        g.setncattr("kind", "value")
        g.setncattr("source", "0" * 64)
    assert "f" * 64 in FS.stored(db_path)
    assert main(["fits", str(cfg)]) == 0
    assert "f" * 64 not in FS.stored(db_path) and set(FS.stored(db_path)) == keys


def test_fits_refuses_what_it_cannot_store(tmp_path, capsys):
    cfg = tmp_path / "dry.toml"
    cfg.write_text((CONFIGS / "double_pendulum.toml").read_text())
    assert main(["fits", str(cfg)]) == 2
    assert "no [hydro] table" in capsys.readouterr().err
    with pytest.raises(ValueError, match="NetCDF database"):
        FS.store(tmp_path / "run.out", {})


def test_the_shipped_stored_fits_are_current():
    """Each item a shipped database stores was made by today's code (else runs fit again, and
    the first call is slower than the README says): after editing the fitting code or the
    mooring tables' (mfm.loads.catenary_tables.make_table), run ``mfm fits`` on the configs
    hydro/data/README.md lists."""
    from mfm.loads.catenary_tables import table_source

    digest = {"fit": FS.source_digest("fit"), "value": FS.source_digest("value"),
              "table": table_source()}
    found = 0
    for path in sorted((ROOT / "hydro" / "data").glob("*.nc")):
        for key, kind in FS.stored(path).items():
            with netCDF4.Dataset(path) as nc:
                source = nc.groups[FS.GROUP].groups["k" + key].getncattr("source")
            assert source == digest[kind], (
                f"{path.name}: a stored {kind} was made by other code; run `mfm fits` on its "
                "configs (hydro/data/README.md)")
            found += 1
    assert found >= 3


def test_m4_134_reads_its_stored_fit_and_values(fresh, monkeypatch):
    import hydro.radiation
    import hydro.statespace
    from hydro.prepare import HydroSpec

    def made(*a, **k):
        raise AssertionError("made, not read from the database file")

    spec = mfm.load(CONFIGS / "m4_134.toml").hydro
    for owner, name in ((hydro.statespace, "fit_state_space"),
                        (hydro.radiation, "impulse_response_memory"),
                        (HydroSpec, "_consistent_added_mass_inf")):
        monkeypatch.setattr(owner, name, made)
    fit = spec.state_space()
    assert fit.report["cache"].endswith("m4_134.nc (stored)")
    assert fit.report["n_states"] == 960 and fit.report["passive"]
    assert spec.memory() > 0 and spec.added_mass_inf().shape == (48, 48)


def test_off_reads_no_stored_fit(monkeypatch):
    """``MFM_FIT_CACHE=off``: every fit made in the process (what the benchmarks time)."""
    monkeypatch.setenv("MFM_FIT_CACHE", "off")
    monkeypatch.setattr(FC, "_memory", collections.OrderedDict())
    spec = mfm.load(CONFIGS / "hallak_fwwp.toml").hydro
    assert FS.stored(spec.stored_in)
    assert spec.state_space().report["cache"] == ""


def test_fits_stores_with_the_cache_off(sphere, monkeypatch):
    cfg, db_path = sphere
    monkeypatch.setenv("MFM_FIT_CACHE", "off")
    monkeypatch.setattr(FC, "_memory", collections.OrderedDict())
    monkeypatch.setattr(FC, "_values", {})
    assert main(["fits", str(cfg)]) == 0
    assert sorted(FS.stored(db_path).values()) == ["fit", "value", "value"]


def test_info_says_what_the_database_stores(capsys):
    assert main(["info", str(CONFIGS / "m4_134.toml"), "--no-restoring"]) == 0
    assert "stores 1 radiation fit(s) and 2 value(s) made from it (`mfm fits`)" in \
        capsys.readouterr().out
    assert main(["info", str(CONFIGS / "wu_yuan_m1.toml"), "--no-restoring"]) == 0
    assert "stores 0 radiation fit(s) and 2 value(s) made from it, 1 mooring table(s)" in \
        capsys.readouterr().out


def test_a_report_reads_back_equal_its_types_kept():
    report = {"omega_fit": (1.0, 2.5), "entry_error": {("a", "b"): 0.1, ("b", "b"): float("inf")},
              "dropped": [("a", "c")], "passivity_violations": [], "max_real_eig": float("nan"),
              "passive": True, "n_states": 12, "nested": {"k": (1, (2, 3))}, "by_int": {1: 2},
              "numpy": np.float64(0.25), "cache": "dropped"}
    back = FS._report_from(FS._report_text(report))
    assert "cache" not in back and np.isnan(back.pop("max_real_eig"))
    expected = {k: v for k, v in report.items() if k not in ("cache", "max_real_eig")}
    assert back == expected
    assert type(back["omega_fit"]) is tuple and type(back["dropped"]) is list
    assert type(back["numpy"]) is float
    with pytest.raises(ValueError, match="not stored"):
        FS._report_text({"odd": object()})


def test_values_only_stores_no_fit(sphere, fresh):
    cfg, db_path = sphere
    assert main(["fits", "--values-only", str(cfg)]) == 0
    assert sorted(FS.stored(db_path).values()) == ["value", "value"]
    assert FC._memory == {}                      # nothing was fitted


def test_a_stored_mooring_table_is_read_without_moorpy(sphere, fresh, monkeypatch, tmp_path):
    """``mfm fits`` stores a config's mooring tables too (a first run then neither imports
    MoorPy nor solves): read back, the same bits; another code's table is dropped."""
    from mfm.loads import catenary_tables as maker
    from mfm.runner import tables

    cfg, db_path = sphere
    monkeypatch.setattr(tables, "_TABLE_CACHE", {})
    args = (775.5, 75.0, (2.0, 1.0), (1.0, 1.0), 800.0, 1.243e9, 2972.43, 0.0)
    with FC.recording() as made:
        table = tables.mooring_table(*args, stored=str(db_path))
    items = {key: item for (_, key), item in made.items()}
    assert [kind for kind, _ in items.values()] == ["table"]
    with pytest.raises(ValueError, match="sources="):
        FS.store(db_path, items)                 # hydro cannot judge mfm's code
    FS.store(db_path, items, sources={"table": maker.table_source()})
    assert list(FS.stored(db_path).values()) == ["table"]
    monkeypatch.setattr(tables, "_TABLE_CACHE", {})
    shutil.rmtree(tmp_path / "empty-fit-cache")  # on another machine

    def moorpy(*a, **k):
        raise AssertionError("MoorPy called: the stored table was not read")

    monkeypatch.setattr(maker, "catenary_forces", moorpy)
    again = tables.mooring_table(*args, stored=str(db_path))
    for a, b in zip(table, again):
        assert a.shape == b.shape and np.array_equal(a.view(np.uint64), b.view(np.uint64))
    FS.store(db_path, {}, sources={"table": "0" * 64})   # made by other code: dropped
    assert FS.stored(db_path) == {}


def test_storing_again_writes_the_same_bytes(sphere, fresh):
    """``mfm fits`` run again gives the file it found, whatever order its items were made in
    (the shipped databases stay unchanged in git)."""
    import hashlib

    cfg, db_path = sphere
    with FC.recording() as made:
        spec = mfm.load(cfg).hydro
        spec.memory()
        spec.added_mass_inf()
        spec.state_space()
    items = {key: item for (_, key), item in made.items()}
    FS.store(db_path, items)
    first = hashlib.sha256(db_path.read_bytes()).hexdigest()
    FS.store(db_path, dict(reversed(list(items.items()))))
    assert hashlib.sha256(db_path.read_bytes()).hexdigest() == first
    FS.store(db_path, {})                        # nothing new: the current items kept
    assert hashlib.sha256(db_path.read_bytes()).hexdigest() == first
