"""Hull geometry for the BEM: capytaine meshes from plain-dict body specs, and their hydrostatics.

A body spec is a plain dict (JSON-able, so it can be hashed and stored in a dataset's attrs):

- ``{"name", "shape": "cylinder", "radius", "draft", "base": "flat" | "hemisphere" | "rounded",
  "knuckle_radius" (for "rounded" only), "origin", "reference_point"}``: a vertical circular float.
  "rounded" is a flat disc of radius ``radius - knuckle_radius`` joined to the wall by a
  quarter-torus knuckle of radius ``knuckle_radius``. ``origin`` is the point on the axis at the
  still-water line (its z must be 0: the draft sets the immersion).
- ``{"name", "shape": "sphere", "radius", "origin" (= centre), "reference_point"}``: pierces the
  surface when ``|z_c| < radius`` (the part above z = 0 is cut off exactly), else fully submerged.
- ``{"name", "shape": "hemisphere", "radius", "origin", "reference_point"}``: a floating hemisphere,
  flat face at the still-water line (origin = centre of that face, z = 0).
- ``{"name", "shape": "revolution", "profile": [[r, z], ...], "origin", "reference_point"}``: any
  body of revolution about the vertical axis through ``origin`` (z 0), given by its meridian
  polyline (r ≥ 0 from the axis, z ≤ 0 absolute): from the water line (first point, z = 0, r > 0)
  down the wetted surface to the keel on the axis (last point, r = 0). Stepped columns and heave
  plates: ``[[8, 0], [8, -18.67], [16, -18.67], [16, -26.67], [0, -26.67]]`` is an OC4-like
  column of D 16 m on a base of D 32 m. It keeps the layout's symmetries, unlike a mesh file.
- ``{"name", "shape": "mesh", "file": "hull.stl", "origin", "reference_point"}``: any mesh file
  capytaine reads (STL via trimesh), translated by ``origin`` and cut at z = 0.

Lengths in m. ``reference_point`` (default: ``origin``) is the rotation centre of the 6 rigid dofs.
Optional ``dx`` (m): this body's panel size, in place of the layout's (a small float beside a large
platform needs finer panels than the platform).

Bodies of revolution are revolved from their meridian (r, z) profile, whose points lie on the exact
surface: the panels are inscribed, so volumes and water-plane integrals converge as O(dθ²) and the
panel size ``dx`` (m) is the only resolution setting. The revolution can return the whole hull, the
half y ≥ 0 (for a ``ReflectionSymmetricMesh`` about xOz) or one wedge (for a
``RotationSymmetricMesh``); the lid (against irregular frequencies) is the water-plane disc revolved
the same way, so it matches the hull's water line exactly.
"""
from __future__ import annotations

import math
import numbers
import os

import numpy as np

SHAPES = ("cylinder", "sphere", "hemisphere", "revolution", "mesh")
BASES = ("flat", "hemisphere", "rounded")
MODES = ("Surge", "Sway", "Heave", "Roll", "Pitch", "Yaw")
_KEYS = {
    "cylinder": {"name", "shape", "radius", "draft", "base", "knuckle_radius", "origin",
                 "reference_point", "dx"},
    "sphere": {"name", "shape", "radius", "origin", "reference_point", "dx"},
    "hemisphere": {"name", "shape", "radius", "origin", "reference_point", "dx"},
    "revolution": {"name", "shape", "profile", "origin", "reference_point", "dx"},
    "mesh": {"name", "shape", "file", "origin", "reference_point", "dx"},
}
REVOLVED = ("cylinder", "sphere", "hemisphere", "revolution")


# ------------------------------------------------------------------------------------------------
# Validation


def _where(spec_index):
    return "body spec" if spec_index is None else f"body spec #{spec_index}"


def _positive(spec, key, where):
    v = spec.get(key)
    if v is None:
        raise ValueError(f"{where}: missing key {key!r} (a positive length in m) for shape "
                         f"{spec.get('shape')!r}; add e.g. {key!r}: 1.0.")
    if isinstance(v, bool) or not isinstance(v, numbers.Real) or not math.isfinite(v) or v <= 0:
        raise ValueError(f"{where}: {key!r} = {v!r} is not a positive finite number (m); "
                         f"give a length > 0.")
    return float(v)


def _point(spec, key, where, default):
    v = spec.get(key, default)
    try:
        p = np.asarray(v, dtype=float)
    except (TypeError, ValueError):
        p = None
    if p is None or p.shape != (3,) or not np.all(np.isfinite(p)):
        raise ValueError(f"{where}: {key!r} = {v!r} is not a point [x, y, z] of 3 finite numbers "
                         f"(m); give e.g. {key!r}: [0.0, 0.0, 0.0].")
    return [float(c) for c in p]


def normalize_spec(spec, index=None):
    """Validate one body spec and return a new dict with every default filled in.

    Raises ``ValueError`` (``TypeError`` for a non-dict) naming the key, the bad value, what is
    accepted and the fix. ``index`` (position in the list of bodies) is only used in messages.
    """
    where = _where(index)
    if not isinstance(spec, dict):
        raise TypeError(f"{where}: expected a dict such as {{'name': 'float1', 'shape': "
                        f"'cylinder', 'radius': 0.1, 'draft': 0.07, 'base': 'flat'}}, "
                        f"got {type(spec).__name__} {spec!r}.")
    shape = spec.get("shape")
    if shape not in SHAPES:
        raise ValueError(f"{where}: 'shape' = {shape!r} is not one of {list(SHAPES)}.")
    unknown = set(spec) - _KEYS[shape]
    if unknown:
        raise ValueError(f"{where}: unknown key(s) {sorted(unknown)} for shape {shape!r}; "
                         f"accepted keys: {sorted(_KEYS[shape])}.")
    name = spec.get("name", None if index is None else f"body{index}")
    if name is None:
        name = "body"
    if not isinstance(name, str) or not name or "__" in name or name.strip() != name:
        raise ValueError(f"{where}: 'name' = {name!r} must be a non-empty string without '__' "
                         f"(dofs are named '<name>__Heave') and without surrounding spaces.")
    out = {"name": name, "shape": shape}
    out["origin"] = _point(spec, "origin", where, [0.0, 0.0, 0.0])

    if shape == "cylinder":
        out["radius"] = _positive(spec, "radius", where)
        out["draft"] = _positive(spec, "draft", where)
        base = spec.get("base", "flat")
        if base not in BASES:
            raise ValueError(f"{where}: 'base' = {base!r} is not one of {list(BASES)}.")
        out["base"] = base
        if base == "rounded":
            rk = _positive(spec, "knuckle_radius", where)
            if rk > out["radius"] or rk > out["draft"]:
                raise ValueError(f"{where}: 'knuckle_radius' = {rk!r} exceeds the radius "
                                 f"({out['radius']}) or the draft ({out['draft']}); give "
                                 f"knuckle_radius <= min(radius, draft).")
            out["knuckle_radius"] = rk
        elif "knuckle_radius" in spec:
            raise ValueError(f"{where}: 'knuckle_radius' = {spec['knuckle_radius']!r} is only "
                             f"used with 'base': 'rounded' (got base {base!r}); remove it.")
        if base == "hemisphere" and out["draft"] < out["radius"]:
            raise ValueError(f"{where}: 'draft' = {out['draft']} is smaller than 'radius' = "
                             f"{out['radius']} for base 'hemisphere'; the draft must be >= the "
                             f"radius (use shape 'sphere' for a shallower spherical cap).")
    elif shape in ("sphere", "hemisphere"):
        out["radius"] = _positive(spec, "radius", where)
        if shape == "sphere" and out["origin"][2] >= out["radius"]:
            raise ValueError(f"{where}: 'origin' z = {out['origin'][2]} puts the sphere (radius "
                             f"{out['radius']}) entirely above the water; give a centre "
                             f"z < radius.")
    elif shape == "revolution":
        out["profile"] = _profile(spec.get("profile"), where)
    else:  # mesh
        f = spec.get("file")
        if not isinstance(f, (str, os.PathLike)) or not os.path.isfile(f):
            raise ValueError(f"{where}: 'file' = {f!r} is not an existing mesh file; give the path "
                             f"of an STL (or gdf/nemoh/pnl/hst) file.")
        out["file"] = os.path.abspath(os.fspath(f))
    if shape in ("cylinder", "hemisphere", "revolution") and out["origin"][2] != 0.0:
        raise ValueError(f"{where}: 'origin' z = {out['origin'][2]} must be 0 for shape {shape!r} "
                         f"(the origin is on the axis at the still-water line; the draft sets the "
                         f"immersion).")
    out["reference_point"] = _point(spec, "reference_point", where, out["origin"])
    if spec.get("dx") is not None:
        out["dx"] = _positive(spec, "dx", where)
    return out


def _profile(prof, where):
    """A meridian polyline [[r, z], ...]: water line (z = 0, r > 0) first, keel on the axis
    (r = 0) last, r ≥ 0, z ≤ 0, no repeated consecutive point. Returned as a list of [r, z]."""
    example = "[[8, 0], [8, -18.67], [16, -18.67], [16, -26.67], [0, -26.67]]"
    try:
        P = np.asarray(prof, dtype=float)
    except (TypeError, ValueError):
        P = np.zeros((0,))
    if P.ndim != 2 or P.shape[1] != 2 or len(P) < 2 or not np.all(np.isfinite(P)):
        raise ValueError(f"{where}: 'profile' = {prof!r} is not a list of at least two finite "
                         f"[r, z] points (m); e.g. {example}.")
    if P[0, 1] != 0.0 or P[0, 0] <= 0.0:
        raise ValueError(f"{where}: 'profile' starts at {P[0].tolist()}; it must start on the "
                         f"water line, [r > 0, 0] (a surface-piercing body), e.g. {example}.")
    if P[-1, 0] != 0.0:
        raise ValueError(f"{where}: 'profile' ends at {P[-1].tolist()}; it must end on the axis, "
                         f"[0, z_keel], so that the revolved surface is closed.")
    bad = np.nonzero((P[:, 0] < 0) | (P[:, 1] > 0))[0]
    if bad.size:
        raise ValueError(f"{where}: 'profile' point {int(bad[0])} = {P[bad[0]].tolist()}: r must "
                         f"be ≥ 0 (distance from the axis) and z ≤ 0 (the wetted surface).")
    seg = np.linalg.norm(np.diff(P, axis=0), axis=1)
    if np.any(seg == 0):
        raise ValueError(f"{where}: 'profile' repeats point {int(np.argmin(seg))} "
                         f"({P[int(np.argmin(seg))].tolist()}); give each point once.")
    if np.any(P[1:-1, 0] == 0.0):
        raise ValueError(f"{where}: 'profile' touches the axis before its last point; a body of "
                         f"revolution is one closed surface (one keel point on the axis).")
    return P.tolist()


def normalize_specs(bodies):
    """Validate a list of body specs (or a single spec); names must be unique."""
    if isinstance(bodies, dict):
        bodies = [bodies]
    if not isinstance(bodies, (list, tuple)) or len(bodies) == 0:
        raise ValueError(f"bodies = {bodies!r}: give a non-empty list of body spec dicts.")
    specs = [normalize_spec(b, i) for i, b in enumerate(bodies)]
    names = [s["name"] for s in specs]
    dup = sorted({n for n in names if names.count(n) > 1})
    if dup:
        raise ValueError(f"bodies: duplicate 'name' value(s) {dup}; every body needs its own name.")
    return specs


# ------------------------------------------------------------------------------------------------
# Meridian profiles and revolution


def _arc(cr, cz, rad, a0, a1, dx):
    """Points (r, z) = (cr + rad cos a, cz + rad sin a) on a circle, a from a0 to a1 included."""
    n = max(2, math.ceil(abs(a1 - a0) * rad / dx))
    a = np.linspace(a0, a1, n + 1)
    return np.stack([cr + rad * np.cos(a), cz + rad * np.sin(a)], axis=1)


def _line(p0, p1, dx):
    n = max(1, math.ceil(math.dist(p0, p1) / dx))
    t = np.linspace(0.0, 1.0, n + 1)[:, None]
    return (1 - t) * np.asarray(p0, float) + t * np.asarray(p1, float)


def _chain(*pieces):
    """Concatenate profile pieces, dropping each piece's first point (shared with the last)."""
    out = [pieces[0]] + [p[1:] for p in pieces[1:]]
    return np.concatenate(out, axis=0)


def meridian(spec, dx):
    """Meridian profile of a body of revolution: r from its own axis, z absolute (0 = still water).

    Returns an array (n, 2) of (r, z) in m, ordered along the wetted surface from the water line
    (or the top, when fully submerged) down to the keel on the axis (r = 0): this order gives
    outward normals once revolved. Points lie on the exact surface, spaced at most ``dx``.
    """
    s = spec
    if s["shape"] == "cylinder":
        R, d = s["radius"], s["draft"]
        if s["base"] == "flat":
            return _chain(_line((R, 0.0), (R, -d), dx), _line((R, -d), (0.0, -d), dx))
        if s["base"] == "hemisphere":
            side = [_line((R, 0.0), (R, -(d - R)), dx)] if d > R else []
            return _chain(*side, _arc(0.0, -(d - R), R, 0.0, -math.pi / 2, dx))
        rk = s["knuckle_radius"]
        rf = R - rk
        pieces = []
        if d > rk:
            pieces.append(_line((R, 0.0), (R, -(d - rk)), dx))
        pieces.append(_arc(rf, -(d - rk), rk, 0.0, -math.pi / 2, dx))
        if rf > 0:
            pieces.append(_line((rf, -d), (0.0, -d), dx))
        return _chain(*pieces)
    if s["shape"] == "hemisphere":
        return _arc(0.0, 0.0, s["radius"], 0.0, -math.pi / 2, dx)
    if s["shape"] == "revolution":
        P = [tuple(p) for p in s["profile"]]
        return _chain(*(_line(a, b, dx) for a, b in zip(P[:-1], P[1:])))
    if s["shape"] == "sphere":
        R, zc = s["radius"], s["origin"][2]
        if zc <= -R:  # fully submerged: top to bottom
            return _arc(0.0, zc, R, math.pi / 2, -math.pi / 2, dx)
        a0 = math.asin(-zc / R)  # angle of the water line seen from the centre
        prof = _arc(0.0, zc, R, a0, -math.pi / 2, dx)
        prof[0, 1] = 0.0  # exactly on the still-water line (not 1e-17 above it)
        return prof
    raise ValueError(f"meridian: shape {s['shape']!r} is not a body of revolution.")


def n_azimuth(spec, dx):
    """Number of panels around the axis: the water-line (or widest) circle in panels of <= dx,
    a multiple of 4 (so halves and quarters are whole) and at least 12."""
    rmax = float(np.max(meridian(spec, dx)[:, 0]))
    n = max(12, math.ceil(2 * math.pi * rmax / dx))
    return 4 * math.ceil(n / 4)


def _revolve(profile, n, k0, k1, name=None):
    """Mesh of the surface swept by ``profile`` (r, z) over sectors k0..k1-1 of 2π/n each."""
    import capytaine as cpt

    r, z = profile[:, 0], profile[:, 1]
    th = 2 * np.pi * np.arange(k0, k1 + 1) / n
    m = len(profile)
    # vertices[k, i] = meridian k, profile point i
    verts = np.stack([r[None, :] * np.cos(th)[:, None], r[None, :] * np.sin(th)[:, None],
                      np.broadcast_to(z, (len(th), m))], axis=-1).reshape(-1, 3)
    faces = []
    for k in range(k1 - k0):
        for i in range(m - 1):
            a, b = k * m + i, k * m + i + 1
            c, d = (k + 1) * m + i + 1, (k + 1) * m + i
            faces.append([a, b, c, d])  # outward for a profile ordered top -> keel
    # A plain list of faces (not an array): capytaine would read a leading 3/4 column as counts.
    # Its cleaning merges the coincident vertices on the axis and turns those quads into triangles.
    return cpt.Mesh(vertices=verts, faces=faces, name=name)


_PART_SECTORS = {"full": lambda n: (0, n), "half": lambda n: (0, n // 2), "wedge": lambda n: (0, 1)}


def body_meshes(spec, dx, part="full", *, lid=True):
    """Hull and lid meshes of one body (global coordinates).

    ``part``: "full" (the whole hull), "half" (the part y >= 0, for a body of revolution whose
    axis is at y = 0) or "wedge" (one sector of 2π/n about the body's own axis, for a body of
    revolution on the z axis). Returns ``(hull, lid, n)``: capytaine ``Mesh`` objects (``lid`` is
    None when fully submerged or ``lid`` is False) and n the number of sectors (None for "mesh").
    """
    import capytaine as cpt

    dx = spec.get("dx", dx)
    x0, y0, z0 = spec["origin"]
    if spec["shape"] == "mesh":
        if part not in ("full", "half"):
            raise ValueError(f"body {spec['name']!r}: a 'mesh' body gives part='full' or 'half' "
                             f"(when its hull is symmetric about y = 0), got part={part!r}.")
        hull = mesh_hull(spec)
        lid_mesh = mesh_lid(spec, hull, dx) if lid else None
        if part == "half":
            if not mesh_symmetric(spec):
                raise ValueError(f"body {spec['name']!r}: part='half' needs a hull symmetric about "
                                 f"y = 0; the mesh {spec['file']!r} at origin {spec['origin']} "
                                 f"is not.")
            # clipped() keeps the side opposite the normal: y >= 0
            hull = hull.clipped(origin=(0.0, 0.0, 0.0), normal=(0.0, -1.0, 0.0),
                                name=spec["name"])
            if lid_mesh is not None:
                lid_mesh = lid_mesh.clipped(origin=(0.0, 0.0, 0.0), normal=(0.0, -1.0, 0.0),
                                            name=f"{spec['name']}_lid")
                lid_mesh = lid_mesh if lid_mesh.nb_faces else None
        return hull, lid_mesh, None
    if part not in _PART_SECTORS:
        raise ValueError(f"part = {part!r} is not one of {list(_PART_SECTORS)}.")
    if part == "half" and y0 != 0.0:
        raise ValueError(f"body {spec['name']!r}: part='half' needs the axis on y = 0, got "
                         f"origin y = {y0}.")
    if part == "wedge" and (x0, y0) != (0.0, 0.0):
        raise ValueError(f"body {spec['name']!r}: part='wedge' needs the axis on x = y = 0, got "
                         f"origin {spec['origin']}.")
    prof = meridian(spec, dx)
    n = n_azimuth(spec, dx)
    k0, k1 = _PART_SECTORS[part](n)
    shift = (x0, y0, 0.0)
    hull = _revolve(prof, n, k0, k1, name=spec["name"]).translated(shift, name=spec["name"])
    lid_mesh = None
    if lid and prof[0, 1] == 0.0 and prof[0, 0] > 0.0:
        lid_prof = _line((prof[0, 0], 0.0), (0.0, 0.0), dx)
        lid_mesh = _revolve(lid_prof, n, k0, k1).translated(shift, name=f"{spec['name']}_lid")
    return hull, lid_mesh, n


def mirror_partner(a, b, tol=1e-12):
    """True when body spec ``b`` is body ``a`` mirrored about the plane y = 0 (same shape and
    sizes, origin (x, -y, z)); reference points may differ (they do not enter the mesh)."""
    if a["shape"] not in REVOLVED or b["shape"] != a["shape"]:
        return False
    keys = set(a) - {"name", "origin", "reference_point"}
    if keys != set(b) - {"name", "origin", "reference_point"}:
        return False
    if any(a[k] != b[k] for k in keys):
        return False
    (xa, ya, za), (xb, yb, zb) = a["origin"], b["origin"]
    return abs(xa - xb) <= tol and abs(ya + yb) <= tol and abs(za - zb) <= tol


# ------------------------------------------------------------------------------------------------
# Hydrostatics of a hull mesh (exact for the polyhedron)


def _triangles(mesh):
    """Vertices of the mesh faces split into triangles: array (n_tri, 3, 3)."""
    mesh = mesh.merged()
    v = np.asarray(mesh.vertices, float)
    f = np.asarray(mesh.faces)  # (n, 4); a triangle repeats its last vertex
    return np.concatenate([v[f[:, [0, 1, 2]]], v[f[:, [0, 2, 3]]]], axis=0)


def hull_hydrostatics(hull, reference_point, *, rho=1000.0, g=9.81):
    """Displaced volume, centre of buoyancy and hydrostatic stiffnesses of one wetted hull.

    ``hull``: capytaine mesh of the wetted surface (outward normals), cut at z = 0 and open there.
    The integrals are exact for the polyhedron closed by its water-plane polygon:

    - V = Σ_T (a·(b×c))/6 over the hull triangles T = (a, b, c) (tetrahedra from the origin, which
      lies in the plane z = 0 of the water-plane polygon, so that polygon adds nothing);
      centre of buoyancy x_B = Σ_T V_T (a+b+c)/4 / V.
    - water-plane integrals ∫_wp f dA = −Σ_T A_T,z · mean of f at T's edge midpoints, with
      A_T,z = ((b−a)×(c−a))_z / 2 the signed projected area (the midpoint rule is exact for the
      quadratic f used here).

    Returns a dict: ``volume`` (m³), ``center_of_buoyancy`` (3,) m, ``waterplane_area`` (m²),
    ``waterplane_stiffness`` (6, 6) and ``hydrostatic_stiffness`` (6, 6), both about the reference
    point (x_r, y_r, z_r), dofs (surge, sway, heave, roll, pitch, yaw):

    - waterplane: C33 = ρgA, C34 = C43 = ρg∫(y−y_r), C35 = C53 = −ρg∫(x−x_r),
      C44 = ρg∫(y−y_r)², C55 = ρg∫(x−x_r)², C45 = C54 = −ρg∫(x−x_r)(y−y_r); all else 0.
    - hydrostatic (buoyancy only, no weight): waterplane + ρgV(z_B − z_r) on C44 and C55,
      C46 = −ρgV(x_B − x_r), C56 = −ρgV(y_B − y_r) (capytaine's rigid-body formula with mass 0).
    """
    T = _triangles(hull)
    a, b, c = T[:, 0], T[:, 1], T[:, 2]
    vt = np.einsum("ij,ij->i", a, np.cross(b, c)) / 6.0
    V = float(vt.sum())
    if V <= 0:
        raise ValueError(f"hull {getattr(hull, 'name', '')!r}: displaced volume {V} <= 0; the "
                         f"mesh must be the wetted surface with outward normals.")
    xB = (vt[:, None] * (a + b + c) / 4.0).sum(axis=0) / V
    az = np.cross(b - a, c - a)[:, 2] / 2.0
    xr, yr, zr = (float(p) for p in reference_point)
    mids = np.stack([(a + b) / 2, (b + c) / 2, (c + a) / 2], axis=1)  # (n, 3, 3)
    X, Y = mids[..., 0] - xr, mids[..., 1] - yr

    def wp(f):
        return float(-(az * f.mean(axis=1)).sum())

    A = wp(np.ones_like(X))
    Sx, Sy = wp(X), wp(Y)
    Ixx, Iyy, Ixy = wp(Y**2), wp(X**2), wp(X * Y)
    rg = rho * g
    W = np.zeros((6, 6))
    W[2, 2] = rg * A
    W[2, 3] = W[3, 2] = rg * Sy
    W[2, 4] = W[4, 2] = -rg * Sx
    W[3, 3] = rg * Ixx
    W[4, 4] = rg * Iyy
    W[3, 4] = W[4, 3] = -rg * Ixy
    H = W.copy()
    H[3, 3] += rg * V * (xB[2] - zr)
    H[4, 4] += rg * V * (xB[2] - zr)
    H[3, 5] = -rg * V * (xB[0] - xr)
    H[4, 5] = -rg * V * (xB[1] - yr)
    return {"volume": V, "center_of_buoyancy": xB, "waterplane_area": A,
            "waterplane_stiffness": W, "hydrostatic_stiffness": H}



# ------------------------------------------------------------------------------------------------
# Mesh files: placing, checking, lids and symmetry (issue 51)

MESH_TOL = 1e-6          # relative to a length of the mesh: coincident points, the water plane
_MESH_CACHE: dict = {}   # (file, size, mtime, origin) -> the checked hull (meshes are immutable)


def _length_scale(mesh):
    v = np.asarray(mesh.vertices, float)
    return float(np.linalg.norm(v.max(axis=0) - v.min(axis=0))) if len(v) else 1.0


def _face_array(mesh):
    """Faces as an (n, 4) int array; a triangle repeats its last vertex (capytaine's layout)."""
    return np.asarray(mesh.faces, dtype=np.int64).reshape(-1, 4)


def mesh_edges(mesh):
    """The edges of a panel mesh: ``(edges, count, same_direction)``.

    ``edges`` (n_e, 2) vertex indices (sorted pair), ``count`` the number of panels that use each
    edge and ``same_direction`` whether two panels run along it the same way. A closed surface
    with consistently ordered panels has count 2 and opposite directions on every edge (each
    panel's boundary, ordered for its outward normal, runs along a shared edge the other way than
    its neighbour's); count 1 is a hole's rim, count > 2 a non-manifold edge.
    """
    F = _face_array(mesh)
    a = F.reshape(-1)
    b = np.roll(F, -1, axis=1).reshape(-1)
    keep = a != b                        # a triangle's repeated last vertex: no edge
    a, b = a[keep], b[keep]
    pairs = np.stack([np.minimum(a, b), np.maximum(a, b)], axis=1)
    forward = a < b
    edges, inv, count = np.unique(pairs, axis=0, return_inverse=True, return_counts=True)
    inv = inv.reshape(-1)
    n_fwd = np.bincount(inv, weights=forward, minlength=len(edges))
    same = (count == 2) & (n_fwd != 1)
    return edges, count, same


def _fmt(p):
    return "(" + ", ".join(f"{float(c):.4g}" for c in p) + ")"


def _edges_text(V, edges, origin, k=4):
    o = np.asarray(origin, float)
    items = [f"{_fmt(V[i] - o)}–{_fmt(V[j] - o)}" for i, j in edges[:k]]
    more = f" and {len(edges) - k} more" if len(edges) > k else ""
    return "; ".join(items) + more


def signed_volume(mesh):
    """Σ_T a·(b×c)/6 over the panels split into triangles: the enclosed volume of a closed
    surface, positive when the panels are ordered for outward normals, negative when inward."""
    V = np.asarray(mesh.vertices, float)
    F = _face_array(mesh)
    T = np.concatenate([V[F[:, [0, 1, 2]]], V[F[:, [0, 2, 3]]]], axis=0)
    return float(np.einsum("ij,ij->i", T[:, 0], np.cross(T[:, 1], T[:, 2])).sum() / 6.0)


def check_closed(mesh, *, what, origin=(0.0, 0.0, 0.0), waterline=None):
    """Refuse a panel mesh that is not a closed, consistently ordered, outward-facing surface.

    A hull's hydrostatics (V, centre of buoyancy, hull_hydrostatics) are surface integrals that
    equal the volume's only for a closed surface: an open end cap loses the volume of the cone it
    subtends and moves the centre of buoyancy (issue 51: 369 → 347 m³, the centre 0.19 m off, a
    4.4° heel at rest), with no error from capytaine. ``waterline`` (a z): a rim at that height is
    allowed (the wetted hull is open at the still-water plane, which closes it), any other rim is
    a hole. Non-manifold edges (3+ panels) and panels ordered against their neighbours are refused
    too; a surface ordered inward (negative enclosed volume) is refused with the fix. ``what``
    starts each message; edges are named by their end points less ``origin`` (the file's frame).
    Raises ValueError; returns None.
    """
    V = np.asarray(mesh.vertices, float)
    edges, count, same = mesh_edges(mesh)
    tol = MESH_TOL * _length_scale(mesh)
    rim = edges[count == 1]
    if waterline is not None and len(rim):
        at_wl = np.all(np.abs(V[rim][:, :, 2] - waterline) <= tol, axis=1)
        rim = rim[~at_wl]
    if len(rim):
        raise ValueError(
            f"{what} is open: {len(rim)} edge(s) belong to one panel only"
            f"{' below the water line' if waterline is not None else ''} (file frame, m): "
            f"{_edges_text(V, rim, origin)}. A hull must be a closed surface (end caps and bottom "
            f"included) for its displaced volume, centre of buoyancy and stiffness to be right; "
            f"close the holes (e.g. trimesh: m.fill_holes(), then check m.is_watertight) and "
            f"give the file again.")
    multi = edges[count > 2]
    if len(multi):
        raise ValueError(
            f"{what} has {len(multi)} edge(s) shared by more than two panels (file frame, m): "
            f"{_edges_text(V, multi, origin)}: duplicated or crossing panels; a hull is one closed "
            f"surface. Remove the extra panels and give the file again.")
    flipped = edges[same]
    if len(flipped):
        raise ValueError(
            f"{what} has panels ordered against their neighbours along {len(flipped)} edge(s) "
            f"(file frame, m): {_edges_text(V, flipped, origin)}: some normals point in, some "
            f"out. Make the ordering consistent (e.g. trimesh: trimesh.repair.fix_normals(m)) "
            f"and give the file again.")
    vol = signed_volume(mesh)
    if vol < 0:
        raise ValueError(
            f"{what} faces inward: its panels enclose {vol:.6g} m³ (negative: normals into the "
            f"body; capytaine needs them out into the water). Reverse the vertex order of every "
            f"panel (e.g. trimesh: m.invert()) and give the file again.")


def check_collocation(meshes, *, what, origin=(0.0, 0.0, 0.0), tol=MESH_TOL, max_named=4):
    """Refuse panels whose collocation point lies on another panel.

    capytaine evaluates the potential at each panel's centre (its collocation point). When that
    point lies on another panel's edge, the Rankine part of the influence of that panel (a
    log-singular line integral along its edges) is NaN: capytaine then fails every frequency
    ("Green function returned a NaN in the interaction matrix. It could be due to overlapping
    panels") after the whole run's set-up, and ends with a hint about kh and threads. A centre
    inside another panel (duplicated or crossing panels) is refused too: the two panels are the
    same surface twice. Checked before any solve, over the hull and lid panels together (a lid
    panel's centre on a hull panel is as bad); candidates from a k-d tree of the panel centres,
    within each panel's circumscribed radius, so the cost is O(N log N).
    Raises ValueError naming the panels (centres in the file's frame, less ``origin``).
    """
    from scipy.spatial import cKDTree

    meshes = [m for m in meshes if m is not None and m.nb_faces]
    if not meshes:
        return
    verts, faces, off = [], [], 0
    for m in meshes:
        verts.append(np.asarray(m.vertices, float))
        faces.append(_face_array(m) + off)
        off += len(verts[-1])
    V = np.concatenate(verts)
    F = np.concatenate(faces)
    P = V[F]                                               # (n, 4, 3)
    C = np.concatenate([np.asarray(m.faces_centers, float) for m in meshes])
    R = np.linalg.norm(P - C[:, None, :], axis=2).max(axis=1)
    eps = tol * max(float(R.max()), 1e-300)
    tree = cKDTree(C)
    near = tree.query_ball_point(C, R + eps)
    jj = np.concatenate([np.full(len(lst), j) for j, lst in enumerate(near)]).astype(np.int64)
    ii = np.concatenate([np.asarray(lst, dtype=np.int64) for lst in near])
    keep = ii != jj
    ii, jj = ii[keep], jj[keep]
    if ii.size == 0:
        return
    c = C[ii]                                              # (m, 3) collocation points
    A = P[jj]                                              # (m, 4, 3) the other panel
    B = np.roll(A, -1, axis=1)
    e = B - A
    L2 = np.einsum("mkd,mkd->mk", e, e)
    s = np.clip(np.einsum("mkd,mkd->mk", c[:, None] - A, e) / np.where(L2 > 0, L2, 1.0), 0, 1)
    d_edge = np.linalg.norm(c[:, None] - (A + s[..., None] * e), axis=2)
    d_edge = np.where(L2 > 0, d_edge, np.linalg.norm(c[:, None] - A, axis=2)).min(axis=1)
    # inside: on the panel's plane and inside one of its two triangles (0, 1, 2), (0, 2, 3)
    inside = np.zeros(len(ii), dtype=bool)
    for t in ((0, 1, 2), (0, 2, 3)):
        a, b, cc = A[:, t[0]], A[:, t[1]], A[:, t[2]]
        n = np.cross(b - a, cc - a)
        nn = np.linalg.norm(n, axis=1)
        ok = nn > 0
        h = np.abs(np.einsum("md,md->m", c - a, n)) / np.where(ok, nn, 1.0)
        w0 = np.einsum("md,md->m", np.cross(b - a, c - a), n)
        w1 = np.einsum("md,md->m", np.cross(cc - b, c - b), n)
        w2 = np.einsum("md,md->m", np.cross(a - cc, c - cc), n)
        inside |= ok & (h <= tol * R[jj]) & (w0 >= 0) & (w1 >= 0) & (w2 >= 0)
    on_edge = d_edge <= tol * R[jj]
    bad = np.flatnonzero(on_edge | inside)
    if bad.size == 0:
        return
    o = np.asarray(origin, float)
    items = []
    for k in bad[:max_named]:
        where = "on an edge of" if on_edge[k] else "inside"
        items.append(f"panel {int(ii[k])} (centre {_fmt(C[ii[k]] - o)}) lies {where} panel "
                     f"{int(jj[k])} (corners {', '.join(_fmt(p - o) for p in P[jj[k]][:3 if F[jj[k], 2] == F[jj[k], 3] else 4])})")
    more = f"; and {bad.size - max_named} more" if bad.size > max_named else ""
    raise ValueError(
        f"{what}: {bad.size} panel collocation point(s) lie on another panel, which capytaine "
        f"cannot solve (NaN influence, every frequency fails after the set-up): "
        + "; ".join(items) + more + " (file frame, m; panels numbered in the hull as placed and "
        "cut at z = 0, then the lid). Remove duplicated or crossing panels (a fin or plate "
        "touching the hull through a panel's centre, a T-junction) and give the file again.")


def _remove_waterline_deck(hull, tol):
    """Drop the panels lying in the still-water plane z = 0 (a hull file closed by a deck at its
    water line): capytaine would solve them as body surface on the free surface, their projected
    area cancels the bottom's in the water-plane integrals (C33 = 0) and they hide the interior
    from generate_lid (0 lid panels). The wetted hull is open at z = 0 by convention."""
    F = _face_array(hull)
    z = np.asarray(hull.vertices, float)[F][:, :, 2]
    deck = np.all(np.abs(z) <= tol, axis=1)
    if not deck.any():
        return hull
    return hull.extract_faces(np.flatnonzero(~deck).tolist())


def mesh_hull(spec):
    """The wetted hull of a ``shape: "mesh"`` body: the file's mesh translated by ``origin``, cut
    at z = 0, any deck panels in the plane z = 0 removed, and checked: closed below the water line
    with consistent outward normals (:func:`check_closed`, on the file's mesh as given and on the
    cut hull) and no collocation point on another panel (:func:`check_collocation`). Raises
    ValueError naming the body, the file and the edges or panels. Cached per file content stamp
    and origin (capytaine meshes are immutable)."""
    import capytaine as cpt

    f = spec["file"]
    key = _mesh_key(spec)
    if key in _MESH_CACHE:
        return _MESH_CACHE[key]
    what = f"body {spec['name']!r}: 'file' = {f!r}"
    raw = cpt.load_mesh(f)
    raw = raw.merged() if hasattr(raw, "merged") else raw
    if raw.nb_faces == 0:
        raise ValueError(f"{what}: the file holds no panels; give a mesh of the hull.")
    # a closed file (the whole body) is checked as a whole; a file of the wetted surface only
    # (open at its own water line, as WAMIT .gdf files are) is checked once placed and cut
    edges, count, _ = mesh_edges(raw)
    whole = not np.any(count == 1)
    if whole:
        check_closed(raw, what=f"{what}: the mesh")
    placed = raw.translated(tuple(spec["origin"]))
    hull = placed.immersed_part()
    hull = hull.merged() if hasattr(hull, "merged") else hull
    if hull.nb_faces == 0:
        raise ValueError(f"{what}: no panel lies below z = 0 with 'origin' = {spec['origin']} "
                         f"(the mesh spans z = {placed.vertices[:, 2].min():.4g} to "
                         f"{placed.vertices[:, 2].max():.4g} m once placed); set origin's z so "
                         f"that the hull is immersed to its draft.")
    tol = MESH_TOL * _length_scale(placed)
    hull = _remove_waterline_deck(hull, tol)
    check_closed(hull, what=f"{what}: the hull as placed (origin {spec['origin']}) and cut at "
                 f"z = 0", origin=spec["origin"], waterline=0.0)
    check_collocation([hull], what=f"{what}: the hull as placed", origin=spec["origin"])
    _MESH_CACHE[key] = hull
    return hull


def mesh_lid(spec, hull, dx):
    """The water-plane lid of a mesh hull (capytaine's ``generate_lid`` at z = 0, panels of
    radius ≤ dx/2), or None for a hull that does not pierce the surface. A piercing hull for
    which no lid panel is found is an error naming ``lid`` (a lid is asked for, none is given:
    the irregular frequencies it removes stay in the results), not a silent 0 lid panels."""
    dx = spec.get("dx", dx)
    edges, count, _ = mesh_edges(hull)
    if not np.any(count == 1):
        return None                                   # fully submerged: no water plane
    lid = hull.generate_lid(z=0.0, faces_max_radius=dx / 2, name=f"{spec['name']}_lid")
    if lid.nb_faces == 0:
        raise ValueError(f"body {spec['name']!r}: 'lid': the hull of {spec['file']!r} pierces "
                         f"the water plane but capytaine's generate_lid found no lid panel inside "
                         f"its water line (dx {dx:g} m): give a smaller dx for this body, or set "
                         f"lid = false (irregular frequencies then stay in the results).")
    check_collocation([hull, lid], what=f"body {spec['name']!r}: 'file' = {spec['file']!r}: "
                      f"the hull and its lid", origin=spec["origin"])
    return lid


def mesh_is_xoz_symmetric(hull, placed=None, tol=MESH_TOL, rtol=1e-6):
    """Whether a hull (as placed and cut at z = 0) is its own mirror image about y = 0, so that
    the BEM needs only the half y ≥ 0 (capytaine's ReflectionSymmetricMesh: about half the cost
    per frequency, CAPYTAINE.md).

    Two tests. (1) The corners: every vertex of ``placed`` (the whole mesh as placed, before the
    cut; the cut's own vertices fall on whichever diagonal a panel has, so they are not mirrored
    in most STL files) has a partner (x, −y, z) within ``tol`` of the mesh's size. (2) The
    surface between them: the half y ≥ 0 and its mirror image give the hull's own volume, centre
    of buoyancy and water-plane stiffness (hull_hydrostatics, exact for the panels) within
    ``rtol`` (relative to V, the size, and the largest stiffness term). A triangulation whose
    diagonals are not mirrored passes for flat panels (the same surface); on curved ones it
    differs by the panels' chordal error, which (2) measures.
    """
    from scipy.spatial import cKDTree
    import capytaine as cpt

    L = _length_scale(hull)
    if placed is not None:
        v = np.asarray(placed.vertices, float)
        d, _ = cKDTree(v).query(v * np.array([1.0, -1.0, 1.0]))
        if not np.all(d <= tol * L):
            return False
    half = hull.clipped(origin=(0.0, 0.0, 0.0), normal=(0.0, -1.0, 0.0))
    if half.nb_faces == 0:
        return False
    whole = cpt.Mesh.join_meshes(half, half.mirrored("xOz"))
    try:
        a = hull_hydrostatics(hull, (0.0, 0.0, 0.0))
        b = hull_hydrostatics(whole, (0.0, 0.0, 0.0))
    except ValueError:
        return False
    W = np.abs(a["waterplane_stiffness"]).max()
    return bool(abs(a["volume"] - b["volume"]) <= rtol * abs(a["volume"])
                and np.all(np.abs(a["center_of_buoyancy"] - b["center_of_buoyancy"]) <= rtol * L)
                and np.all(np.abs(a["waterplane_stiffness"] - b["waterplane_stiffness"])
                           <= rtol * W))


def mesh_symmetric(spec):
    """:func:`mesh_is_xoz_symmetric` of a mesh body as placed (cached with its hull)."""
    hull = mesh_hull(spec)
    key = ("sym",) + _mesh_key(spec)
    if key not in _MESH_CACHE:
        import capytaine as cpt

        raw = cpt.load_mesh(spec["file"])
        raw = raw.merged() if hasattr(raw, "merged") else raw
        _MESH_CACHE[key] = mesh_is_xoz_symmetric(hull, raw.translated(tuple(spec["origin"])))
    return _MESH_CACHE[key]


def _mesh_key(spec):
    st = os.stat(spec["file"])
    return (spec["file"], st.st_size, st.st_mtime_ns, tuple(spec["origin"]))
