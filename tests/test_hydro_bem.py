"""hydro.geometry and hydro.bem: meshes, hydrostatics, capytaine solves, symmetry, cache, NetCDF.

BEM solves here are tiny (coarse panels, 1-2 frequencies, a few seconds); the accurate checks use
the shipped hydro/data/sphere.nc (a floating hemisphere, dx = 0.05 m, see hydro/data/README.md).
"""
from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("capytaine")
import capytaine as cpt  # noqa: E402

from hydro import bem  # noqa: E402
from hydro import geometry as geo  # noqa: E402

RHO, G = 1000.0, 9.81
SPHERE_NC = Path(bem.__file__).parent / "data" / "sphere.nc"
# Exact floating hemisphere heave added mass / (rho 2/3 pi R^3) (Hulme 1982; CAPYTAINE.md).
MU33_ZERO, MU33_INF = 0.8310, 0.5


def _heave_mu(ds, name):
    a = ds["added_mass"].sel(influenced_dof=f"{name}__Heave", radiating_dof=f"{name}__Heave")
    return a.values / (RHO * 2.0 / 3.0 * math.pi)  # R = 1 m


# ------------------------------------------------------------------------------------------------
# The shipped dataset: hemisphere added mass against the exact values


def test_sphere_dataset_heave_added_mass_limits():
    ds = bem.load(SPHERE_NC)
    assert ds.attrs["dx"] == "0.05" and np.isinf(ds.attrs["water_depth"])
    mu = _heave_mu(ds, "sphere")
    w = ds["omega"].values
    assert np.isinf(w[-1]) and w[0] == pytest.approx(0.1)
    err0 = mu[0] / MU33_ZERO - 1
    err_inf = mu[-1] / MU33_INF - 1
    # Panel convergence goes as dx^0.8 and always overestimates (test below and CAPYTAINE.md):
    # measured +3.4 %, +2.1 %, +1.1 % at dx/R = 0.2, 0.1, 0.05, so dx/R = 0.05 allows (0, 2 %).
    assert 0.0 < err_inf < 0.02, err_inf
    # The smallest omega (0.1 rad/s, kR = 0.001) is not omega = 0: A33 still rises by ~0.5 % between
    # kR = 1e-5 and 1e-3 (measured), on top of the ~1 % panel overestimate: allow (0, 2.5 %).
    assert 0.0 < err0 < 0.025, err0


def test_panel_convergence_is_slow_and_from_above():
    """Tiny solves of the hemisphere at dx/R = 0.2 and 0.1: the error at ω = ∞ and ω → 0 is
    positive and shrinks like dx^p with p between 0.5 and 1.2 (measured p ≈ 0.7-0.9)."""
    errs = {}
    for dx in (0.2, 0.1):
        ds = bem.solve([{"name": "h", "shape": "hemisphere", "radius": 1.0}], omega=[1e-3], dx=dx,
                       cache=False, progress=False)
        mu = _heave_mu(ds, "h")
        errs[dx] = (mu[0] / MU33_ZERO - 1, mu[-1] / MU33_INF - 1)
    for k in (0, 1):
        e1, e2 = errs[0.2][k], errs[0.1][k]
        assert 0 < e2 < e1 < 0.05
        p = math.log2(e1 / e2)
        assert 0.5 < p < 1.2, p


def test_sphere_dataset_schema_and_physics():
    ds = bem.load(SPHERE_NC)
    dofs = [f"sphere__{m}" for m in geo.MODES]
    assert list(ds["influenced_dof"].values) == dofs and list(ds["radiating_dof"].values) == dofs
    assert list(ds["body"].values) == ["sphere"] and list(ds["axis"].values) == ["x", "y", "z"]
    assert ds["excitation_force"].dtype == np.complex128
    assert np.all(np.isnan(ds["excitation_force"].sel(omega=np.inf).values))  # radiation only at ∞
    assert np.all(np.isfinite(ds["excitation_force"].isel(omega=slice(0, -1)).values))
    for k in ("rho", "g", "water_depth"):
        assert isinstance(ds.attrs[k], (float, np.floating))
    for k in ("capytaine_version", "numpy_version", "date", "hash", "bodies", "generated_by"):
        assert isinstance(ds.attrs[k], str) and ds.attrs[k]
    assert ds.attrs["convention"] == "exp(-i omega t)"
    A = ds["added_mass"].isel(omega=slice(0, -1)).values
    B = ds["radiation_damping"].isel(omega=slice(0, -1)).values
    # Reciprocity: A and B symmetric (to solver precision, relative 1e-6 of the largest term).
    assert np.abs(A - A.transpose(0, 2, 1)).max() < 1e-6 * np.abs(A).max()
    assert np.abs(B - B.transpose(0, 2, 1)).max() < 1e-6 * np.abs(B).max()
    # Surge and sway are the same by axisymmetry (1e-9: same panels rotated by 90 degrees).
    assert np.allclose(A[:, 0, 0], A[:, 1, 1], rtol=1e-9)
    # Haskind relation (deep water, axisymmetric body so |X3| does not depend on the heading):
    # B33 = k |X3|² / (4 ρ g c_g), c_g = g / (2ω). Ties the diffraction solution to the radiation
    # one. Measured: within 0.8-1.5 % up to 4.6 rad/s, 2.5 % at 5.2-5.5 rad/s (just above the
    # first irregular frequency, ≈ 4.85 rad/s, that the lid removes); 3 % where B33 is not small.
    w = ds["omega"].values[:-1]
    X3 = ds["excitation_force"].sel(influenced_dof="sphere__Heave").values[:-1, 0]
    k = w**2 / G
    b33_haskind = k * np.abs(X3) ** 2 / (4 * RHO * G * (G / (2 * w)))
    b33 = B[:, 2, 2]
    big = b33 > 0.1 * b33.max()
    assert np.allclose(b33_haskind[big], b33[big], rtol=0.03)


# ------------------------------------------------------------------------------------------------
# Hydrostatics against closed forms and capytaine


def _regular_polygon(n, R):
    """Area and second moment about a diameter of the regular n-gon inscribed in radius R."""
    t = 2 * math.pi / n
    return n / 2 * R**2 * math.sin(t), n * R**4 / 24 * math.sin(t) * (2 + math.cos(t))


def test_cylinder_hydrostatics_exact_for_polygon_and_close_to_circle():
    R, d, dx = 0.5, 0.3, 0.05
    spec = geo.normalize_spec({"name": "c", "shape": "cylinder", "radius": R, "draft": d})
    n = geo.n_azimuth(spec, dx)
    hull = geo.body_meshes(spec, dx)[0]
    h = geo.hull_hydrostatics(hull, spec["reference_point"], rho=RHO, g=G)
    A, Ixx = _regular_polygon(n, R)
    # The panelled hull is a prism on the inscribed n-gon: these are exact (round-off only).
    assert h["volume"] == pytest.approx(A * d, rel=1e-12)
    assert h["center_of_buoyancy"] == pytest.approx([0, 0, -d / 2], abs=1e-12)
    W = h["waterplane_stiffness"]
    assert W[2, 2] == pytest.approx(RHO * G * A, rel=1e-12)
    assert W[3, 3] == pytest.approx(RHO * G * Ixx, rel=1e-12)
    assert W[4, 4] == pytest.approx(RHO * G * Ixx, rel=1e-12)
    # Against the circle: the n-gon misses a fraction ≈ (2π/n)²/6 of the area (more for I).
    tol = 2 * (2 * math.pi / n) ** 2 / 6
    assert W[2, 2] == pytest.approx(RHO * G * math.pi * R**2, rel=tol)
    assert W[3, 3] == pytest.approx(RHO * G * math.pi * R**4 / 4, rel=tol)
    assert h["volume"] == pytest.approx(math.pi * R**2 * d, rel=tol)
    off = np.ones((6, 6), bool)
    off[[2, 3, 4], [2, 3, 4]] = False
    assert np.abs(W[off]).max() < 1e-9 * W[2, 2]
    # Buoyancy-only stiffness about the origin: roll/pitch add ρ g V z_B.
    H = h["hydrostatic_stiffness"]
    assert H[3, 3] == pytest.approx(RHO * G * (Ixx + A * d * (-d / 2)), rel=1e-12)


def test_hemisphere_hydrostatics_close_to_closed_forms():
    R, dx = 1.0, 0.1
    spec = geo.normalize_spec({"name": "h", "shape": "hemisphere", "radius": R})
    h = geo.hull_hydrostatics(geo.body_meshes(spec, dx)[0], [0, 0, 0], rho=RHO, g=G)
    # Inscribed panels: azimuth step 2π/64 and meridian step π/32 each miss ≈ θ²/6 ≈ 0.16 %,
    # always from below; 1 % covers both with margin and fails for a wrong formula.
    for got, exact in ((h["volume"], 2 / 3 * math.pi * R**3),
                       (h["waterplane_stiffness"][2, 2], RHO * G * math.pi * R**2),
                       (h["waterplane_stiffness"][3, 3], RHO * G * math.pi * R**4 / 4),
                       (h["waterplane_stiffness"][4, 4], RHO * G * math.pi * R**4 / 4)):
        assert 0.99 * exact < got < exact
    assert h["center_of_buoyancy"][2] == pytest.approx(-3 * R / 8, rel=0.01)
    # About the centre, buoyancy alone is neutral in roll: ρg(πR⁴/4 − V·3R/8) = 0 for the exact
    # hemisphere; the panelled one is within 1 % of ρgπR⁴/4.
    assert abs(h["hydrostatic_stiffness"][3, 3]) < 0.01 * RHO * G * math.pi * R**4 / 4


@pytest.mark.parametrize("spec", [
    {"name": "c", "shape": "cylinder", "radius": 0.5, "draft": 0.3, "origin": [1.0, 0.5, 0.0],
     "reference_point": [1.3, 0.3, -0.1]},
    {"name": "h", "shape": "hemisphere", "radius": 1.0, "reference_point": [0.2, -0.1, -0.3]},
    {"name": "r", "shape": "cylinder", "radius": 0.175, "draft": 0.214, "base": "rounded",
     "knuckle_radius": 0.125, "origin": [-1.05, 0.0, 0.0]},
    {"name": "s", "shape": "sphere", "radius": 0.4, "origin": [0.0, 0.0, -0.1]},
])
def test_hydrostatics_match_capytaine(spec):
    """Our exact polyhedron integrals against capytaine's own rigid-body hydrostatics (mass 0, so
    only buoyancy) with the 2×2 Gauss-Legendre quadrature, which is exact on these planar panels
    for the quadratic integrands: agreement to round-off (1e-10)."""
    s = geo.normalize_spec(spec)
    hull = geo.body_meshes(s, 0.1 * s["radius"])[0]
    h = geo.hull_hydrostatics(hull, s["reference_point"], rho=RHO, g=G)
    body = cpt.FloatingBody(mesh=hull.with_quadrature("Gauss-Legendre 2"),
                            dofs=cpt.rigid_body_dofs(rotation_center=s["reference_point"]),
                            center_of_mass=s["reference_point"], mass=0.0)
    C = body.compute_hydrostatic_stiffness(rho=RHO, g=G).values
    scale = np.abs(C).max()
    assert np.abs(C - h["hydrostatic_stiffness"]).max() < 1e-10 * scale
    assert body.volume == pytest.approx(h["volume"], rel=1e-10)
    assert np.allclose(body.center_of_buoyancy, h["center_of_buoyancy"], atol=1e-10)
    # The water-plane part is capytaine's stiffness with the ρgV terms removed.
    V, (xB, yB, zB) = h["volume"], h["center_of_buoyancy"]
    xr, yr, zr = s["reference_point"]
    Cw = C.copy()
    Cw[3, 3] -= RHO * G * V * (zB - zr)
    Cw[4, 4] -= RHO * G * V * (zB - zr)
    Cw[3, 5] -= -RHO * G * V * (xB - xr)
    Cw[4, 5] -= -RHO * G * V * (yB - yr)
    assert np.abs(Cw - h["waterplane_stiffness"]).max() < 1e-10 * scale


def test_waterplane_parallel_axis_theorem():
    base = {"name": "c", "shape": "cylinder", "radius": 0.5, "draft": 0.3, "base": "hemisphere"}
    s0 = geo.normalize_spec({**base, "draft": 0.6})
    xr, yr = 0.3, -0.2
    s1 = geo.normalize_spec({**base, "draft": 0.6, "reference_point": [xr, yr, -0.1]})
    hull = geo.body_meshes(s0, 0.1)[0]
    W0 = geo.hull_hydrostatics(hull, s0["reference_point"])["waterplane_stiffness"]
    W1 = geo.hull_hydrostatics(hull, s1["reference_point"])["waterplane_stiffness"]
    k = W0[2, 2]  # ρ g A; the water plane's centroid is at x = y = 0
    expect = W0.copy()
    expect[3, 3] += k * yr**2
    expect[4, 4] += k * xr**2
    expect[3, 4] = expect[4, 3] = W0[3, 4] - k * xr * yr
    expect[2, 3] = expect[3, 2] = -k * yr
    expect[2, 4] = expect[4, 2] = k * xr
    assert np.allclose(W1, expect, rtol=1e-12, atol=1e-9 * k)


def _write_box_stl(path, lx, ly, h, zc):
    """ASCII STL of a closed box [-lx/2, lx/2] × [-ly/2, ly/2] × [zc - h/2, zc + h/2]."""
    x, y, z = lx / 2, ly / 2, h / 2
    v = np.array([[sx * x, sy * y, zc + sz * z] for sz in (-1, 1) for sy in (-1, 1)
                  for sx in (-1, 1)])
    quads = [(0, 2, 3, 1), (4, 5, 7, 6), (0, 1, 5, 4), (2, 6, 7, 3), (0, 4, 6, 2), (1, 3, 7, 5)]
    lines = ["solid box"]
    for q in quads:
        for tri in ((q[0], q[1], q[2]), (q[0], q[2], q[3])):
            a, b, c = v[list(tri)]
            nrm = np.cross(b - a, c - a)
            nrm /= np.linalg.norm(nrm)
            lines += [f"facet normal {nrm[0]} {nrm[1]} {nrm[2]}", "outer loop"]
            lines += [f"vertex {p[0]} {p[1]} {p[2]}" for p in (a, b, c)]
            lines += ["endloop", "endfacet"]
    lines.append("endsolid box")
    path.write_text("\n".join(lines))


def test_mesh_file_box_hydrostatics(tmp_path):
    pytest.importorskip("trimesh")
    stl = tmp_path / "box.stl"
    _write_box_stl(stl, 2.0, 1.0, 1.0, 0.0)  # half immersed once cut at z = 0
    s = geo.normalize_spec({"name": "box", "shape": "mesh", "file": str(stl),
                            "origin": [0.5, 0.0, -0.2]})
    hull, lid, _ = geo.body_meshes(s, 0.25)
    h = geo.hull_hydrostatics(hull, s["reference_point"], rho=RHO, g=G)
    draft = 0.7
    # A box is exact in panels: closed forms to round-off.
    assert h["volume"] == pytest.approx(2.0 * 1.0 * draft, rel=1e-12)
    assert h["center_of_buoyancy"] == pytest.approx([0.5, 0.0, -draft / 2], abs=1e-12)
    W = h["waterplane_stiffness"]
    assert W[2, 2] == pytest.approx(RHO * G * 2.0, rel=1e-12)
    assert W[3, 3] == pytest.approx(RHO * G * 2.0 * 1.0**3 / 12, rel=1e-12)
    assert W[4, 4] == pytest.approx(RHO * G * 1.0 * 2.0**3 / 12, rel=1e-12)
    assert lid is not None and lid.nb_faces > 0


RM3_DIR = Path(__file__).resolve().parents[1] / "hydro" / "data" / "rm3"   # shipped with the repo


def test_mesh_file_rm3_float_against_wamit():
    """The RM3 float STL at WAMIT's body origin (z = -0.72 m) against rm3.out: volume 725.833 m³,
    C33 = 285.52 ρg, C44 = 7347.0 ρg about the body origin. The STL is a different panelling of the
    hull than WAMIT's input (measured differences 0.14-0.35 %): 1 %."""
    d = RM3_DIR
    s = geo.normalize_spec({"name": "float", "shape": "mesh", "file": str(d / "float.stl"),
                            "origin": [0.0, 0.0, -0.72]})
    h = geo.hull_hydrostatics(geo.body_meshes(s, 1.0)[0], s["reference_point"], rho=RHO, g=G)
    assert h["volume"] == pytest.approx(725.833, rel=0.01)
    H = h["hydrostatic_stiffness"] / (RHO * G)
    assert H[2, 2] == pytest.approx(285.52, rel=0.01)
    assert H[3, 3] == pytest.approx(7347.0, rel=0.01)
    assert H[4, 4] == pytest.approx(7347.0, rel=0.01)


# ------------------------------------------------------------------------------------------------
# Solving: symmetry, interaction, depth, cache, NetCDF


LAYOUT = [
    {"name": "bow", "shape": "cylinder", "radius": 0.2, "draft": 0.15, "origin": [-1.0, 0.0, 0.0]},
    {"name": "p", "shape": "cylinder", "radius": 0.2, "draft": 0.3, "base": "hemisphere",
     "origin": [0.5, 0.6, 0.0], "reference_point": [0.5, 0.6, 0.1]},
    {"name": "s", "shape": "cylinder", "radius": 0.2, "draft": 0.3, "base": "hemisphere",
     "origin": [0.5, -0.6, 0.0], "reference_point": [0.4, -0.6, 0.1]},
]


def test_symmetric_layout_same_with_and_without_xoz_symmetry():
    """Three floats symmetric about y = 0 (one on the axis, a mirrored pair): one capytaine body
    with a ReflectionSymmetricMesh and DofOnSubmesh dofs against a plain capytaine Multibody. Both
    use the same panels, so they agree far inside the brief's 0.5 %; excitation at β = 0.3 rad
    (not symmetric) too."""
    kw = dict(omega=[4.0], dx=0.1, wave_directions=(0.3,), cache=False, progress=False)
    sym = bem.solve(LAYOUT, symmetry="auto", **kw)
    ref = bem.solve(LAYOUT, symmetry="none", **kw)
    assert sym.attrs["symmetry_used"] == "xOz" and ref.attrs["symmetry_used"] == "none"
    dofs = [f"{b['name']}__{m}" for b in LAYOUT for m in geo.MODES]
    assert sorted(sym["influenced_dof"].values) == sorted(dofs)
    for v in ("added_mass", "radiation_damping", "excitation_force"):
        a = sym[v].sel(influenced_dof=dofs)
        b = ref[v].sel(influenced_dof=dofs)
        if "radiating_dof" in a.dims:
            a, b = a.sel(radiating_dof=dofs), b.sel(radiating_dof=dofs)
        a, b = np.nan_to_num(a.values), np.nan_to_num(b.values)
        assert np.abs(a - b).max() <= 5e-3 * np.abs(b).max(), v
    # Interaction is in: the pair's cross heave added mass is not zero, and by the mirror
    # symmetry port/starboard heave terms are equal.
    A = ref["added_mass"].sel(omega=4.0)
    cross = float(A.sel(influenced_dof="p__Heave", radiating_dof="s__Heave"))
    own = float(A.sel(influenced_dof="p__Heave", radiating_dof="p__Heave"))
    assert abs(cross) > 1e-3 * own
    assert float(A.sel(influenced_dof="s__Heave", radiating_dof="s__Heave")) == pytest.approx(
        own, rel=1e-6)


def test_layout_symmetry_detection_and_request_errors():
    specs = geo.normalize_specs(LAYOUT)
    assert bem.layout_symmetry(specs) == "xOz"
    assert bem.layout_symmetry(specs[:1]) == "xOz"  # on y = 0, not on the z axis
    assert bem.layout_symmetry(specs[:2]) == "none"  # the port float has no partner
    hemi = geo.normalize_specs([{"name": "h", "shape": "hemisphere", "radius": 1.0}])
    assert bem.layout_symmetry(hemi) == "rotation"
    with pytest.raises(ValueError, match="symmetry"):
        bem.build_body(specs[:2], 0.1, symmetry="xOz")
    with pytest.raises(ValueError, match="symmetry"):
        bem.solve(LAYOUT, omega=[1.0], dx=0.1, symmetry="yOz", cache=False)


def test_rotation_symmetry_matches_plain_solve():
    """A single body of revolution on the z axis is solved with the rotation symmetry by
    default; the plain solve on the same panels gives the same numbers (1e-9)."""
    b = [{"name": "h", "shape": "sphere", "radius": 1.0, "reference_point": [0.1, 0.0, -0.2]}]
    kw = dict(omega=[2.0], dx=0.25, cache=False, progress=False)
    rot = bem.solve(b, **kw)
    plain = bem.solve(b, symmetry="none", **kw)
    assert rot.attrs["symmetry_used"] == "rotation"
    for v in ("added_mass", "radiation_damping", "excitation_force"):
        a, p = np.nan_to_num(rot[v].values), np.nan_to_num(plain[v].values)
        assert np.abs(a - p).max() < 1e-9 * np.abs(p).max(), v


def test_finite_depth_tends_to_deep_water_and_checks_the_sea_bed():
    b = [{"name": "h", "shape": "hemisphere", "radius": 1.0}]
    kw = dict(omega=[2.0], dx=0.25, cache=False, progress=False, infinite_frequency=False)
    deep = bem.solve(b, **kw)
    h20 = bem.solve(b, water_depth=20.0, **kw)
    assert h20.attrs["water_depth"] == 20.0 and np.isinf(deep.attrs["water_depth"])
    # kh = 8 at 20 m: the finite-depth Green function (a different code path) must reproduce the
    # deep-water one on the same panels; depth effects are O(e^{-2kh}) ~ 1e-7, so 0.5 % is the
    # accuracy of capytaine's finite-depth tabulation and Prony fit, not physics.
    for v in ("added_mass", "radiation_damping", "excitation_force"):
        a, d = h20[v].values, deep[v].values
        assert np.abs(a - d).max() < 5e-3 * np.abs(d).max(), v
    with pytest.raises(ValueError, match="water_depth"):
        bem.solve(b, water_depth=0.9, **kw)


def test_cache_second_call_is_a_hit(tmp_path, monkeypatch):
    b = [{"name": "h", "shape": "hemisphere", "radius": 1.0}]
    kw = dict(omega=[1.0], dx=0.3, cache_dir=tmp_path, progress=False)
    first = bem.solve(b, **kw)
    assert first.attrs["cache_status"] == "computed"
    assert len(list(tmp_path.glob("bem-*.nc"))) == 1

    def no_solver(*args, **kwargs):
        raise AssertionError("the solver ran although the result was cached")

    monkeypatch.setattr(bem, "_solve_problems", no_solver)
    second = bem.solve(b, **kw)
    assert second.attrs["cache_status"] == "hit"
    assert second.attrs["hash"] == first.attrs["hash"]
    np.testing.assert_array_equal(second["added_mass"].values, first["added_mass"].values)
    np.testing.assert_array_equal(second["excitation_force"].values,
                                  first["excitation_force"].values)
    # Any change of geometry or setting is a different key, so it would solve again.
    with pytest.raises(AssertionError, match="solver ran"):
        bem.solve(b, rho=1025.0, **kw)
    with pytest.raises(AssertionError, match="solver ran"):
        bem.solve([{**b[0], "radius": 1.01}], **kw)


def test_save_load_round_trip(tmp_path):
    ds = bem.load(SPHERE_NC)
    p = tmp_path / "again.nc"
    bem.save(ds, p)
    back = bem.load(p)
    for v in ("added_mass", "radiation_damping", "excitation_force", "hydrostatic_stiffness",
              "waterplane_stiffness", "displaced_volume", "center_of_buoyancy", "reference_point"):
        np.testing.assert_array_equal(back[v].values, ds[v].values)
    assert back["excitation_force"].dtype == np.complex128
    assert np.isinf(back.attrs["water_depth"]) and isinstance(back.attrs["water_depth"], float)
    assert json.loads(back.attrs["bodies"])[0]["shape"] == "sphere"
    # capytaine's own reader rejoins the complex values of our file the same way.
    from capytaine.io.xarray import merge_complex_values
    import xarray as xr
    with xr.open_dataset(p) as f:
        cap = merge_complex_values(f.load())
    np.testing.assert_array_equal(cap["excitation_force"].values, ds["excitation_force"].values)


# ------------------------------------------------------------------------------------------------
# Geometry validation


@pytest.mark.parametrize("spec, key", [
    ({"name": "a", "shape": "cone", "radius": 1.0}, "'shape'"),
    ({"name": "a", "shape": "cylinder", "draft": 1.0}, "'radius'"),
    ({"name": "a", "shape": "cylinder", "radius": -1.0, "draft": 1.0}, "'radius'"),
    ({"name": "a", "shape": "cylinder", "radius": 1.0, "draft": float("nan")}, "'draft'"),
    ({"name": "a", "shape": "cylinder", "radius": 1.0, "draft": 1.0, "base": "cone"}, "'base'"),
    ({"name": "a", "shape": "cylinder", "radius": 1.0, "draft": 0.5, "base": "hemisphere"},
     "'draft'"),
    ({"name": "a", "shape": "cylinder", "radius": 1.0, "draft": 1.0, "base": "rounded"},
     "'knuckle_radius'"),
    ({"name": "a", "shape": "cylinder", "radius": 1.0, "draft": 1.0, "base": "rounded",
      "knuckle_radius": 1.5}, "'knuckle_radius'"),
    ({"name": "a", "shape": "cylinder", "radius": 1.0, "draft": 1.0, "knuckle_radius": 0.2},
     "'knuckle_radius'"),
    ({"name": "a", "shape": "cylinder", "radius": 1.0, "draft": 1.0, "origin": [0, 0]}, "'origin'"),
    ({"name": "a", "shape": "cylinder", "radius": 1.0, "draft": 1.0, "origin": [0, 0, 0.1]},
     "'origin'"),
    ({"name": "a", "shape": "hemisphere", "radius": 1.0, "reference_point": "centre"},
     "'reference_point'"),
    ({"name": "a", "shape": "sphere", "radius": 1.0, "origin": [0, 0, 2.0]}, "'origin'"),
    ({"name": "a", "shape": "mesh", "file": "/no/such/hull.stl"}, "'file'"),
    ({"name": "a__b", "shape": "hemisphere", "radius": 1.0}, "'name'"),
    ({"name": "a", "shape": "hemisphere", "radius": 1.0, "colour": "red"}, "colour"),
])
def test_geometry_validation_errors_name_the_key(spec, key):
    with pytest.raises(ValueError, match=key):
        geo.normalize_spec(spec)


def test_duplicate_names_and_solver_settings_are_rejected():
    h = {"name": "a", "shape": "hemisphere", "radius": 1.0}
    with pytest.raises(ValueError, match="'name'"):
        geo.normalize_specs([h, h])
    for kw, key in (({"omega": [0.0, 1.0]}, "omega"), ({"omega": [1.0], "dx": -0.1}, "dx"),
                    ({"omega": [1.0], "rho": 0.0}, "rho"),
                    ({"omega": [1.0], "wave_directions": [np.nan]}, "wave_directions")):
        kw = {"dx": 0.3, **kw}
        with pytest.raises(ValueError, match=key):
            bem.solve([h], cache=False, **kw)


def test_meshes_are_closed_with_outward_normals_and_exact_water_line():
    """Each revolved hull: positive volume (outward normals), water-line vertices exactly at z = 0
    on the circle of the hull radius, lid normals pointing down and lid area = water-plane area."""
    for spec in ({"name": "a", "shape": "cylinder", "radius": 0.175, "draft": 0.214,
                  "base": "rounded", "knuckle_radius": 0.125},
                 {"name": "b", "shape": "cylinder", "radius": 0.125, "draft": 0.15,
                  "base": "hemisphere"},
                 {"name": "c", "shape": "sphere", "radius": 0.3, "origin": [0, 0, 0.1]}):
        s = geo.normalize_spec(spec)
        hull, lid, n = geo.body_meshes(s, 0.03)
        h = geo.hull_hydrostatics(hull, [0, 0, 0])
        assert h["volume"] > 0
        top = hull.vertices[np.abs(hull.vertices[:, 2]) < 1e-12]
        r_wl = geo.meridian(s, 0.03)[0, 0]
        assert len(top) == n and np.allclose(np.hypot(top[:, 0], top[:, 1]), r_wl, rtol=1e-12)
        assert np.all(lid.faces_normals[:, 2] < 0)
        assert lid.faces_areas.sum() == pytest.approx(h["waterplane_area"], rel=1e-12)
    # Meridian of the rounded base: wall, quarter torus of radius rk, then the flat disc.
    m = geo.meridian(geo.normalize_spec({"name": "a", "shape": "cylinder", "radius": 0.175,
                                         "draft": 0.214, "base": "rounded",
                                         "knuckle_radius": 0.125}), 0.01)
    knuckle = (m[:, 0] > 0.05 + 1e-9) & (m[:, 1] < -0.089 - 1e-9)
    assert np.allclose(np.hypot(m[knuckle, 0] - 0.05, m[knuckle, 1] + 0.089), 0.125)
    assert m[-1] == pytest.approx([0.0, -0.214])


STEPPED = [[8.0, 0.0], [8.0, -18.67], [16.0, -18.67], [16.0, -26.67], [0.0, -26.67]]


def test_revolved_profile_is_the_cylinder_and_a_stepped_column_converges():
    """shape "revolution": a flat cylinder's profile gives the cylinder's very panels; the stepped
    OC4-like column's inscribed volume converges to π(8²·18.67 + 16²·8) as O(dθ²) (the panel
    error of an inscribed polygon, 1 − sin(2π/n)/(2π/n)), and its water-plane area to π·8²."""
    cyl = geo.normalize_spec({"name": "c", "shape": "cylinder", "radius": 1.0, "draft": 0.7})
    rev = geo.normalize_spec({"name": "c", "shape": "revolution",
                              "profile": [[1.0, 0.0], [1.0, -0.7], [0.0, -0.7]]})
    np.testing.assert_array_equal(geo.meridian(cyl, 0.1), geo.meridian(rev, 0.1))
    assert geo.n_azimuth(cyl, 0.1) == geo.n_azimuth(rev, 0.1)
    col = geo.normalize_spec({"name": "col", "shape": "revolution", "profile": STEPPED})
    exact = math.pi * (64 * 18.67 + 256 * 8)
    for dx in (2.0, 1.0):
        hull = geo.body_meshes(col, dx, lid=False)[0]
        h = geo.hull_hydrostatics(hull, [0.0, 0.0, 0.0])
        n = geo.n_azimuth(col, dx)
        polygon = n * math.sin(2 * math.pi / n) / (2 * math.pi)   # inscribed area / circle area
        assert h["volume"] == pytest.approx(exact * polygon, rel=1e-9)
        assert h["waterplane_area"] == pytest.approx(math.pi * 64 * polygon, rel=1e-9)
    # the step faces up: the base's top ring adds buoyancy below the upper column's water line
    zB = (math.pi * 64 * 18.67 * (-18.67 / 2) + math.pi * 256 * 8 * (-18.67 - 4)) / exact
    assert h["center_of_buoyancy"][2] == pytest.approx(zB, rel=1e-9)


@pytest.mark.parametrize("profile, words", [
    ([[8.0, -1.0], [0.0, -2.0]], "water line"),
    ([[8.0, 0.0], [8.0, -2.0]], "axis"),
    ([[8.0, 0.0], [-1.0, -2.0], [0.0, -3.0]], "r must"),
    ([[8.0, 0.0], [8.0, 1.0], [0.0, -3.0]], "z ≤ 0"),
    ([[8.0, 0.0], [8.0, 0.0], [0.0, -3.0]], "repeats"),
    ([[8.0, 0.0], [0.0, -1.0], [4.0, -2.0], [0.0, -3.0]], "touches the axis"),
    ("tall", "not a list"),
])
def test_revolved_profile_errors_name_the_point(profile, words):
    with pytest.raises(ValueError, match="'profile'") as info:
        geo.normalize_spec({"name": "a", "shape": "revolution", "profile": profile})
    assert words in str(info.value)


def test_per_body_panel_size():
    """A body's own ``dx`` sets its panels, the layout's ``dx`` the others'."""
    small = {"name": "w", "shape": "hemisphere", "radius": 1.0, "dx": 0.1, "origin": [5.0, 0, 0]}
    big = {"name": "p", "shape": "cylinder", "radius": 1.0, "draft": 1.0}
    specs = geo.normalize_specs([big, small])
    body, used, hulls = bem.build_body(specs, 0.5, lid=False)
    own = geo.body_meshes(geo.normalize_spec(small), 0.1, lid=False)[0].nb_faces
    other = geo.body_meshes(geo.normalize_spec(big), 0.5, lid=False)[0].nb_faces
    assert hulls[1].nb_faces == own and hulls[0].nb_faces == other and own > other


def test_deep_water_above_kh_is_the_deep_solve_there_and_finite_below():
    """``deep_water_kh``: each frequency is solved exactly as the plain deep or finite-depth solve
    would (same panels, same code path; 1e-4: capytaine's finite-depth values of one ω move by
    ≈ 1e-5 with the other problems solved beside it, its Green-function and matrix caches), the
    dataset keeps the physical depth and records where the split lies."""
    b = [{"name": "h", "shape": "hemisphere", "radius": 1.0}]
    h = 4.0
    omega = [1.0, 2.0, 3.5]   # k h = 0.6, 1.8 (finite), 5.0 (deep: k = 3.5²/9.81 = 1.25 /m)
    kw = dict(dx=0.4, cache=False, progress=False)
    split = bem.solve(b, omega=omega, water_depth=h, deep_water_kh=4.9, **kw)
    fin = bem.solve(b, omega=omega[:2], water_depth=h, infinite_frequency=False, **kw)
    deep = bem.solve(b, omega=omega[2:], **kw)
    assert split.attrs["water_depth"] == h and split.attrs["deep_water_omega_min"] == "3.5"
    np.testing.assert_array_equal(split["omega"].values[:3], omega)
    for v in ("added_mass", "radiation_damping"):
        s = split[v].values
        np.testing.assert_allclose(s[:2], fin[v].values, rtol=1e-4, atol=1e-4 * np.abs(s).max())
        np.testing.assert_allclose(s[2:], deep[v].values, rtol=1e-4, atol=1e-4 * np.abs(s).max())
    ex = split["excitation_force"].values
    top = np.abs(ex[:3]).max()   # sway and roll are round-off (1e-13) at heading 0
    np.testing.assert_allclose(ex[:2], fin["excitation_force"].values, rtol=1e-4, atol=1e-9 * top)
    np.testing.assert_allclose(ex[2:3], deep["excitation_force"].values[:1], rtol=1e-4,
                               atol=1e-9 * top)
    # and the depth matters below the split: the finite-depth heave damping at k h = 0.6 is not
    # the deep-water one
    deep_low = bem.solve(b, omega=omega[:1], infinite_frequency=False, **kw)
    b_fin = float(split["radiation_damping"].values[0, 2, 2])
    assert abs(b_fin / float(deep_low["radiation_damping"].values[0, 2, 2]) - 1) > 0.05
    with pytest.raises(ValueError, match="deep_water_kh"):
        bem.solve(b, omega=omega, water_depth=h, deep_water_kh=-1.0, **kw)
