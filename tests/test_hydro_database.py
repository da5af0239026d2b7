"""hydro.database and hydro.wamit: schema, validation, NetCDF, capytaine import, WAMIT reader.

Independent references: hand computations from raw lines of the WAMIT files, the float's
water-plane geometry read from its STL, capytaine's own complex-splitting helper.
"""
import warnings
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

from hydro import database as D
from hydro.wamit import read_wamit

DATA = Path(__file__).resolve().parents[1] / "hydro" / "data"
RM3 = DATA / "rm3"
RHO, G = 1000.0, 9.81


@pytest.fixture(scope="module")
def rm3():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", D.HydroDatabaseWarning)
        return read_wamit(RM3 / "rm3", rho=RHO, g=G, body_names=["float", "spar"])


def _raw_line(fname, first, *ints):
    """The numbers of the first line of `fname` whose first column ≈ first and whose integer
    columns 2… equal ints."""
    for line in (RM3 / fname).read_text().splitlines()[1:]:
        p = line.split()
        if np.isclose(float(p[0]), first, rtol=1e-6, atol=1e-9) and all(
                int(float(p[k + 1 + (fname.endswith(".3"))])) == v for k, v in enumerate(ints)):
            return [float(x) for x in p]
    raise LookupError((fname, first, ints))


def test_rm3_heave_added_mass_and_damping_by_hand(rm3):
    om = 1.0
    T = 2 * np.pi / om                     # rm3.1 lists periods; 6.283185 s is in the file
    p = _raw_line("rm3.1", T, 3, 3)        # float heave: translation-translation, k = 3, L = 1
    k = int(np.argmin(np.abs(rm3.omega.values - om)))
    assert rm3.omega.values[k] == pytest.approx(om, rel=1e-6)
    A = rm3.added_mass.sel(influenced_dof="float__Heave", radiating_dof="float__Heave").values[k]
    B = rm3.radiation_damping.sel(influenced_dof="float__Heave", radiating_dof="float__Heave").values[k]
    # exact rescaling of the printed numbers: float64 round-off only
    assert A == pytest.approx(p[3] * RHO, rel=1e-12)
    assert B == pytest.approx(p[4] * RHO * om, rel=1e-6)      # ω from 2π/T printed to 7 digits
    # a mixed mode pair scales with L^4 (L = 1 here) and keeps influenced/radiating order
    p15 = _raw_line("rm3.1", T, 1, 5)
    assert rm3.added_mass.sel(influenced_dof="float__Surge", radiating_dof="float__Pitch").values[k] \
        == pytest.approx(p15[3] * RHO, rel=1e-12)


def test_rm3_excitation_by_hand_with_conjugation(rm3):
    om = 1.0
    for mode, label, L_pow in ((3, "float__Heave", 2), (11, "spar__Pitch", 3)):
        p = _raw_line("rm3.3", 2 * np.pi / om, mode)     # period, heading, i, |X|, phase, Re, Im
        X_wamit = (p[5] + 1j * p[6]) * RHO * G * 1.0 ** L_pow
        X = rm3.excitation.sel(influenced_dof=label, wave_direction=0.0).values[
            int(np.argmin(np.abs(rm3.omega.values - om)))]
        # e^{+iωt} → e^{−iωt}: the same force history needs the complex conjugate
        assert X == pytest.approx(np.conj(X_wamit), rel=1e-12)
        t = np.linspace(0, 2 * np.pi / om, 7)
        np.testing.assert_allclose((X * np.exp(-1j * om * t)).real,
                                   (X_wamit * np.exp(1j * om * t)).real, rtol=1e-12, atol=1e-9)
        # |X| and the phase columns agree with Re/Im (phase in degrees, WAMIT sign)
        assert abs(X) == pytest.approx(p[3] * RHO * G, rel=1e-5)
        assert np.angle(X, deg=True) == pytest.approx(-p[4], abs=1e-3)


def test_rm3_bodies_stay_separate_and_limits(rm3):
    assert list(rm3.body.values) == ["float", "spar"]
    assert rm3.sizes["influenced_dof"] == rm3.sizes["radiating_dof"] == 12
    assert list(rm3.influenced_dof.values[6:9]) == ["spar__Surge", "spar__Sway", "spar__Heave"]
    # cross-body heave coupling at ω = 1 rad/s, from the raw (3, 9) line
    p = _raw_line("rm3.1", 2 * np.pi, 3, 9)
    k = int(np.argmin(np.abs(rm3.omega.values - 1.0)))
    assert rm3.added_mass.values[k, 2, 8] == pytest.approx(p[3] * RHO, rel=1e-12)
    # period 0 → A∞, period −1 → A0 (the .out: "Wave period = zero / infinite")
    assert rm3.added_mass_inf.values[2, 2] == pytest.approx(_raw_line("rm3.1", 0.0, 3, 3)[3] * RHO)
    assert rm3.added_mass_zero.values[8, 8] == pytest.approx(_raw_line("rm3.1", -1.0, 9, 9)[3] * RHO)
    assert rm3.omega.values[0] == pytest.approx(0.02, rel=1e-5)
    assert rm3.sizes["omega"] == 260 and np.all(np.diff(rm3.omega.values) > 0)
    np.testing.assert_allclose(rm3.reference_point.values, [[0, 0, -0.72], [0, 0, -21.29]])
    # the spar's centre of buoyancy 5.686 m above its origin → −15.604 m in inertial axes
    assert rm3.center_of_buoyancy.values[1, 2] == pytest.approx(-21.29 + 5.686012, abs=1e-9)
    assert rm3.attrs["convention"] == "exp(-i omega t)" and np.isinf(rm3.attrs["water_depth"])


def _stl_radii(path, z_cut):
    """Inner and outer radius of the hull's vertical walls crossing z = z_cut (STL body axes)."""
    v = np.array([[float(x) for x in line.split()[1:]] for line in Path(path).read_text().splitlines()
                  if line.strip().startswith("vertex")])
    r = np.round(np.hypot(v[:, 0], v[:, 1]), 6)
    walls = [rr for rr in np.unique(r)
             if v[r == rr, 2].min() < z_cut < v[r == rr, 2].max() and np.ptp(v[r == rr, 2]) > 1.0]
    return min(walls), max(walls)


def test_rm3_waterplane_stiffness_matches_float_geometry(rm3):
    # the STL is in body axes, origin 0.72 m below the water: the water line is at z = +0.72
    r_in, r_out = _stl_radii(RM3 / "float.stl", 0.72)
    assert (r_in, r_out) == pytest.approx((3.038, 10.0), abs=1e-3)
    W = rm3.waterplane_stiffness.values
    C33 = RHO * G * np.pi * (r_out ** 2 - r_in ** 2)
    C44 = RHO * G * np.pi / 4 * (r_out ** 4 - r_in ** 4)
    # WAMIT integrates over its own panel mesh (float.gdf, 144 water-line panels), not the STL:
    # measured 0.13 % (C33) and 0.36 % (C44); 1 % allows for that discretisation
    assert W[2, 2] == pytest.approx(C33, rel=0.01)
    # C44 checks the removal of ρgV z_B (7347 in the .hst → 7763 after removal, ρg = 1 units)
    assert W[3, 3] == pytest.approx(C44, rel=0.01) and W[4, 4] == pytest.approx(C44, rel=0.01)
    H = rm3.hydrostatic_stiffness.values
    V, zB = rm3.displaced_volume.values[0], rm3.center_of_buoyancy.values[0, 2] + 0.72
    assert H[3, 3] - W[3, 3] == pytest.approx(RHO * G * V * zB, rel=1e-9)
    # only water-plane terms: nothing in surge/sway/yaw rows or across bodies
    mask = np.zeros((12, 12), bool)
    for o in (0, 6):
        mask[o + 2:o + 5, o + 2:o + 5] = True
    assert np.all(W[~mask] == 0.0) and np.allclose(W, W.T)
    # spar: a 3 m column (ρg π r² = 28.27 ρg); its C44 is a small difference of two large numbers
    assert W[8, 8] == pytest.approx(RHO * G * np.pi * 9.0, rel=0.01)


def test_netcdf_round_trip(rm3, tmp_path):
    path = D.to_netcdf(rm3, tmp_path / "rm3.nc")
    back = D.open_database(path)
    assert np.iscomplexobj(back.excitation.values)
    xr.testing.assert_identical(back[list(rm3.data_vars)], rm3[list(rm3.data_vars)])
    assert back.attrs["water_depth"] == np.inf and back.attrs["rho"] == RHO


def test_from_capytaine_transposes_and_splits(rm3):
    """An RM3-valued dataset laid out as capytaine writes it (dims (omega, radiating_dof,
    influenced_dof), ω = inf row, split complex via capytaine's own helper) converts back to the
    asymmetric RM3 data exactly: a transposition error would show on the asymmetric entries."""
    from capytaine.io.xarray import separate_complex_values
    A = xr.concat([rm3.added_mass, rm3.added_mass_inf.expand_dims(omega=[np.inf])], "omega")
    B = xr.concat([rm3.radiation_damping, 0 * rm3.added_mass_inf.expand_dims(omega=[np.inf])], "omega")
    nan = np.full((1, 1, 12), np.nan + 0j)
    fk = 0.3 * rm3.excitation
    df = rm3.excitation - fk
    cds = xr.Dataset({
        "added_mass": A.transpose("omega", "radiating_dof", "influenced_dof"),
        "radiation_damping": B.transpose("omega", "radiating_dof", "influenced_dof"),
        "Froude_Krylov_force": xr.concat([fk, xr.DataArray(nan, dims=fk.dims, coords={"omega": [np.inf]})], "omega"),
        "diffraction_force": xr.concat([df, xr.DataArray(nan, dims=df.dims, coords={"omega": [np.inf]})], "omega"),
        "waterplane_stiffness": rm3.waterplane_stiffness.transpose("radiating_dof", "influenced_dof"),
    }, coords={"g": G, "rho": RHO, "water_depth": np.inf,
               "rotation_center": (("body", "space_coordinate"), rm3.reference_point.values)})
    cds = cds.assign_coords(period=("omega", 2 * np.pi / cds.omega.values))
    split = separate_complex_values(cds)
    assert "complex" in split.Froude_Krylov_force.dims
    db = D.from_capytaine(split)
    for name in ("added_mass", "radiation_damping", "added_mass_inf", "excitation",
                 "waterplane_stiffness"):
        # exact up to the round-off of FK + diffraction re-summed
        np.testing.assert_allclose(db[name].values, rm3[name].values, rtol=1e-14, atol=1e-9, err_msg=name)
    np.testing.assert_array_equal(db.reference_point.values, rm3.reference_point.values)
    assert db.attrs["rho"] == RHO and np.isinf(db.attrs["water_depth"])
    with pytest.raises(ValueError, match="mfm hydro"):
        D.from_capytaine(split.drop_vars("waterplane_stiffness"))
    with pytest.raises(ValueError, match="no omega = inf"):
        D.from_capytaine(split.isel(omega=slice(0, -1)))


@pytest.fixture(scope="module")
def sphere():
    path = DATA / "sphere.nc"   # shipped (hydro/data/README.md)
    return D.from_capytaine(xr.load_dataset(path))


def test_sphere_dataset_is_valid(sphere):
    with warnings.catch_warnings():
        warnings.simplefilter("error")          # a clean capytaine database raises no warning
        D.validate(sphere, bodies=["sphere"])
    assert list(sphere.influenced_dof.values)[2] == "sphere__Heave"
    assert sphere.displaced_volume.values[0] == pytest.approx(2 / 3 * np.pi, rel=0.01)


def test_validate_reports_each_bad_input(sphere, rm3, monkeypatch):
    # each warning is given once per database per process: forget those an earlier test gave
    monkeypatch.setattr(D, "_WARNED", set())
    with pytest.raises(KeyError, match=r"\['buoy'\].*available bodies: \['sphere'\]"):
        D.validate(sphere, bodies=["sphere", "buoy"])
    with pytest.raises(ValueError, match="added_mass_inf.*omega=numpy.inf.*period 0"):
        D.validate(sphere.drop_vars("added_mass_inf"))
    with pytest.raises(ValueError, match="'excitation'"):
        D.validate(sphere.drop_vars("excitation"))
    bad = sphere.copy(deep=True)
    bad["added_mass"][:, 2, 0] = 250.0       # A_13 ≈ 0 (symmetry), A_31 = 250 kg ≈ 0.4 sqrt(A11 A33)
    with pytest.warns(D.HydroDatabaseWarning, match=r"added_mass is not symmetric.*\(sphere__Surge, sphere__Heave\).*M_ji = 250"):
        D.validate(bad)
    neg = sphere.copy(deep=True)
    neg["radiation_damping"][10, 2, 2] = -0.1 * float(neg.radiation_damping[:, 2, 2].max())
    with pytest.warns(D.HydroDatabaseWarning, match=r"B\[sphere__Heave\].*omega = 1\.1 rad/s"):
        D.validate(neg)
    # every dof negative beyond the noise is named, not only the worst
    monkeypatch.setattr(D, "_WARNED", set())
    neg["radiation_damping"][20, 0, 0] = -0.05 * float(neg.radiation_damping[:, 0, 0].max())
    with pytest.warns(D.HydroDatabaseWarning, match=r"B\[sphere__Heave\].*Also negative: "
                      r"B\[sphere__Surge\] = .*\(-0\.05 of its peak\)"):
        D.validate(neg)
    # the RM3 WAMIT data are asymmetric (float sway–roll A∞ by 15 %): warned, with the dofs
    with warnings.catch_warnings(record=True) as rec:
        warnings.simplefilter("always")
        D.validate(rm3)
    msgs = [str(w.message) for w in rec]
    assert any("added_mass_inf is not symmetric" in m and "(float__Sway, float__Roll)" in m for m in msgs)


def test_select_bodies_and_dof_index(rm3):
    spar = D.select_bodies(rm3, ["spar"])
    assert spar.sizes["influenced_dof"] == 6 and list(spar.body.values) == ["spar"]
    np.testing.assert_array_equal(spar.added_mass.values, rm3.added_mass.values[:, 6:, 6:])
    assert D.dof_index(rm3)["spar__Heave"] == 8
    with pytest.raises(KeyError, match="available bodies"):
        D.select_bodies(rm3, ["plate"])
