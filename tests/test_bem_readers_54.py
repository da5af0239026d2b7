"""Issue 54, items 1-3: NEMOH v3.0.2's multi-body hydrostatics, headings in degrees, and the one
database check behind every reader. Each test fails on the tree before the fix (d8f0eb7's
readers: the union's hydrostatics loaded for each body, ``Regular(heading=30)`` ran at 30 rad,
the corrupt databases below loaded without a word, a cut ``.hst`` read its lost entries as 0)."""
from __future__ import annotations

import gzip
import math
import shutil
import warnings
from pathlib import Path

import numpy as np
import pytest

import hydro
from hydro import nemoh
from hydro.database import HydroDatabaseWarning, read_netcdf, to_netcdf, validate, write_netcdf
from hydro.prepare import open_any_database

DATA = Path(__file__).parent / "data" / "bemio"
V3_RM3 = DATA / "nemoh_v3" / "rm3"
V2_RM3 = DATA / "nemoh_v2" / "rm3"
ROOT = Path(__file__).resolve().parents[1]
RM3_WAMIT = ROOT / "hydro" / "data" / "rm3"
SPHERE = ROOT / "hydro" / "data" / "sphere.nc"


def _v3_run(tmp_path, meshes=True):
    """The NEMOH v3.0.2 RM3 fixture as NEMOH left it: its body meshes unpacked (or left out)."""
    d = tmp_path / "rm3"
    shutil.copytree(V3_RM3, d)
    for gz in (d / "Mesh").glob("*.gz"):
        if meshes:
            gz.with_suffix("").write_bytes(gzip.decompress(gz.read_bytes()))
        gz.unlink()
    return d


# ------------------------------------------------------------------------------- item 1: NEMOH v3
def test_nemoh_v3_rm3_each_body_gets_its_own_hydrostatics(tmp_path):
    """Both hydrostatics_0.dat and _1.dat of WEC-Sim's v3.0.2 RM3 hold the union (1,612.5 m³,
    z_B −9.163 m); from each body's own mesh the reader gives NEMOH v2.3's and WAMIT's bodies."""
    run = _v3_run(tmp_path)
    with pytest.warns(HydroDatabaseWarning, match=r"hydrostatics_0\.dat.*1612\.49 m³.*float\.dat"):
        db = nemoh.read_nemoh(run)
    assert [str(b) for b in db.body.values] == ["float", "spar"]
    vol = db.displaced_volume.values
    zb = db.center_of_buoyancy.values[:, 2]
    v2 = nemoh.read_nemoh(V2_RM3)
    wamit = hydro.read_wamit(RM3_WAMIT / "rm3", body_names=["float", "spar"])
    # the same meshes as NEMOH v2.3's run: 725.83 and 886.69 m³ (the union was 1612.5 for both)
    np.testing.assert_allclose(vol, v2.displaced_volume.values, rtol=1e-4)
    np.testing.assert_allclose(vol, wamit.displaced_volume.values, rtol=1e-4)
    np.testing.assert_allclose(zb, v2.center_of_buoyancy.values[:, 2], atol=2e-3)
    np.testing.assert_allclose(zb, [-1.2927, -15.604], atol=2e-3)
    W, Ww = db.waterplane_stiffness.values, wamit.waterplane_stiffness.values
    # heave water-plane stiffness: float 2.80e6, spar 2.77e5 N/m (the union's 3.08e6 each before)
    np.testing.assert_allclose(W[[2, 8], [2, 8]], Ww[[2, 8], [2, 8]], rtol=1e-4)
    # roll/pitch water-plane terms: within 2 % of WAMIT's (a polygon of the same circles)
    np.testing.assert_allclose(W[[3, 4, 9, 10], [3, 4, 9, 10]], Ww[[3, 4, 9, 10], [3, 4, 9, 10]], rtol=0.02)
    assert "float, spar" in db.attrs["nemoh_hydrostatics"]
    # and the radiation data are those of the same device as v2.3 (float heave A within 10 %
    # over 0.5-1.1 rad/s, where the power was 8.8x off)
    band = (db.omega >= 0.5) & (db.omega <= 1.1)
    a3 = db.added_mass.sel(influenced_dof="float__Heave", radiating_dof="float__Heave")[band]
    a2 = v2.added_mass.sel(influenced_dof="float__Heave", radiating_dof="float__Heave").interp(omega=a3.omega)
    np.testing.assert_allclose(a3.values, a2.values, rtol=0.1)


def test_nemoh_v3_rm3_union_refused_without_meshes(tmp_path):
    """Without the body meshes, files that give both bodies one volume and centre are refused,
    naming the files and the fix."""
    run = _v3_run(tmp_path, meshes=False)
    with pytest.raises(nemoh.NemohFormatError) as e:
        nemoh.read_nemoh(run)
    msg = str(e.value)
    for part in ("hydrostatics_0.dat", "hydrostatics_1.dat", "1612.49 m³", "mesh\\float.dat",
                 "all the bodies together", "KH_<b>.dat"):
        assert part in msg, part


def test_nemoh_v2_rm3_unchanged():
    """Files that agree with their bodies (v2.3: no meshes in the fixture) are read as before."""
    db = nemoh.read_nemoh(V2_RM3)
    np.testing.assert_allclose(db.displaced_volume.values, [725.8328, 886.6924])
    assert db.attrs["nemoh_hydrostatics"] == "the KH and Hydrostatics files"


def test_mesh_hydrostatics_half_mesh_matches_full(tmp_path):
    """A mesh stored as a half (Isym = 1) and the same mesh written whole give one answer."""
    run = _v3_run(tmp_path)
    f = run / "Mesh" / "float.dat"
    V, P, sym = nemoh.read_mesh(f)
    assert sym
    Vm = V * [1.0, -1.0, 1.0]
    full = np.concatenate([V, Vm])
    Pm = P[:, ::-1] + len(V)
    lines = ["2 0"] + [f"{i + 1} {x:.17g} {y:.17g} {z:.17g}" for i, (x, y, z) in enumerate(full)] + ["0 0. 0. 0."]
    lines += [" ".join(str(k + 1) for k in p) for p in np.concatenate([P, Pm])] + ["0 0 0 0"]
    g = tmp_path / "full.dat"
    g.write_text("\n".join(lines) + "\n")
    a = nemoh.mesh_hydrostatics(f, [0, 0, -0.72], 1000.0, 9.81)
    b = nemoh.mesh_hydrostatics(g, [0, 0, -0.72], 1000.0, 9.81)
    assert a["volume"] == pytest.approx(b["volume"], rel=1e-12)
    np.testing.assert_allclose(a["waterplane_stiffness"], b["waterplane_stiffness"], rtol=1e-10, atol=1e-6)


# ------------------------------------------------------------------------------- item 2: headings
@pytest.mark.parametrize("make", [
    lambda h: hydro.Regular(height=2.0, period=11.0, heading=h),
    lambda h: hydro.Jonswap(hs=2.0, tp=10.0, heading=h),
    lambda h: hydro.PiersonMoskowitz(hs=2.0, tp=10.0, heading=h, spreading=hydro.Spreading(4.0)),
    lambda h: hydro.UserSpectrum(omega=np.linspace(0.3, 2.0, 20), S=np.ones(20), heading=h),
    lambda h: hydro.MeasuredElevation(t=np.arange(64) * 0.5, eta=np.sin(np.arange(64)), heading=h),
], ids=["Regular", "Jonswap", "PiersonMoskowitz+Spreading", "UserSpectrum", "MeasuredElevation"])
def test_heading_in_degrees_warned(make):
    """Every sea's heading beyond ±2π (degrees where radians are meant) warns, naming the value
    and the fix; within ±2π nothing (before: nothing either way)."""
    from hydro.waves import SeaStateWarning

    with pytest.warns(SeaStateWarning, match=r"heading = 30 rad \(1718\.87°\).*math\.radians\(30\)"):
        make(30)
    with pytest.warns(SeaStateWarning, match=r"math\.radians\(-90\)"):
        make(-90)
    with warnings.catch_warnings():
        warnings.simplefilter("error", SeaStateWarning)
        for ok in (0.0, math.radians(30), 2 * math.pi, -2 * math.pi, math.pi):
            assert make(ok).heading == pytest.approx(ok)


# ------------------------------------------------------------------- item 3: one database check
def _capytaine_file(tmp_path, name, change):
    raw = change(read_netcdf(SPHERE))
    p = tmp_path / f"{name}_capy.nc"
    write_netcdf(raw, p)
    return p


def _own_file(tmp_path, name, change):
    db = change(open_any_database(SPHERE))
    p = tmp_path / f"{name}_own.nc"
    to_netcdf(db, p)
    return p


def _set(key, value):
    def change(ds):
        if key in ds.coords:
            return ds.assign_coords({key: value})
        ds.attrs[key] = value
        return ds
    return change


def _swap_omega(ds):
    o = ds.omega.values.copy()
    o[[1, 2]] = o[[2, 1]]
    return ds.assign_coords(omega=o)


def _negative_volume(ds):
    ds["displaced_volume"] = -ds["displaced_volume"]
    return ds


CASES = [
    ("rho_negative", _set("rho", -1025.0), r"attribute rho = -1025\.0 kg/m³; accepted: 800–1300"),
    ("rho_t_per_m3", _set("rho", 1.025), r"rho = 1\.025 kg/m³.*1025 × 10\^-3, a unit slip"),
    ("rho_by_10", _set("rho", 102.5), r"rho = 102\.5 kg/m³.*10\^-1, a unit slip"),
    ("g_by_10", _set("g", 0.981), r"attribute g = 0\.981 m/s²; accepted: 9–10\.5.*10\^-1"),
    ("omega_order", _swap_omega, r"omega.*not strictly ascending.*0\.3.*0\.2"),
    ("negative_volume", _negative_volume, r"displaced_volume of body 'sphere' = -2\.09.*accepted"),
]


@pytest.mark.parametrize("form", ["own", "capytaine"])
@pytest.mark.parametrize("name, change, match", CASES, ids=[c[0] for c in CASES])
def test_corrupt_database_refused_naming_the_file(tmp_path, form, name, change, match):
    """The project's NetCDF (ours and mfm hydro's capytaine form): each kind of the corpus is
    refused by open_any_database, the message naming the file, the variable, the value and what
    is accepted (before: loaded; a negative volume: TypeError in the body check)."""
    p = (_own_file if form == "own" else _capytaine_file)(tmp_path, name, change)
    with pytest.raises(ValueError, match=match) as e:
        open_any_database(p)
    assert str(p) in str(e.value)


def test_corrupt_database_refused_by_mfm_load(tmp_path):
    """The same check runs on mfm.load's path (a config naming the file)."""
    import re

    import mfm

    p = _capytaine_file(tmp_path, "rho", _set("rho", 1.025))
    cfg = (ROOT / "configs" / "sphere.toml").read_text()
    c = tmp_path / "sphere.toml"
    c.write_text(re.sub(r'database\s*=\s*"[^"]*"', f'database = "{p}"', cfg))
    with pytest.raises(ValueError, match=r"rho = 1\.025 kg/m³"):
        mfm.load(c)


def test_wamit_scaled_with_rho_in_tonnes_refused():
    """WAMIT's nondimensional data scaled by rho = 1.025 (t/m³) is refused behind the reader."""
    with pytest.raises(ValueError, match=r"rm3\.out.*rho = 1\.025 kg/m³"):
        open_any_database(RM3_WAMIT / "rm3.out", names=["float", "spar"], rho=1.025)


def test_headings_in_degrees_in_a_database_refused(tmp_path):
    db = open_any_database(SPHERE)
    db = db.assign_coords(wave_direction=np.rad2deg(db.wave_direction.values) + 90.0)
    with pytest.raises(ValueError, match=r"wave_direction\[0\] = 90\.0 rad.*deg2rad"):
        validate(db, source="x.nc")


def test_wamit_hst_cut_short_refused(tmp_path):
    """A .hst cut at a line end still parses; its lost entries were read as zero stiffness."""
    d = tmp_path / "rm3"
    shutil.copytree(RM3_WAMIT, d)
    lines = (RM3_WAMIT / "rm3.hst").read_text().splitlines(keepends=True)
    (d / "rm3.hst").write_text("".join(lines[:100]))
    with pytest.raises(ValueError, match=r"rm3\.hst: 99 of the 144 entries.*missing \[\(9, 4\)"):
        open_any_database(d / "rm3.out", names=["float", "spar"])


def test_every_reader_still_loads(tmp_path):
    """The readers' good files pass the check: WAMIT, NEMOH v2/v3, capytaine 2.3.1, ours."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", HydroDatabaseWarning)
        open_any_database(RM3_WAMIT / "rm3.out", names=["float", "spar"])
        open_any_database(V2_RM3)
        open_any_database(DATA / "nemoh_v3" / "sphere")
        open_any_database(_v3_run(tmp_path))
        open_any_database(DATA / "capytaine_2.3.1" / "rm3" / "rm3_hydrodynamics.nc")
        open_any_database(_own_file(tmp_path, "good", lambda d: d))
