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
        if part != "full":
            raise ValueError(f"body {spec['name']!r}: a 'mesh' body only gives part='full', got "
                             f"part={part!r}.")
        hull = cpt.load_mesh(spec["file"]).translated((x0, y0, z0)).immersed_part()
        hull = hull.merged() if hasattr(hull, "merged") else hull
        lid_mesh = hull.generate_lid(z=0.0, faces_max_radius=dx / 2) if lid else None
        if lid_mesh is not None and lid_mesh.nb_faces == 0:
            lid_mesh = None
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

