"""Issue 54, item 4: BEMIO HDF5 (WEC-Sim's and SEA-Stack's hydro data), read and written.

The public file: the WAMIT sphere (R = 5 m hemisphere, G 2 m below the water line, depth 200 m)
of NREL/HydroChrono and Project-SEA-Stack/SEA-Stack (the same bytes), cut to every 10th
frequency in tests/data/bemio/bemio_h5 (README there). It is compared with the same body solved
by NEMOH v3.0.2 (WEC-Sim's example, tests/data/bemio/nemoh_v3/sphere, depth 50 m) and with Hulme's
exact A∞ of a floating hemisphere. WEC-Sim's own public rm3.h5 is a Git LFS object in every
public copy (WEC-Sim and its forks hold a 132-byte pointer), so the RM3 checks write the shipped
WAMIT RM3 (the data WEC-Sim's rm3.h5 is made from) as BEMIO and read it back.
"""
from __future__ import annotations

import json
import warnings
from pathlib import Path

import netCDF4
import numpy as np
import pytest

from hydro import bemio
from hydro.database import HydroDatabaseWarning
from hydro.prepare import open_any_database

ROOT = Path(__file__).resolve().parents[1]
DATA = Path(__file__).parent / "data" / "bemio"
SPHERE_H5 = DATA / "bemio_h5" / "sphere.h5"
SPHERE_LAYOUT = DATA / "bemio_h5" / "sphere_layout.json"
NEMOH_SPHERE = DATA / "nemoh_v3" / "sphere"
WAMIT_RM3 = ROOT / "hydro" / "data" / "rm3" / "rm3.out"
R = 5.0
RHO = 1000.0


def _walk(g, prefix=""):
    """Every dataset of an HDF5 file (netCDF4's view, not hydro.bemio's): path → shape."""
    for name, v in g.variables.items():
        yield f"{prefix}/{name}", tuple(v.shape)
    for name, sub in g.groups.items():
        yield from _walk(sub, f"{prefix}/{name}")


def _open(path):
    """An HDF5 file read from memory: HDF5 never holds the path (a second handle on a file already
    open in the process can crash it, hydro.database's note)."""
    return netCDF4.Dataset("in-memory.h5", memory=Path(path).read_bytes())


def _layout(path):
    with _open(path) as nc:
        return dict(_walk(nc))


def _rewrite(src, dst, drop=(), change=None):
    """`src` copied to `dst` dataset by dataset (values verbatim), without the paths in `drop` and
    with those in `change` replaced: a partial or damaged BEMIO file."""
    change = change or {}
    with _open(src) as nc, netCDF4.Dataset(dst, "w", format="NETCDF4") as out:
        nc.set_auto_mask(False)
        w = bemio._Writer(out)
        for p, _ in _walk(nc):
            if p in drop:
                continue
            v = nc[p.lstrip("/")]
            a = change.get(p, v[...])
            if isinstance(a, str):
                w.text(p, a)
            else:
                w.array(p, a, "", "")
    return dst


def _diag(db, var, mode):
    b = str(db.body.values[0])
    return db[var].sel(influenced_dof=f"{b}__{mode}", radiating_dof=f"{b}__{mode}").values


# ------------------------------------------------------------------ the public file, another solver
@pytest.fixture(scope="module")
def sphere_pair():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", HydroDatabaseWarning)
        return open_any_database(SPHERE_H5), open_any_database(NEMOH_SPHERE)


def test_public_sphere_reads_as_its_body(sphere_pair):
    """The file's settings and hydrostatics as BEMIO states them (ρ g = 9810 N/m³): ω 0.05 …
    11.55 rad/s (24), heading 0° → 0 rad, the body named by the file, rotations about cg."""
    h5, _ = sphere_pair
    assert [str(b) for b in h5.body.values] == ["sphere"]
    assert h5.sizes["omega"] == 24 and h5.omega.values[0] == pytest.approx(0.05, rel=1e-6)
    assert h5.attrs["water_depth"] == 200.0 and h5.attrs["rho"] == 1000.0
    np.testing.assert_array_equal(h5.wave_direction.values, [0.0])
    np.testing.assert_allclose(h5.reference_point.values, [[0.0, 0.0, -2.0]])
    # C33 = ρ g π R² (the exact disc: 770,463 N/m; WAMIT's panels 770,389)
    assert h5.waterplane_stiffness.values[2, 2] == pytest.approx(RHO * 9.81 * np.pi * R**2, rel=2e-4)
    # roll: ρ g π R⁴/4 (4,815,468 N m/rad) once ρ g V (z_B − z_G) is taken out of BEMIO's 44
    assert h5.waterplane_stiffness.values[3, 3] == pytest.approx(RHO * 9.81 * np.pi * R**4 / 4, rel=1e-3)
    assert h5.hydrostatic_stiffness.values[3, 3] == pytest.approx(
        h5.waterplane_stiffness.values[3, 3] + RHO * 9.81 * 261.724 * (-1.874766 + 2.0), rel=1e-9)


def test_public_sphere_a_inf_against_hulme(sphere_pair):
    """A∞ of the floating hemisphere in heave: exactly ρ (2/3 π R³) / 2 (Hulme 1982, the value
    tests/test_hydro_bem.py uses); the file's is 0.4999 of ρ (2/3 π R³), i.e. −0.02 %: 0.5 %
    allowed (WAMIT's panels). A BEMIO reader that forgot ρ would be off by 1000×."""
    h5, _ = sphere_pair
    mu = h5.added_mass_inf.values[2, 2] / (RHO * 2.0 / 3.0 * np.pi * R**3)
    assert mu == pytest.approx(0.5, rel=5e-3)


def test_public_sphere_against_nemoh(sphere_pair):
    """The BEMIO file (WAMIT) against NEMOH v3.0.2's run of the same sphere, over 0.8–3 rad/s
    (kh > 3 at both depths: 200 and 50 m make no difference there), NEMOH's 0.2 rad/s grid
    interpolated onto the file's. Measured: A within 1.5 % of its peak (surge, heave, pitch), B
    within 4.1 % of its peak (heave, whose damping falls 30× over the band: the interpolation),
    |X| within 1.9 % of its peak and phases within 2.5°; the volume 0.14 %, C33 0.06 %, the
    water-plane C44 0.18 % (NEMOH's coarser mesh). Tolerances: 3 %, 6 %, 4 %, 5°, 0.5 %. A
    wrong sign of the imaginary parts (BEMIO's e^{+iωt} read as e^{−iωt}) turns the surge force's
    phase by ≈ 180° here; B read without its ω would be off by ω."""
    h5, nm = sphere_pair
    om = h5.omega.values
    sel = (om >= 0.8) & (om <= 3.0)
    assert sel.sum() == 4
    w = om[sel]
    for var, tol in (("added_mass", 0.03), ("radiation_damping", 0.06)):
        for mode in ("Surge", "Heave", "Pitch"):
            a = _diag(h5, var, mode)[sel]
            b = np.interp(w, nm.omega.values, _diag(nm, var, mode))
            assert np.abs(a - b).max() / np.abs(b).max() < tol, (var, mode, a, b)
    for mode in ("Surge", "Heave", "Pitch"):
        b = str(h5.body.values[0])
        xa = h5.excitation.sel(influenced_dof=f"{b}__{mode}").isel(wave_direction=0).values[sel]
        xn = nm.excitation.sel(influenced_dof=f"{b}__{mode}").isel(wave_direction=0).values
        xb = np.interp(w, nm.omega.values, xn.real) + 1j * np.interp(w, nm.omega.values, xn.imag)
        assert np.abs(np.abs(xa) - np.abs(xb)).max() / np.abs(xb).max() < 0.04, mode
        assert np.degrees(np.abs(np.angle(xa * np.conj(xb)))).max() < 5.0, mode
    np.testing.assert_allclose(h5.displaced_volume.values, nm.displaced_volume.values, rtol=5e-3)
    np.testing.assert_allclose(h5.center_of_buoyancy.values, nm.center_of_buoyancy.values, atol=5e-3)
    for i in (2, 3, 4):
        assert h5.waterplane_stiffness.values[i, i] == pytest.approx(
            nm.waterplane_stiffness.values[i, i], rel=5e-3)


# ------------------------------------------------------------------------------- writing: RM3
@pytest.fixture(scope="module")
def rm3(tmp_path_factory):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", HydroDatabaseWarning)
        db = open_any_database(WAMIT_RM3, names=["float", "spar"])
        out = bemio.write_bemio(db, tmp_path_factory.mktemp("bemio") / "rm3.h5", code="WAMIT")
        return db, out, open_any_database(out)


def test_rm3_round_trip(rm3):
    """WAMIT's RM3 written as BEMIO and read back: every variable within 1e-12 of its largest
    entry (measured ≤ 1.1e-16: one division and one multiplication by ρ, ρω, ρg each; the
    water-plane stiffness passes BEMIO's restoring matrix, ρgV(z_B − z_G) added and removed)."""
    db, _, back = rm3
    assert [str(b) for b in back.body.values] == ["float", "spar"]
    for v in ("added_mass", "radiation_damping", "added_mass_inf", "excitation",
              "waterplane_stiffness", "displaced_volume", "center_of_buoyancy", "reference_point"):
        a, b = db[v].values, back[v].values
        assert np.abs(a - b).max() <= 1e-12 * np.abs(a).max(), v
    np.testing.assert_array_equal(back.omega.values, db.omega.values)
    for a in ("rho", "g", "water_depth"):
        assert back.attrs[a] == db.attrs[a]


# writeBEMIOH5.m (WEC-Sim a23d299): the datasets it writes for each body n, shapes as HDF5 shows
# MATLAB's (reversed) order; m = 6, N = 6 × bodies, nw frequencies, nh headings, IRFs nt × nw'
def _wecsim_layout(nb, nw, nh, nt, nwi):
    n = 6 * nb
    lay = {"/simulation_parameters/scaled": (1, 1), "/simulation_parameters/g": (1, 1),
           "/simulation_parameters/rho": (1, 1), "/simulation_parameters/T": (nw, 1),
           "/simulation_parameters/w": (nw, 1), "/simulation_parameters/wave_dir": (nh, 1),
           "/simulation_parameters/water_depth": (), "/bem_data/code": ()}
    for k in range(1, nb + 1):
        b = f"/body{k}"
        lay.update({f"{b}/properties/name": (), f"{b}/properties/body_number": (1, 1),
                    f"{b}/properties/cb": (3, 1), f"{b}/properties/cg": (3, 1),
                    f"{b}/properties/disp_vol": (1, 1), f"{b}/properties/dof": (1, 1),
                    f"{b}/properties/dof_start": (1, 1), f"{b}/properties/dof_end": (1, 1)})
        hc = f"{b}/hydro_coeffs"
        lay.update({f"{hc}/linear_restoring_stiffness": (6, 6),
                    f"{hc}/added_mass/inf_freq": (6, n), f"{hc}/added_mass/all": (6, n, nw),
                    f"{hc}/radiation_damping/all": (6, n, nw),
                    f"{hc}/radiation_damping/impulse_response_fun/K": (6, n, nt),
                    f"{hc}/radiation_damping/impulse_response_fun/t": (nt, 1),
                    f"{hc}/radiation_damping/impulse_response_fun/w": (nwi, 1),
                    f"{hc}/excitation/impulse_response_fun/f": (6, nh, nt),
                    f"{hc}/excitation/impulse_response_fun/t": (nt, 1),
                    f"{hc}/excitation/impulse_response_fun/w": (nwi, 1)})
        for grp in ("excitation", "excitation/scattering", "excitation/froude-krylov"):
            for part in ("re", "im", "mag", "phase"):
                lay[f"{hc}/{grp}/{part}"] = (6, nh, nw)
    return lay


def test_rm3_layout_is_wecsims(rm3):
    """The written file holds every dataset writeBEMIOH5 writes for two bodies, at its path and in
    its shape, and nothing else (netCDF4's listing, not hydro.bemio's reader)."""
    db, path, _ = rm3
    got = _layout(path)
    want = _wecsim_layout(2, db.sizes["omega"], 1, bemio.IRF_N_T, bemio.IRF_N_OMEGA)
    assert got == want


def test_layout_matches_the_public_file(tmp_path):
    """A one-body database (NEMOH's sphere, 42 frequencies, depth 50 m) written as BEMIO has the
    public sphere.h5's datasets (those of sphere_layout.json but python-BEMIO's ``components``
    copies and the state-space fit, which the writer does not make) in the same shapes, the
    frequency count 240 → 42."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", HydroDatabaseWarning)
        db = open_any_database(NEMOH_SPHERE)
    out = bemio.write_bemio(db, tmp_path / "s.h5")
    public = json.loads(SPHERE_LAYOUT.read_text())
    want = {p: tuple(db.sizes["omega"] if s == 240 else s for s in shape)
            for p, shape in public.items() if "/components/" not in p and "/state_space/" not in p}
    assert _layout(out) == want


def test_written_irf_is_bemios_transform(rm3):
    """K(t) written is (2/π) ∫ B/ρ cos ωt dω: at t = 0 the float's heave K equals (2/π) ∫ B33/ρ
    dω of the database (trapezoid on the database's own grid: the same integral, 1e-3 for the
    1001-point resampling)."""
    db, path, _ = rm3
    with _open(path) as nc:
        K = nc["body1/hydro_coeffs/radiation_damping/impulse_response_fun/K"][...]
    B = db.radiation_damping.values[:, 2, 2] / RHO
    assert K[2, 2, 0] == pytest.approx(2 / np.pi * np.trapezoid(B, db.omega.values), rel=1e-3)


def test_rm3_config_with_bemio_database_runs_as_wamit(rm3, tmp_path):
    """configs/rm3.toml with ``[hydro] database`` the .h5 written from its WAMIT data, a regular
    wave H 2 m, T 8 s, 120 s at dt 0.05 s: the mean PTO power over the last 40 s equals the WAMIT
    run's (measured 165.205 kW both, 1.1e-8 apart: the state-space fit of the same A, B, A∞);
    1e-6 allowed."""
    import hydro
    import mfm

    _, path, _ = rm3
    text = (ROOT / "configs" / "rm3.toml").read_text()
    old = 'database = "../hydro/data/rm3/rm3.out"'
    assert old in text
    cfg = tmp_path / "rm3_bemio.toml"
    cfg.write_text(text.replace(old, f'database = "{path.as_posix()}"'))
    sea = hydro.Regular(height=2.0, period=8.0)
    P = []
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", HydroDatabaseWarning)
        for c in (ROOT / "configs" / "rm3.toml", cfg):
            ds = mfm.simulate(mfm.load(c), sea, duration=120.0, dt=0.05)
            P.append(ds.pto_power.sel(time=slice(80, None)).mean().item())
    assert P[0] > 1e5
    assert P[1] == pytest.approx(P[0], rel=1e-6)


def test_cli_writes_bemio(tmp_path, capsys):
    """``mfm hydro configs/rm3.toml --format bemio --out …``: the WAMIT database converted without
    a solve; a wrong suffix is a usage error naming --out."""
    import mfm_cli

    out = tmp_path / "rm3.h5"
    assert mfm_cli.main(["hydro", str(ROOT / "configs" / "rm3.toml"), "--format", "bemio",
                         "--out", str(out)]) in (0, None)
    assert "BEMIO HDF5" in capsys.readouterr().out
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", HydroDatabaseWarning)
        back = open_any_database(out)
    assert [str(b) for b in back.body.values] == ["float", "spar"]
    assert mfm_cli.main(["hydro", str(ROOT / "configs" / "rm3.toml"), "--format", "bemio",
                         "--out", str(tmp_path / "rm3.nc")]) == 2
    assert "--out" in capsys.readouterr().err


# ------------------------------------------------------------------------------------ bad files
AM = "/body1/hydro_coeffs/added_mass/all"


@pytest.mark.parametrize("drop,change,match", [
    ((AM,), None, r"sphere\.h5'?: no dataset /body1/hydro_coeffs/added_mass/all"),
    (("/simulation_parameters/rho",), None, r"no dataset /simulation_parameters/rho"),
    ((), {AM: np.zeros((24, 6, 6))}, r"added_mass/all has shape \(24, 6, 6\); expected \(6, 6, 24\)"),
    ((), {"/body1/properties/dof": np.array([[7.0]])}, r"properties/dof = 7; accepted: 6"),
    ((), {"/simulation_parameters/scaled": np.array([[1.0]])}, r"scaled = 1; accepted: 0"),
    ((), {"/body1/properties/cg": np.zeros((2, 1))}, r"properties/cg has shape \(2, 1\); expected 3"),
])
def test_bad_files_are_refused_naming_the_dataset(tmp_path, drop, change, match):
    bad = _rewrite(SPHERE_H5, tmp_path / "sphere.h5", drop, change)
    with pytest.raises(ValueError, match=match):
        open_any_database(bad)


def test_bemio_goes_through_the_one_database_check(tmp_path):
    """What every reader's database must hold (hydro.database.check_values) is checked behind the
    BEMIO reader too: ρ in t/m³, frequencies out of order, a heading of 720°."""
    with _open(SPHERE_H5) as nc:
        w = np.array(nc["simulation_parameters/w"][...])
    cases = [({"/simulation_parameters/rho": np.array([[1.025]])}, r"sphere\.h5.*rho = 1\.025"),
             ({"/simulation_parameters/w": w[::-1].copy()}, r"sphere\.h5.*omega is not strictly ascending"),
             ({"/simulation_parameters/wave_dir": np.array([[720.0]])}, r"wave_direction\[0\] = 12\.566")]
    for change, match in cases:
        bad = _rewrite(SPHERE_H5, tmp_path / "sphere.h5", (), change)
        with pytest.raises(ValueError, match=match):
            open_any_database(bad)


def test_not_hdf5_and_missing(tmp_path):
    p = tmp_path / "x.h5"
    p.write_text("not hdf5")
    with pytest.raises(ValueError, match=r"x\.h5.*is not an HDF5 file"):
        open_any_database(p)
    with pytest.raises(FileNotFoundError, match=r"nothere\.h5"):
        open_any_database(tmp_path / "nothere.h5")


def test_names_and_g(tmp_path):
    """``[hydro] names`` renames the file's bodies; a g other than the file's is refused (the
    coefficients were computed with it), a ρ other than the file's scales them (WEC-Sim's way)."""
    db = open_any_database(SPHERE_H5, names=["ball"])
    assert [str(b) for b in db.body.values] == ["ball"] and "ball__Heave" in db.influenced_dof.values
    with pytest.raises(ValueError, match=r"hydro\.g = 9\.7 differs .*simulation_parameters/g = 9\.81"):
        open_any_database(SPHERE_H5, g=9.7)
    d1025 = open_any_database(SPHERE_H5, rho=1025.0)
    d1000 = open_any_database(SPHERE_H5)
    np.testing.assert_allclose(d1025.added_mass.values, 1.025 * d1000.added_mass.values, rtol=1e-14)


def test_headings_round_trip_in_degrees(tmp_path):
    """Three headings, each with its own excitation (the sphere's × 1, × 2i, × 3): written in
    degrees at /simulation_parameters/wave_dir, the excitation (dof, heading, ω) as BEMIO orders it,
    read back at the same headings in radians within 1e-12."""
    import xarray as xr

    db = open_any_database(SPHERE_H5)
    beta = np.deg2rad([0.0, 30.0, 90.0])
    ex = xr.concat([db.excitation * f for f in (1.0, 2.0j, 3.0)], dim="wave_direction")
    db = db.drop_vars(["excitation", "wave_direction"]).assign_coords(wave_direction=beta)
    db["excitation"] = ex.assign_coords(wave_direction=beta).transpose(
        "omega", "wave_direction", "influenced_dof")
    out = bemio.write_bemio(db, tmp_path / "three.h5")
    with _open(out) as nc:
        np.testing.assert_allclose(nc["simulation_parameters/wave_dir"][...].ravel(), [0, 30, 90])
        im = np.array(nc["body1/hydro_coeffs/excitation/im"][...])
    # BEMIO's e^{+iωt}: im = −Im(X)/(ρg); heading 1 is the sphere's × 2i
    x = db.excitation.values
    np.testing.assert_allclose(im[2, 1], -(x[:, 1, 2] / (RHO * 9.81)).imag, rtol=1e-12)
    back = open_any_database(out)
    np.testing.assert_allclose(back.wave_direction.values, beta, rtol=1e-14)
    assert np.abs(back.excitation.values - x).max() <= 1e-12 * np.abs(x).max()
