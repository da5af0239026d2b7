"""The nonlinear level's hull from a mesh file (issue 53, item 1): ``[bodies.hull] mesh = "path"``
and ``shape = "geometry"`` over a mesh geometry. The readers (hydro/meshfiles.py: WAMIT .gdf with
its symmetry flags, NEMOH .dat, ASCII and binary STL) against the analytic box written in each
format (the same panels, so the same volume and centre of buoyancy to round-off); a wetted
surface closed by its side continued up to a freeboard against the closed form; the sphere's
config with its hull as a mesh file against the analytic hull (the same triangles: the same
stiffness at rest to round-off); and every error, each naming the body, the file and the values.
The files are written here, into tmp_path, by the writers below."""
from __future__ import annotations

import copy
import math
import struct
import tomllib

import jax.numpy as jnp
import numpy as np
import pytest
from conftest import CONFIGS

import mfm
from hydro import meshfiles as M
from hydro import wetted as W
from mfm.errors import ConfigError

pytestmark = pytest.mark.filterwarnings("ignore::hydro.database.HydroDatabaseWarning")

SPHERE = tomllib.loads((CONFIGS / "sphere.toml").read_text())
SPHERE_DB = str((CONFIGS / SPHERE["hydro"]["database"]).resolve())

# the box: 4 × 2 m, from 1 m below still water to 1 m above; its panel size 0.125 m puts grid lines
# on x = 0 and y = 0 (its symmetry planes) and every coordinate is a multiple of 1/8 (exact in
# float32: the binary STL's precision costs nothing)
BOX = {"shape": "box", "length": 4.0, "beam": 2.0, "bottom": -1.0, "top": 1.0}
EPS = 1e-12


# ------------------------------------------------------------------------------------ writers
def _fmt(x):
    return f"{float(x):.17g}"


def panels_of(V, F):
    """Panels (n, 4, 3): quadrilaterals as they are, triangles with their last vertex repeated
    (the GDF and NEMOH way of storing a triangle)."""
    V, F = np.asarray(V, float), np.asarray(F)
    if F.shape[1] == 3:
        F = np.concatenate([F, F[:, 2:]], axis=1)
    return V[F]


def write_gdf(path, P, isx=0, isy=0, ulen=1.0, per_line=3):
    """A WAMIT .gdf of panels P (n, 4, 3): ``per_line`` numbers a line (the format is free)."""
    x = P.reshape(-1)
    rows = [" ".join(_fmt(v) for v in x[i:i + per_line]) for i in range(0, len(x), per_line)]
    path.write_text("\n".join(["written by test_hull_mesh.py", f"{ulen} 9.80665",
                               f"{isx} {isy}", f"{len(P)}"] + rows) + "\n")
    return path


def write_nemoh(path, P, isym=0):
    """A NEMOH mesh of panels P (n, 4, 3), the nodes shared (welded)."""
    pts, idx = M.weld(P.reshape(-1, 1, 3).repeat(3, axis=1))
    idx = idx[:, 0].reshape(-1, 4) + 1
    lines = [f"2 {isym}"] + [f"{i + 1} {_fmt(p[0])} {_fmt(p[1])} {_fmt(p[2])}"
                             for i, p in enumerate(pts)]
    lines += ["0 0.00 0.00 0.00"] + [" ".join(str(int(v)) for v in row) for row in idx]
    path.write_text("\n".join(lines + ["0 0 0 0"]) + "\n")
    return path


def write_stl_ascii(path, T):
    out = ["solid hull"]
    for t in T:
        n = np.cross(t[1] - t[0], t[2] - t[0])
        out += [f"  facet normal {' '.join(_fmt(v) for v in n / np.linalg.norm(n))}",
                "    outer loop"] + [f"      vertex {' '.join(_fmt(v) for v in p)}" for p in t]
        out += ["    endloop", "  endfacet"]
    path.write_text("\n".join(out + ["endsolid hull"]) + "\n")
    return path


def write_stl_binary(path, T):
    data = bytearray(b"binary STL written by test_hull_mesh.py".ljust(80, b" "))
    data += struct.pack("<I", len(T))
    for t in T:
        n = np.cross(t[1] - t[0], t[2] - t[0])
        data += struct.pack("<12fH", *(n / np.linalg.norm(n)), *t.reshape(-1), 0)
    path.write_bytes(bytes(data))
    return path


def _box():
    V, F = W.hull_mesh(BOX)
    return panels_of(V, F), W.triangles(V, F)


def _part(P, x=False, y=False, wet=False):
    """The panels of P with every vertex at x ≥ 0 (``x``), y ≥ 0 (``y``), z ≤ 0 (``wet``)."""
    keep = np.ones(len(P), bool)
    if x:
        keep &= np.all(P[..., 0] >= -EPS, axis=1)
    if y:
        keep &= np.all(P[..., 1] >= -EPS, axis=1)
    if wet:
        keep &= np.all(P[..., 2] <= EPS, axis=1)
    return P[keep]


def _still(T):
    v, c = W.submerged_volume(jnp.asarray(T), jnp.eye(3), jnp.zeros(3))
    return float(v), np.asarray(c)


# ------------------------------------------------------------------------------------ readers
def _written(kind, tmp_path):
    P, T = _box()
    if kind == "gdf":
        return write_gdf(tmp_path / "box.gdf", P)
    if kind == "gdf_isx_isy":
        return write_gdf(tmp_path / "box.gdf", _part(P, x=True, y=True), 1, 1, ulen=7.5,
                         per_line=12)
    if kind == "gdf_isy":
        return write_gdf(tmp_path / "box.gdf", _part(P, y=True), 0, 1)
    if kind == "gdf_isx":
        return write_gdf(tmp_path / "box.gdf", _part(P, x=True), 1, 0)
    if kind == "nemoh":
        return write_nemoh(tmp_path / "box.dat", P)
    if kind == "nemoh_isym":
        return write_nemoh(tmp_path / "box.dat", _part(P, y=True), 1)
    if kind == "stl_ascii":
        return write_stl_ascii(tmp_path / "box.stl", T)
    return write_stl_binary(tmp_path / "box.stl", T)


KINDS = ["gdf", "gdf_isx_isy", "gdf_isy", "gdf_isx", "nemoh", "nemoh_isym", "stl_ascii",
         "stl_binary"]


@pytest.mark.parametrize("kind", KINDS)
def test_each_reader_gives_the_analytic_box(kind, tmp_path):
    """The box written whole, as a symmetric half or quarter (GDF ISX/ISY, NEMOH ISYM: the
    reader mirrors the rest) and as ASCII and binary STL: the triangles read are closed and
    outward, and enclose the box's 16 m³ about its centre, its still-water part the closed form
    L B (−bottom) = 8 m³ at z = −0.5 m, as the analytic hull's triangles do, to round-off (1e-12
    of the volume and of the size: every coordinate is a multiple of 1/8, exact in every format).
    ULEN (7.5 in the quarter's file) scales nothing."""
    T_ref = _box()[1]
    T = M.read_mesh(_written(kind, tmp_path))
    W.check_hull(T, what=kind)
    v, c = M.volume_and_centroid(T)
    v_ref, c_ref = M.volume_and_centroid(T_ref)
    assert v == pytest.approx(16.0, rel=1e-12) and v_ref == pytest.approx(16.0, rel=1e-12)
    np.testing.assert_allclose(c, c_ref, rtol=0, atol=1e-12 * 4)
    np.testing.assert_allclose(c, 0.0, rtol=0, atol=1e-12 * 4)
    vs, cs = _still(T)
    assert vs == pytest.approx(8.0, rel=1e-12)
    np.testing.assert_allclose(cs, [0.0, 0.0, -0.5], rtol=0, atol=1e-12 * 4)
    # placed by `center` through [bodies.hull]: the analytic box with the same center
    center = [1.5, -2.0, 0.25]
    Vm, Fm = W.hull_mesh({"mesh": str(_written(kind, tmp_path)), "center": center})
    Va, Fa = W.hull_mesh({**BOX, "center": center})
    vm, cm = _still(W.triangles(Vm, Fm))
    va, ca = _still(W.triangles(Va, Fa))
    assert vm == pytest.approx(va, rel=1e-12) and va == pytest.approx(4 * 2 * 0.75, rel=1e-12)
    np.testing.assert_allclose(cm, ca, rtol=0, atol=1e-12 * 4)


def test_a_wetted_surface_closed_by_its_side_continued_up_to_a_freeboard(tmp_path):
    """The box's wetted part only (a BEM mesh stops at its water line), as a GDF quarter, with
    freeboard = 0.6 m: closed by vertical walls and a deck, the solid is the box from −1 to 0.6 m
    (12.8 m³ about z = −0.2 m, closed form) and its still-water part is the whole box's (8 m³ at
    z = −0.5 m), to round-off. The same file with a lid in the water plane (panels at z = 0, as
    capytaine's lids are) gives the same hull: the lid is replaced."""
    P = _box()[0]
    wet = _part(P, wet=True)
    f = write_gdf(tmp_path / "wet.gdf", _part(wet, x=True, y=True), 1, 1)
    V, F = W.hull_mesh({"mesh": str(f), "freeboard": 0.6})
    T = W.triangles(V, F)
    W.check_hull(T, what="closed")
    v, c = M.volume_and_centroid(T)
    assert v == pytest.approx(4 * 2 * 1.6, rel=1e-12)
    np.testing.assert_allclose(c, [0.0, 0.0, (-1.0 + 0.6) / 2], rtol=0, atol=1e-12 * 4)
    vs, cs = _still(T)
    assert vs == pytest.approx(8.0, rel=1e-12)
    np.testing.assert_allclose(cs, [0.0, 0.0, -0.5], rtol=0, atol=1e-12 * 4)
    lid = W.hull_mesh({**BOX, "top": 0.0})
    lidded = _part(panels_of(*lid), x=True, y=True)
    g = write_gdf(tmp_path / "lidded.gdf", lidded, 1, 1)
    T2 = W.triangles(*W.hull_mesh({"mesh": str(g), "freeboard": 0.6}))
    assert M.volume_and_centroid(T2)[0] == pytest.approx(12.8, rel=1e-12)
    # a waterline that is not convex (an L-shaped barge, two boxes side by side): the deck's ear
    # clipping still closes it, and the volume is the L's
    a = panels_of(*W.hull_mesh({"shape": "box", "length": 2.0, "beam": 1.0, "bottom": -1.0,
                                "top": 0.0, "center": [0.0, 0.0, 0.0], "panel_size": 0.25}))
    b = panels_of(*W.hull_mesh({"shape": "box", "length": 1.0, "beam": 1.0, "bottom": -1.0,
                                "top": 0.0, "center": [-0.5, 1.0, 0.0], "panel_size": 0.25}))
    L = np.concatenate([a, b])
    # the two boxes' shared wall (y = 0.5, −1 < x < 0) is inside the L: remove it from both
    inner = np.all(np.abs(L[..., 1] - 0.5) < EPS, axis=1) & np.all(L[..., 0] <= EPS, axis=1)
    L = L[~inner & ~np.all(np.abs(L[..., 2]) < EPS, axis=1)]
    h = write_nemoh(tmp_path / "L.dat", L)
    TL = W.triangles(*W.hull_mesh({"mesh": str(h), "freeboard": 0.5}))
    W.check_hull(TL, what="L")
    assert M.volume_and_centroid(TL)[0] == pytest.approx(3.0 * 1.5, rel=1e-12)
    assert _still(TL)[0] == pytest.approx(3.0, rel=1e-12)


# --------------------------------------------------------------------------- through the model
def _sphere_cfg(hull, geometry=None):
    cfg = copy.deepcopy(SPHERE)
    cfg["hydro"].update({"hydrostatics": "nonlinear", "database": SPHERE_DB})
    cfg["bodies"][0]["hull"] = hull
    if geometry is not None:
        cfg["bodies"][0]["geometry"] = geometry
    return cfg


def _sphere_panels():
    V, F = W.hull_mesh({"shape": "sphere", "radius": 1.0})
    return panels_of(V, F)


def _toml(cfg):
    def val(v):
        if isinstance(v, str):
            return '"' + v.replace("\\", "\\\\") + '"'
        if isinstance(v, bool):
            return "true" if v else "false"
        if isinstance(v, (list, tuple)):
            return "[" + ", ".join(val(x) for x in v) + "]"
        if isinstance(v, dict):
            return "{ " + ", ".join(f"{k} = {val(x)}" for k, x in v.items()) + " }"
        return repr(v)

    out = []
    for k, v in cfg.items():
        if k == "bodies":
            continue
        out.append(f"[{k}]")
        out += [f"{kk} = {val(vv)}" for kk, vv in v.items()]
    for b in cfg["bodies"]:
        out.append("[[bodies]]")
        out += [f"{kk} = {val(vv)}" for kk, vv in b.items()]
    return "\n".join(out) + "\n"


@pytest.fixture(scope="module")
def analytic_K():
    nl = mfm.load(_sphere_cfg({"shape": "sphere", "radius": 1.0}), base=CONFIGS)
    return np.asarray(mfm.frequency.linearise(nl)[2])


def test_a_config_with_a_mesh_file_is_the_analytic_hull(analytic_K, tmp_path):
    """The sphere's config with its hull as a NEMOH file (the analytic hull's own triangles,
    17 digits), named relative to a config file in tmp_path: the model runs the nonlinear level,
    and its stiffness at rest (jax's derivative through mfm.frequency.linearise) is the analytic
    hull's to 1e-10 (the same triangles: round-off)."""
    write_nemoh(tmp_path / "sphere.dat", _sphere_panels())
    path = tmp_path / "sphere_mesh.toml"
    path.write_text(_toml(_sphere_cfg({"mesh": "sphere.dat"})))
    model = mfm.load(path)
    assert model.hydro.hydrostatics == "nonlinear"
    K = np.asarray(mfm.frequency.linearise(model)[2])
    np.testing.assert_allclose(K, analytic_K, rtol=0, atol=1e-10 * np.abs(analytic_K).max())


def test_the_body_s_mesh_geometry_closed_up_to_top(tmp_path):
    """shape = "geometry" over a mesh geometry (the file `mfm hydro` would mesh): the wetted half
    of a hull of revolution (the sphere's lower half, 13 facets on its meridian, under a vertical
    wall to 0.5 m: the analytic `shape = "revolution"`), as a WAMIT quarter (ISX = ISY = 1),
    closed up to top = 0.5 m by its side continued vertically: the stiffness at its rest
    (linearised at the equilibrium, 3.4 mm below z = 0: the database's mass is ρ times its own
    panels' volume, 0.5 % above this hull's) is the analytic hull's to 1e-9, every entry: the
    same wetted triangles (mirrored: the other diagonal of planar trapezoids) and the same
    vertical wall (in other rows: a plane, integrated exactly)."""
    a = np.linspace(0.0, -np.pi / 2, 14)
    prof = [[0.0, 0.5], [1.0, 0.5]] + [[math.cos(t), math.sin(t)] for t in a[:-1]] + [[0.0, -1.0]]
    analytic = {"shape": "revolution", "profile": prof, "panel_size": 0.125}
    P = panels_of(*W.hull_mesh(analytic))
    write_gdf(tmp_path / "wet.gdf", _part(P, x=True, y=True, wet=True), 1, 1)
    K_a = np.asarray(mfm.frequency.linearise(mfm.load(_sphere_cfg(analytic), base=CONFIGS))[2])
    cfg = _sphere_cfg({"shape": "geometry", "top": 0.5},
                      geometry={"shape": "mesh", "file": "wet.gdf"})
    K = np.asarray(mfm.frequency.linearise(mfm.load(cfg, base=tmp_path))[2])
    np.testing.assert_allclose(K, K_a, rtol=0, atol=1e-9 * np.abs(K_a).max())
    assert K_a[1, 1] > 3e4 and K_a[2, 2] > 6e3            # heave, pitch: restoring
    # without top, the open hull is refused with the fix
    cfg["bodies"][0]["hull"] = {"shape": "geometry"}
    with pytest.raises(ConfigError, match=r"bodies \('sphere'\).hull \(shape 'geometry': the "
                       r"body's mesh file 'wet.gdf'\): \d+ edge\(s\) belong to one triangle only "
                       r".*top = <m>"):
        mfm.load(cfg, base=tmp_path)


def test_a_mesh_of_another_hull_is_refused_naming_both(tmp_path):
    """A mesh whose still-water volume is not the database body's (the sphere scaled by 1.3):
    refused when the model loads, the error naming the body, the file and both volumes."""
    P = _sphere_panels() * 1.3
    write_stl_ascii(tmp_path / "big.stl", W.triangles(P.reshape(-1, 3),
                                                      np.arange(4 * len(P)).reshape(-1, 4)))
    cfg = _sphere_cfg({"mesh": "big.stl"})
    with pytest.raises(ConfigError, match=r"bodies \('sphere'\).hull.mesh 'big.stl': at rest it "
                       r"displaces 4\.\d+ m³ .* the database body 'sphere' 2\.09\d+ m³"):
        mfm.load(cfg, base=tmp_path)
    # a config file's mesh is read (and checked) when the config is read
    path = tmp_path / "c.toml"
    path.write_text(_toml(_sphere_cfg({"mesh": "missing.stl"})))
    with pytest.raises(ConfigError, match=r"bodies\[0\] \('sphere'\).hull.mesh 'missing.stl': "
                       r"file .*missing.stl' not found"):
        mfm.load(path)


# ------------------------------------------------------------------------------------ errors
def _bad(tmp_path, T, name="bad.stl", **keys):
    f = write_stl_ascii(tmp_path / name, T)
    return lambda: W.hull_mesh({"mesh": str(f), **keys}, where="bodies ('b').hull")


def test_bad_meshes_are_refused(tmp_path):
    """Open (with how many edges, a sample and the three fixes), inward, non-manifold, flipped
    panels, a lid at the water line without a freeboard, a freeboard on a closed hull, a hole off
    the water line with a freeboard: each names the table and the file."""
    T = _box()[1]
    where = r"bodies \('b'\).hull.mesh '.*bad.stl': "
    with pytest.raises(ValueError, match=where + r"\d+ edge\(s\) belong to one triangle only "
                       r"\(\(.*\)–\(.*\).* and \d+ more\): the hull is open; .*whole hull.*"
                       r"freeboard = <m>.*analytic shape"):
        _bad(tmp_path, T[:-2])()
    with pytest.raises(ValueError, match=where + r"enclosed volume -16 m³ ≤ 0: the normals point "
                       "inward"):
        _bad(tmp_path, T[:, ::-1])()
    with pytest.raises(ValueError, match=where + r"3 non-manifold edge\(s\), shared by three or "
                       "more triangles"):
        _bad(tmp_path, np.concatenate([T, T[:1]]))()
    flipped = T.copy()
    flipped[0] = flipped[0, ::-1]
    with pytest.raises(ValueError, match=where + r"3 edge\(s\) run the same way in two triangles "
                       r".*not ordered consistently"):
        _bad(tmp_path, flipped)()
    lidded = W.triangles(*W.hull_mesh({**BOX, "top": 0.0}))
    with pytest.raises(ValueError, match=where + r"closed by a lid at the still-water line .*"
                       "give freeboard"):
        _bad(tmp_path, lidded)()
    with pytest.raises(ValueError, match=where + r"the mesh reaches z = 1 m above still water"):
        _bad(tmp_path, T, freeboard=0.5)()
    wet = T[np.all(T[..., 2] <= EPS, axis=1)]
    hole = wet[np.argmin(wet[:, :, 2].max(axis=1))]          # a bottom panel
    holed = wet[~np.all(wet == hole, axis=(1, 2))]
    with pytest.raises(ValueError, match=where + r"3 open edge\(s\) lie off the water line z = 0 "
                       r".*a hole"):
        _bad(tmp_path, holed, freeboard=0.5)()
    sub = T + np.array([0.0, 0.0, -2.0])                     # wholly under water
    with pytest.raises(ValueError, match=where + r"no open water line to continue up to "
                       r"freeboard = 0.5 m \(the mesh does not pierce z = 0\)"):
        _bad(tmp_path, sub, freeboard=0.5)()


def test_bad_files_and_keys_are_refused(tmp_path):
    """The files: an unknown suffix, a missing file, a GDF header or panel count that is wrong,
    a NEMOH list without its end, STL that is neither binary nor ASCII; the keys: mesh with shape
    or panel_size, a non-positive freeboard, center not [x, y, z]; a closed mesh geometry under a
    top; a config given as a dict checks its keys when read and its file when it loads."""
    hm = lambda spec: W.hull_mesh(spec, where="h")  # noqa: E731
    with pytest.raises(ValueError, match=r"h.mesh 'a.obj': suffix '.obj' is not a mesh format "
                       r"read here; accepted: \['.dat', '.gdf', '.mar', '.nemoh', '.stl'\]"):
        hm({"mesh": "a.obj"})
    with pytest.raises(ValueError, match=r"h.mesh '.*nothere.gdf': file .* not found"):
        hm({"mesh": str(tmp_path / "nothere.gdf")})
    g = tmp_path / "h.gdf"
    g.write_text("title\n1 9.81\n0 0\n")
    with pytest.raises(ValueError, match=r"h.gdf: 3 line\(s\)"):
        M.read_mesh(g)
    g.write_text("title\n1 9.81\n2 0\n1\n0 0 0 1 0 0 1 1 0 0 1 0\n")
    with pytest.raises(ValueError, match=r"ISX, ISY = 2, 0; accepted 0 or 1"):
        M.read_mesh(g)
    g.write_text("title\n1 9.81\n0 0\n2\n0 0 0 1 0 0 1 1 0 0 1 0\n")
    with pytest.raises(ValueError, match=r"NPAN = 2 panels need 24 coordinates; the file has 12"):
        M.read_mesh(g)
    d = tmp_path / "h.dat"
    d.write_text("2 0\n1 0 0 0\n2 1 0 0\n3 1 1 0\n0 0 0 0\n1 2 3 3\n")
    with pytest.raises(ValueError, match=r"does not end with a line of zeros"):
        M.read_mesh(d)
    d.write_text("2 0\n1 0 0 0\n2 1 0 0\n3 1 1 0\n0 0 0 0\n1 2 3 9\n0 0 0 0\n")
    with pytest.raises(ValueError, match=r"panels name nodes 1 to 9; the file has 3 nodes"):
        M.read_mesh(d)
    s = tmp_path / "h.stl"
    s.write_bytes(b"\x00" * 90)
    with pytest.raises(ValueError, match=r"neither binary STL .*90\) nor ASCII STL"):
        M.read_mesh(s)
    f = write_stl_ascii(tmp_path / "box.stl", _box()[1])
    with pytest.raises(ValueError, match=r"h: give shape or mesh, not both"):
        hm({"mesh": str(f), "shape": "box"})
    with pytest.raises(ValueError, match=r"h: key\(s\) \['panel_size'\] do not go with mesh"):
        hm({"mesh": str(f), "panel_size": 0.1})
    with pytest.raises(ValueError, match=r"h.freeboard: -1; give a positive height in m"):
        hm({"mesh": str(f), "freeboard": -1})
    with pytest.raises(ValueError, match=r"h.center: \[1, 2\]; give \[x, y, z\]"):
        hm({"mesh": str(f), "center": [1, 2]})
    with pytest.raises(ValueError, match=r"h.shape: 'mesh'; accepted: .* or mesh = \"<file>\""):
        hm({"shape": "mesh"})
    geo = {"shape": "mesh", "file": str(f), "origin": [0.0, 0.0, 0.0]}
    with pytest.raises(ValueError, match=r"h \(shape 'geometry': the body's mesh file .*box.stl'\): "
                       r"the mesh reaches z = 1 m above still water, so it is not the wetted "
                       r"surface only; leave top out"):
        W.hull_mesh({"shape": "geometry", "top": 0.5}, where="h", geometry=geo)
    with pytest.raises(ValueError, match=r"h.panel_size: the body's geometry is a mesh file"):
        W.hull_mesh({"shape": "geometry", "panel_size": 0.1}, where="h", geometry=geo)
    # the closed mesh geometry, no top: the box itself
    T = W.triangles(*W.hull_mesh({"shape": "geometry"}, where="h", geometry=geo))
    assert M.volume_and_centroid(T)[0] == pytest.approx(16.0, rel=1e-12)
    # a config given as a dict: its file is read when it loads (base), its keys when it is read
    with pytest.raises(ConfigError, match=r"bodies\[0\] \('sphere'\).hull.freeboard: 0"):
        mfm.load(_sphere_cfg({"mesh": "sphere.dat", "freeboard": 0}), base=tmp_path)
    with pytest.raises(ConfigError, match=r"bodies \('sphere'\).hull.mesh 'sphere.dat': file "
                       r".*sphere.dat' not found"):
        mfm.load(_sphere_cfg({"mesh": "sphere.dat"}), base=tmp_path)


def test_the_extrusion_s_own_checks():
    """extrude_waterline on a closed mesh, a rim that is not loops, a bad freeboard; and the
    deck's ear clipping on a square gives two triangles of the square's area."""
    T = _box()[1]
    with pytest.raises(ValueError, match="the mesh is closed: nothing to extrude"):
        M.extrude_waterline(T, 1.0)
    wet = T[np.all(T[..., 2] <= EPS, axis=1)]
    with pytest.raises(ValueError, match=r"freeboard: 0; give a positive height"):
        M.extrude_waterline(wet, 0)
    tri = M._ear_clip(np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]]))
    assert len(tri) == 2
    with pytest.raises(ValueError, match="two open edges leave one vertex"):
        M._loops(np.array([[0, 1], [0, 2], [1, 0], [2, 0]]))


def test_the_stiffness_at_rest_with_the_water_line_on_vertices():
    """A hull whose water line at rest runs along its vertices (the analytic sphere's equator
    ring, every BEM mesh cut at z = 0): jax's derivative of the still-water force and moment is
    the polyhedron's closed form, heave ρ g A_wp with A_wp = (n/2) sin(2π/n) of its n = 52-gon and
    pitch about the centre ρ g (I_wp + V z_B), I_wp = (n/24) sin(2π/n)(2 + cos(2π/n)), to 1e-12.
    (A quadrilateral's second half is degenerate at rest and grows linearly with the motion: its
    area taken by a norm had no derivative there, and the heave stiffness came out 0.12 % high.)"""
    import jax

    T = jnp.asarray(W.triangles(*W.hull_mesh({"shape": "sphere", "radius": 1.0})))

    def loads(z, th):
        c, s = jnp.cos(th), jnp.sin(th)
        R = jnp.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])
        F, Mo = W.pressure_loads(T, R, jnp.array([0.0, 0.0, z]), jnp.zeros(3), W.still_water(),
                                 0.0, rho=1.0, g=1.0)
        return F[2], Mo[1]

    n, a = 52, 2 * math.pi / 52
    A_wp, I_wp = n / 2 * math.sin(a), n / 24 * math.sin(a) * (2 + math.cos(a))
    v, c = _still(np.asarray(T))
    assert float(jax.grad(lambda z: loads(z, 0.0)[0])(0.0)) == pytest.approx(-A_wp, rel=1e-12)
    assert float(jax.grad(lambda t: loads(0.0, t)[1])(0.0)) == pytest.approx(
        -(I_wp + v * c[2]), abs=1e-12 * A_wp)


@pytest.mark.parametrize("kind", KINDS)
def test_capytaine_reads_the_same_hull(kind, tmp_path):
    """The same files through capytaine's own readers (what `mfm hydro` meshes: its GDF and NEMOH
    symmetry flags, trimesh's STL), an independent reading of each format: the same enclosed
    volume, and the same still-water volume and centre of buoyancy, to 1e-12. Skipped where
    capytaine (the BEM's optional dependency) is not installed."""
    cpt = pytest.importorskip("capytaine")
    f = _written(kind, tmp_path)
    m = cpt.load_mesh(str(f), file_format={".gdf": "gdf", ".dat": "nemoh", ".stl": "stl"}[f.suffix])
    m = m.merged()
    T_c = W.triangles(np.asarray(m.vertices, float), np.asarray(m.faces).reshape(-1, 4))
    T = M.read_mesh(f)
    assert M.volume_and_centroid(T_c)[0] == pytest.approx(M.volume_and_centroid(T)[0], rel=1e-12)
    (vc, cc), (v, c) = _still(T_c), _still(T)
    assert vc == pytest.approx(v, rel=1e-12)
    np.testing.assert_allclose(cc, c, rtol=0, atol=1e-12 * 4)
