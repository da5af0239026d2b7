"""Issue 51 items 4-9: meshes a user brings to `mfm hydro`, checked before any solve.

No BEM is solved here: `hydro.bem.solve` (and its problem loop) is replaced by a function that
fails the test if reached, so a check that does not fire shows as "BEM reached", in seconds.
Meshes are built in code (trimesh boxes written to tmp_path, or capytaine meshes).
"""
from __future__ import annotations

import warnings
from types import SimpleNamespace

import numpy as np
import pytest
import xarray as xr

cpt = pytest.importorskip("capytaine")
trimesh = pytest.importorskip("trimesh")

import mfm  # noqa: E402
from hydro import bem, geometry as geo  # noqa: E402
from hydro.database import HydroDatabaseWarning  # noqa: E402
from hydro.prepare import HydroSpec  # noqa: E402
from mfm.io import bemgen  # noqa: E402

RHO = 1000.0


def _box(path, extents, centre=(0.0, 0.0, 0.0), faces=None):
    m = trimesh.creation.box(extents=extents)
    m.apply_translation(centre)
    if faces is not None:
        m = trimesh.Trimesh(m.vertices, faces(m), process=False)
    m.export(path)
    return path


CONFIG = """
[model]
name = "mesh float"
gravity = 9.81

[hydro]
database = "out.nc"

[hydro.bem]
omega = [1.0, 2.0]
water_depth = "inf"
dx = 0.25
{bem}

[[bodies]]
name = "float"
mass = {mass}
com = [0.0, 0.0, {zc}]
principal_inertia = [1000.0, 1000.0, 1000.0]
[bodies.joint]
type = "{joint}"
{joint_extra}
[bodies.geometry]
shape = "mesh"
file = "hull.stl"
{geometry}
"""


def _config(tmp_path, *, mass, zc, joint="free", joint_extra="", geometry="", bem_extra="",
            extra=""):
    cfg = tmp_path / "c.toml"
    cfg.write_text(CONFIG.format(mass=mass, zc=zc, joint=joint, joint_extra=joint_extra,
                                 geometry=geometry, bem=bem_extra) + extra)
    return cfg


@pytest.fixture
def no_bem(monkeypatch):
    """Any solve reached fails the test at once (the checks must come first)."""
    def reached(*a, **k):
        raise AssertionError("BEM reached")
    monkeypatch.setattr(bem, "solve", reached)
    monkeypatch.setattr(bem, "_solve_problems", reached)


# ------------------------------------------------------------------------------------------------
# Item 4: a mesh centred on the CoM, placed at z = 0 and cut there


def test_item4_mesh_centred_on_com_is_refused_naming_volumes_and_origin(tmp_path, no_bem):
    # a 2 x 1 x 2 m box centred on its file origin, the body's CoM at z = -0.4: at origin
    # z = -0.4 it is immersed 1.4 m (V 2.8 m³ = m/ρ); the default origin z = 0 immerses 1.0 m
    _box(tmp_path / "hull.stl", (2.0, 1.0, 2.0))
    cfg = _config(tmp_path, mass=2800.0, zc=-0.4)
    with pytest.raises(mfm.ConfigError) as e:
        bemgen.generate(cfg, progress=False, cache=False)
    msg = str(e.value)
    assert msg.startswith("bodies[0] ('float').geometry.origin:")
    assert "V = 2 m³" in msg and "ρV = 2000 kg" in msg and "m = 2800 kg" in msg and "-28.6%" in msg
    assert "origin = [0, 0, -0.4]" in msg                # the fix, the file being CoM-centred
    # given that origin, the same body passes every check and reaches the solve
    cfg = _config(tmp_path, mass=2800.0, zc=-0.4, geometry="origin = [0.0, 0.0, -0.4]")
    with pytest.raises(AssertionError, match="BEM reached"):
        bemgen.generate(cfg, progress=False, cache=False)


def test_item4_hinged_or_moored_bodies_are_not_refused(tmp_path, no_bem):
    """A body on a hinge need not float on its own; a config with loads (moorings...) warns."""
    _box(tmp_path / "hull.stl", (2.0, 1.0, 2.0))
    # the mesh body hangs on a revolute hinge from a dry root fixed in space: not checked
    dry = ('\n[[bodies]]\nname = "frame"\nmass = 10.0\ncom = [0.0, 0.0, 1.0]\n'
           'principal_inertia = [1.0, 1.0, 1.0]\n[bodies.joint]\ntype = "fixed"\n')
    cfg = tmp_path / "h.toml"
    text = CONFIG.format(mass=2800.0, zc=-0.4, joint="revolute",
                         joint_extra='axis = [0.0, 1.0, 0.0]\npoint = [0.0, 0.0, 1.0]',
                         geometry="", bem="")
    cfg.write_text(text.replace('[[bodies]]\nname = "float"', dry + '\n[[bodies]]\nname = '
                                '"float"\nparent = "frame"', 1))
    with pytest.raises(AssertionError, match="BEM reached"):
        bemgen.generate(cfg, progress=False, cache=False)
    # equilibrium_check = false: a warning naming the same numbers, then the solve
    cfg = _config(tmp_path, mass=2800.0, zc=-0.4, bem_extra="equilibrium_check = false")
    with pytest.warns(bemgen.HullWarning, match=r"ρV = 2000 kg.*m = 2800 kg"):
        with pytest.raises(AssertionError, match="BEM reached"):
            bemgen.generate(cfg, progress=False, cache=False)


def test_item4_heel_at_rest_is_refused(tmp_path, no_bem):
    # the right volume (2 m³ at origin z = 0) but the mesh 0.3 m off the CoM in x: a free
    # floater would trim; K55 = ρg(I_wp + V(z_B - z_G)) about G
    _box(tmp_path / "hull.stl", (2.0, 1.0, 2.0))
    cfg = _config(tmp_path, mass=2000.0, zc=-0.5, geometry="origin = [0.3, 0.0, 0.0]")
    with pytest.raises(mfm.ConfigError, match=r"geometry\.origin: 'float' turns in pitch .*"
                                              r"lies 0\.3 m \(x\).* by \d+\.\d+° at rest"):
        bemgen.generate(cfg, progress=False, cache=False)


# ------------------------------------------------------------------------------------------------
# Item 5: open or inward-facing meshes


def test_item5_open_mesh_is_refused_naming_the_edges(tmp_path, no_bem):
    # the box without its bottom (normal -z): before, V and the centre of buoyancy were silently
    # those of the open surface
    _box(tmp_path / "hull.stl", (2.0, 1.0, 2.0), (0.0, 0.0, -0.4),
         faces=lambda m: m.faces[m.face_normals[:, 2] > -0.5])
    cfg = _config(tmp_path, mass=2800.0, zc=-0.4)
    with pytest.raises(mfm.ConfigError, match=r"^bodies\[0\] \('float'\)\.geometry\.file: .*is "
                                              r"open: 4 edge\(s\).*\(-1, -0\.5, -1\.4\)"):
        bemgen.generate(cfg, progress=False, cache=False)
    spec = geo.normalize_spec({"name": "f", "shape": "mesh", "file": str(tmp_path / "hull.stl")})
    with pytest.raises(ValueError, match="is open"):
        geo.body_meshes(spec, 0.25)


def test_item5_inward_mesh_is_refused(tmp_path, no_bem):
    m = trimesh.creation.box(extents=(2.0, 1.0, 2.0))
    m.apply_translation((0.0, 0.0, -0.4))
    m.invert()
    m.export(tmp_path / "hull.stl")
    cfg = _config(tmp_path, mass=2800.0, zc=-0.4)
    with pytest.raises(mfm.ConfigError, match=r"geometry\.file: .*faces inward: its panels "
                                              r"enclose -4 m³.*m\.invert\(\)"):
        bemgen.generate(cfg, progress=False, cache=False)


def test_item5_closed_mesh_hydrostatics_exact():
    """The check accepts a closed box and keeps its exact hydrostatics."""
    box = cpt.mesh_parallelepiped(size=(2.0, 1.0, 2.0), center=(0.0, 0.0, -0.4), resolution=(4, 2, 4))
    geo.check_closed(box, what="box")
    h = geo.hull_hydrostatics(box.immersed_part(), (0, 0, 0))
    assert h["volume"] == pytest.approx(2.8, rel=1e-12)


# ------------------------------------------------------------------------------------------------
# Item 6: panels capytaine cannot solve


def _two_panels(shift):
    """Panel A horizontal at z = -1; panel B vertical in the plane x = 0.5, moved by `shift`."""
    A = [[0, 0, -1], [1, 0, -1], [1, 1, -1], [0, 1, -1]]
    B = (np.array([[0.5, -0.5, -1.5], [0.5, 0.5, -1.5], [0.5, 0.5, -0.5], [0.5, -0.5, -0.5]])
         + shift).tolist()
    return cpt.Mesh(np.array(A + B, float), [[0, 1, 2, 3], [4, 5, 6, 7]], auto_clean=False)


def test_item6_collocation_point_on_another_panel_edge_is_refused():
    # B's centre (0.5, 0, -1) lies on A's edge y = 0: capytaine's influence matrix holds NaN
    # there (measured: Delhommeau().evaluate gives 2 NaN in K)
    with pytest.raises(ValueError, match=r"panel 1 \(centre \(0\.5, 0, -1\)\) lies on an edge of "
                                         r"panel 0"):
        geo.check_collocation([_two_panels([0.0, 0.0, 0.0])], what="m")
    geo.check_collocation([_two_panels([0.0, -1.0, 0.0])], what="m")   # clear of A: accepted


def test_item6_mesh_file_with_such_panels_is_refused_before_the_solve(tmp_path, no_bem):
    # a closed box and a closed tetrahedron whose face centre lies on the box's bottom edge
    box = trimesh.creation.box(extents=(2.0, 1.0, 2.0))
    box.apply_translation((0.0, 0.0, -0.4))
    c = np.array([0.1, -0.5, -1.4])                     # on the edge y = -0.5, z = -1.4
    p = [c + [-0.3, -0.2, 0.2], c + [0.3, -0.2, 0.2], c + [0.0, 0.4, -0.4]]
    tip = c + [0.0, -0.6, -0.6]
    tet = trimesh.Trimesh(np.array(p + [tip]), [[0, 1, 2], [0, 3, 1], [1, 3, 2], [2, 3, 0]],
                          process=False)
    if tet.volume < 0:
        tet.invert()
    trimesh.Trimesh(np.vstack([box.vertices, tet.vertices]),
                    np.vstack([box.faces, tet.faces + 8]), process=False).export(tmp_path / "hull.stl")
    cfg = _config(tmp_path, mass=2800.0, zc=-0.4, geometry="origin = [0.0, 0.0, 0.0]")
    with pytest.raises(mfm.ConfigError, match=r"geometry\.file: .*collocation point\(s\) lie on "
                                              r"another panel.*lies on an edge of panel"):
        bemgen.generate(cfg, progress=False, cache=False)


# ------------------------------------------------------------------------------------------------
# Item 7: the lowest frequency against what capytaine accepts


def test_item7_kh_limit_is_capytaines(tmp_path, no_bem):
    # kh = 0.12 at 10 m: accepted before (KH_MIN was 0.1), fails in capytaine 3.0
    h, g = 10.0, 9.81
    kh = 0.12
    w = float(np.sqrt(g * kh / h * np.tanh(kh)))
    with pytest.raises(mfm.ConfigError, match=r"hydro\.bem\.omega: .*kh = 0\.12.*kh >= 0\.14"):
        bemgen.bem_settings({"omega": [w, 1.0], "water_depth": h, "dx": 0.1})
    # the solver's own Green function is asked, before any solve
    with pytest.raises(ValueError, match=r"cannot evaluate the finite-depth Green function at 1 "
                                         r"frequency: .*kh = 0\.12"):
        bem.check_finite_depth([w, 1.0], h, g)
    bem.check_finite_depth([float(np.sqrt(g * 0.15 / h * np.tanh(0.15)))], h, g)   # kh 0.15: fine
    bem.check_finite_depth([w], np.inf, g)                                         # deep water
    assert bemgen.KH_MIN == bem.KH_MIN == 0.14


# ------------------------------------------------------------------------------------------------
# Item 8: lids and symmetry for mesh hulls


def test_item8_mesh_closed_at_the_water_line_gets_its_lid_and_water_plane(tmp_path):
    # a box whose top is at z = 0: before, its deck panels stayed in the hull (C33 = 0: their
    # projected area cancelled the bottom's) and generate_lid found no lid panel, silently
    _box(tmp_path / "deck.stl", (2.0, 1.0, 1.0), (0.0, 0.0, -0.5))
    spec = geo.normalize_spec({"name": "b", "shape": "mesh", "file": str(tmp_path / "deck.stl")})
    hull, lid, _ = geo.body_meshes(spec, 0.2)
    h = geo.hull_hydrostatics(hull, (0, 0, 0))
    assert h["waterplane_area"] == pytest.approx(2.0, rel=1e-12)
    assert h["volume"] == pytest.approx(2.0, rel=1e-12)
    assert lid is not None and lid.nb_faces > 0
    assert np.all(np.abs(hull.faces_centers[:, 2]) > 1e-9)     # no panel left on z = 0


def test_item8_symmetric_mesh_uses_xoz_symmetry_and_a_lid(tmp_path):
    _box(tmp_path / "hull.stl", (2.0, 1.0, 2.0), (0.0, 0.0, -0.4))
    spec = geo.normalize_spec({"name": "b", "shape": "mesh", "file": str(tmp_path / "hull.stl")})
    assert bem.layout_symmetry([spec]) == "xOz"
    body, used, hulls = bem.build_body([spec], 0.25, lid=True)
    assert used == "xOz"
    assert isinstance(body.mesh, cpt.ReflectionSymmetricMesh)
    assert body.lid_mesh is not None and body.lid_mesh.nb_faces > 0
    # the half mirrored is the whole hull: same volume and water plane
    h = geo.hull_hydrostatics(body.mesh.merged(), (0, 0, 0))
    assert h["volume"] == pytest.approx(2.8, rel=1e-6)            # STL: float32 vertices
    assert h["waterplane_area"] == pytest.approx(2.0, rel=1e-6)
    # moved off y = 0 it is not symmetric about y = 0: the whole hull, with its lid
    off = geo.normalize_spec(dict(spec, origin=[0.0, 0.3, 0.0]))
    assert bem.layout_symmetry([off]) == "none"
    body, used, _ = bem.build_body([off], 0.25, lid=True)
    assert used == "none" and body.lid_mesh.nb_faces > 0


# ------------------------------------------------------------------------------------------------
# Item 9: the memory warning names what the user can do


def _resonance_db(a, omega, w0=5.0):
    """K(t) = e^{-at} cos(w0 t): B(ω) = ½[a/(a² + (ω − w0)²) + a/(a² + (ω + w0)²)]."""
    B = 0.5 * (a / (a * a + (omega - w0) ** 2) + a / (a * a + (omega + w0) ** 2))
    return xr.Dataset({"radiation_damping": (("omega", "influenced_dof", "radiating_dof"),
                                             B[:, None, None])},
                      coords={"omega": omega, "influenced_dof": ["b__Heave"],
                              "radiating_dof": ["b__Heave"]})


def test_item9_grid_warning_names_what_the_user_can_do():
    # K ∝ e^{-0.7 t} (below 1e-3 by 10 s) on a grid of step 0.8 rad/s (t_N = 3.9 s): the memory
    # measured on the interpolated K is 26 s, mostly the grid's alias; π/T_K = 0.12 rad/s was the
    # only advice, while a step of 0.4 already passes (measured ratio 0.53)
    om = np.arange(0.8, 25.01, 0.8)
    db = _resonance_db(0.7, om)
    T_K = 26.2
    spec = SimpleNamespace(database=lambda: db, wave_band=lambda: (float(om[0]), float(om[-1])),
                           moving=[0])
    with pytest.warns(HydroDatabaseWarning) as rec:
        ratio = HydroSpec.check_grid(spec, T_K)
    assert ratio > 1.0
    msg = str(rec[0].message)
    assert "radiation='state_space'" in msg
    assert "memory=3.927" in msg                                 # π/Δω, the resolved window
    step = float(msg.split("a step of about ")[1].split(" ")[0])
    assert 0.3 < step < 0.5                                      # the alias estimate, not 0.12
    finer = _resonance_db(0.7, np.arange(step, 25.01, step))
    from hydro.radiation import check_grid, impulse_response_memory
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", HydroDatabaseWarning)
        T_f = impulse_response_memory(finer, np.arange(0.0, 400.0, 0.05), rtol=1e-3)
    assert check_grid(finer, T_f) <= 1.0                         # the advised grid passes
