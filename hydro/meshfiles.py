"""Hull mesh files read without capytaine (pure numpy), for the nonlinear level's closed hulls.

capytaine reads these formats to make a database; the nonlinear level (:mod:`hydro.wetted`) needs
only the panels, so a run that uses a mesh hull does not need the BEM's dependencies. Every reader
returns triangles (n, 3, 3) in m, in the file's axes, each ordered for the outward normal
(counter-clockwise seen from the water, as all three formats store their panels); quadrilaterals
are split along their first diagonal (v0 v1 v2, v0 v2 v3), a triangle stored as a quadrilateral
(a repeated vertex) gives one triangle.

- WAMIT ``.gdf`` (low-order geometry): a title line, ``ULEN GRAV``, ``ISX ISY``, ``NPAN``, then
  4 × NPAN vertices (x, y, z), free format. ULEN is WAMIT's length scale for non-dimensional
  output and GRAV its gravity: the coordinates are dimensional and neither changes them.
  ISX = 1: x = 0 is a plane of symmetry and the file holds the half x ≥ 0 (ISY = 1: y = 0, the
  half y ≥ 0); the omitted half is the mirror image, its panels' order reversed so their normals
  stay outward (both flags: the quarter, mirrored three times). The same reading as capytaine's
  (``capytaine.meshes.io._read_gdf``: ISX the yOz plane, ISY the xOz plane).
- NEMOH ``.dat`` mesh (also ``.nemoh``, ``.mar``): a first line ``2 ISYM``, node lines
  ``id x y z`` up to one whose id is 0, panel lines of four 1-based node numbers up to a line of
  zeros. Node numbers count the node lines in order (as capytaine reads them). ISYM = 1: y = 0 is a
  plane of symmetry, the file holds one half and the other is mirrored.
- STL, ASCII (``solid … facet normal … outer loop vertex x y z …``) or binary (an 80-byte header,
  a uint32 count, 50 bytes per triangle). The facets' stored normals are ignored: the vertex order
  is the orientation (the STL convention, counter-clockwise seen from outside), which is what
  :func:`edge_report` checks.

:func:`edge_report` and :func:`extrude_waterline` work on triangles: the edges that are open
(one triangle), non-manifold (three or more) or run the same way in two triangles (normals
flipped), and the closing of a wetted-surface-only mesh by its side continued vertically to a
deck.
"""
from __future__ import annotations

import math
import os
import struct
from pathlib import Path

import numpy as np

# formats by suffix: what :func:`read_mesh` reads
FORMATS = {".gdf": "wamit", ".dat": "nemoh", ".nemoh": "nemoh", ".mar": "nemoh", ".stl": "stl"}


def _mirror(T: np.ndarray, axis: int) -> np.ndarray:
    """The mirror image of triangles (n, 3, 3) about the plane x_axis = 0, vertex order reversed
    (a reflection turns the orientation: reversed, the normals stay outward)."""
    M = T.copy()
    M[:, :, axis] *= -1.0
    return M[:, ::-1]


def _quads_to_triangles(P: np.ndarray) -> np.ndarray:
    """Panels (n, 4, 3) → triangles (v0 v1 v2), (v0 v2 v3), those of zero area dropped (a
    triangle stored as a quadrilateral repeats a vertex: one of its halves is a segment)."""
    T = np.concatenate([P[:, [0, 1, 2]], P[:, [0, 2, 3]]], axis=0)
    # keep the order panel by panel (first halves, then seconds would scatter neighbours)
    n = len(P)
    order = np.stack([np.arange(n), n + np.arange(n)], axis=1).reshape(-1)
    T = T[order]
    area = np.linalg.norm(np.cross(T[:, 1] - T[:, 0], T[:, 2] - T[:, 0]), axis=1)
    scale = float(np.ptp(P.reshape(-1, 3), axis=0).max()) if n else 1.0
    return np.ascontiguousarray(T[area > 1e-14 * max(scale, 1e-300) ** 2])


def _numbers(text: str, path, what: str) -> np.ndarray:
    try:
        return np.array(text.replace("D", "E").replace("d", "e").split(), dtype=float)
    except ValueError:
        raise ValueError(f"{path}: {what} are not all numbers") from None


def read_gdf(path) -> np.ndarray:
    """Triangles (n, 3, 3) of a WAMIT ``.gdf`` file, its symmetric halves mirrored (module
    docstring)."""
    path = Path(path)
    lines = path.read_text(encoding="utf-8", errors="replace").splitlines()
    if len(lines) < 4:
        raise ValueError(f"{path}: {len(lines)} line(s); a WAMIT .gdf file has a title, "
                         "'ULEN GRAV', 'ISX ISY', 'NPAN', then 4 vertices per panel")
    try:
        float(lines[1].split()[0]), float(lines[1].split()[1])
        isx, isy = (int(v) for v in lines[2].split()[:2])
        npan = int(lines[3].split()[0])
    except (IndexError, ValueError):
        raise ValueError(f"{path}: lines 2-4 are not 'ULEN GRAV', 'ISX ISY', 'NPAN' (WAMIT .gdf "
                         "header)") from None
    if isx not in (0, 1) or isy not in (0, 1):
        raise ValueError(f"{path}: ISX, ISY = {isx}, {isy}; accepted 0 or 1 (1: x = 0, y = 0 a "
                         "plane of symmetry)")
    if npan <= 0:
        raise ValueError(f"{path}: NPAN = {npan}; give the number of panels (> 0)")
    x = _numbers("\n".join(lines[4:]), path, "the vertices")
    if len(x) < 12 * npan:
        raise ValueError(f"{path}: NPAN = {npan} panels need {12 * npan} coordinates; the file "
                         f"has {len(x)}")
    T = _quads_to_triangles(x[:12 * npan].reshape(npan, 4, 3))
    if isx:
        T = np.concatenate([T, _mirror(T, 0)])
    if isy:
        T = np.concatenate([T, _mirror(T, 1)])
    return T


def read_nemoh(path) -> np.ndarray:
    """Triangles (n, 3, 3) of a NEMOH mesh file (``.dat``), its symmetric half mirrored (module
    docstring)."""
    path = Path(path)
    lines = [ln.split() for ln in path.read_text(encoding="utf-8", errors="replace").splitlines()]
    lines = [ln for ln in lines if ln]
    try:
        isym = int(lines[0][1])
    except (IndexError, ValueError):
        raise ValueError(f"{path}: the first line is not '2 ISYM' (NEMOH mesh header)") from None
    if isym not in (0, 1):
        raise ValueError(f"{path}: ISYM = {isym}; accepted 0 or 1 (1: y = 0 a plane of symmetry)")
    nodes, i = [], 1
    try:
        while int(lines[i][0]) != 0:
            nodes.append([float(v) for v in lines[i][1:4]])
            i += 1
        i += 1
        panels = []
        while int(lines[i][0]) != 0:
            panels.append([int(v) for v in lines[i][:4]])
            i += 1
    except IndexError:
        raise ValueError(f"{path}: the node or panel list does not end with a line of zeros "
                         "(NEMOH mesh: nodes 'id x y z' up to '0 0. 0. 0.', panels of four node "
                         "numbers up to '0 0 0 0')") from None
    except ValueError:
        raise ValueError(f"{path}: line {i + 1} is not a node 'id x y z' or a panel of four node "
                         "numbers") from None
    V = np.asarray(nodes, float).reshape(-1, 3)
    F = np.asarray(panels, dtype=np.int64).reshape(-1, 4) - 1
    if not len(F):
        raise ValueError(f"{path}: no panels")
    if F.min() < 0 or F.max() >= len(V):
        raise ValueError(f"{path}: panels name nodes {F.min() + 1} to {F.max() + 1}; the file "
                         f"has {len(V)} nodes (numbered from 1)")
    T = _quads_to_triangles(V[F])
    return np.concatenate([T, _mirror(T, 1)]) if isym else T


def read_stl(path) -> np.ndarray:
    """Triangles (n, 3, 3) of an STL file, ASCII or binary (module docstring)."""
    path = Path(path)
    data = path.read_bytes()
    if len(data) >= 84:
        (n,) = struct.unpack("<I", data[80:84])
        if len(data) == 84 + 50 * n:
            rec = np.frombuffer(data, dtype=np.dtype([("n", "<f4", 3), ("v", "<f4", (3, 3)),
                                                      ("attr", "<u2")]), count=n, offset=84)
            return np.ascontiguousarray(rec["v"].astype(float))
    text = data.decode("ascii", errors="replace")
    if not text.lstrip().lower().startswith("solid"):
        raise ValueError(f"{path}: neither binary STL (84 + 50 × count bytes: the file has "
                         f"{len(data)}) nor ASCII STL (starting 'solid')")
    rows = [ln.split()[1:4] for ln in text.splitlines() if ln.strip().lower().startswith("vertex")]
    try:
        V = np.asarray(rows, dtype=float)
    except ValueError:
        raise ValueError(f"{path}: a 'vertex' line without three numbers") from None
    if len(V) % 3 or not len(V):
        raise ValueError(f"{path}: {len(V)} vertex lines; ASCII STL gives 3 per facet")
    return V.reshape(-1, 3, 3)


def read_mesh(path) -> np.ndarray:
    """Triangles (n, 3, 3) of a mesh file by its suffix: ``.gdf`` (WAMIT), ``.dat`` / ``.nemoh``
    / ``.mar`` (NEMOH), ``.stl`` (ASCII or binary). Raises ValueError naming the file and what is
    wrong; FileNotFoundError for a missing file."""
    path = Path(path)
    fmt = FORMATS.get(path.suffix.lower())
    if fmt is None:
        raise ValueError(f"{path}: suffix {path.suffix!r} is not a mesh format read here; "
                         f"accepted: {sorted(FORMATS)} (WAMIT .gdf, NEMOH .dat, STL); convert "
                         "other formats (e.g. meshio, trimesh) to STL")
    if not path.is_file():
        raise FileNotFoundError(f"mesh file {os.fspath(path)!r} not found")
    T = {"wamit": read_gdf, "nemoh": read_nemoh, "stl": read_stl}[fmt](path)
    if not np.all(np.isfinite(T)):
        raise ValueError(f"{path}: non-finite coordinates")
    if not len(T):
        raise ValueError(f"{path}: no panels of non-zero area")
    return T


# ------------------------------------------------------------------------------ the edges
def weld(T: np.ndarray, rtol: float = 1e-9):
    """Vertices shared by triangles: (points (V, 3), index (n, 3)), coordinates equal within
    ``rtol`` of the mesh's size taken as one point (files repeat each vertex per panel)."""
    T = np.asarray(T, float)
    P = T.reshape(-1, 3)
    scale = max(float(np.ptp(P, axis=0).max()), 1e-300)
    key = np.round(P / (rtol * scale)).astype(np.int64)
    _, first, idx = np.unique(key, axis=0, return_index=True, return_inverse=True)
    return P[first], idx.reshape(-1, 3)


def edge_report(T: np.ndarray) -> dict:
    """The edges of triangles (n, 3, 3) that keep them from being one closed, consistently
    ordered surface: ``open`` (used by one triangle: a hole's or a cut's rim), ``non_manifold``
    (three or more), ``flipped`` (two triangles run along it the same way: one's normal turned),
    each an (m, 2, 3) array of the edges' end points, with ``points``/``index`` (:func:`weld`) and
    the directed boundary edges ``rim`` (m, 2) as point indices, in the direction their triangle
    runs."""
    P, idx = weld(T)
    a, b = idx.reshape(-1), np.roll(idx, -1, axis=1).reshape(-1)
    lo, hi = np.minimum(a, b), np.maximum(a, b)
    pairs = np.stack([lo, hi], axis=1)
    edges, inv, count = np.unique(pairs, axis=0, return_inverse=True, return_counts=True)
    inv = inv.reshape(-1)
    forward = np.bincount(inv, weights=(a < b), minlength=len(edges))
    flipped = (count == 2) & (forward != 1)
    rim = np.stack([a, b], axis=1)[count[inv] == 1]
    return {"points": P, "index": idx, "open": P[edges[count == 1]],
            "non_manifold": P[edges[count > 2]], "flipped": P[edges[flipped]], "rim": rim}


def edges_text(E: np.ndarray, k: int = 3) -> str:
    """The first ``k`` edges (m, 2, 3) as '(x, y, z)–(x, y, z)' in m, and how many more."""
    f = lambda p: "(" + ", ".join(f"{float(c):.4g}" for c in p) + ")"  # noqa: E731
    items = [f"{f(e[0])}–{f(e[1])}" for e in E[:k]]
    return "; ".join(items) + (f" and {len(E) - k} more" if len(E) > k else "")


def closed_volume(T) -> float:
    """Σ a·(b×c)/6 over the triangles: the volume a closed surface encloses (> 0 for outward
    normals)."""
    T = np.asarray(T, float)
    return float(np.einsum("ij,ij->i", T[:, 0], np.cross(T[:, 1], T[:, 2])).sum() / 6.0)


def volume_and_centroid(T) -> tuple[float, np.ndarray]:
    """(V, centroid (3,)) of the solid a closed outward surface encloses: the signed tetrahedra
    (0, a, b, c), V = Σ a·(b×c)/6, centroid Σ V_t (a + b + c)/4 / V. Exact for the polyhedron."""
    T = np.asarray(T, float)
    v = np.einsum("ij,ij->i", T[:, 0], np.cross(T[:, 1], T[:, 2])) / 6.0
    V = float(v.sum())
    return V, (v[:, None] * T.sum(axis=1)).sum(axis=0) / (4.0 * V)


# ------------------------------------------------------------------- closing a wetted surface
def _loops(rim: np.ndarray) -> list[list[int]]:
    """The rim's directed edges (m, 2) as closed loops of point indices; ValueError where a point
    starts or ends other than one rim edge (the rim is not a set of simple loops)."""
    nxt = {}
    for a, b in rim:
        if a in nxt:
            raise ValueError("two open edges leave one vertex")
        nxt[int(a)] = int(b)
    if sorted(nxt) != sorted(nxt.values()):
        raise ValueError("the open edges do not close into loops")
    loops, seen = [], set()
    for s in nxt:
        if s in seen:
            continue
        loop, p = [], s
        while p not in seen:
            seen.add(p)
            loop.append(p)
            p = nxt[p]
        loops.append(loop)
    return loops


def _ear_clip(xy: np.ndarray) -> list[tuple[int, int, int]]:
    """Triangles (index triples, counter-clockwise) of a simple polygon ``xy`` (m, 2) given
    counter-clockwise: ear clipping, O(m²)."""
    idx = list(range(len(xy)))
    out = []

    def cross(o, p, q):
        return (p[0] - o[0]) * (q[1] - o[1]) - (p[1] - o[1]) * (q[0] - o[0])

    scale = float(np.ptp(xy, axis=0).max()) ** 2
    guard = 0
    while len(idx) > 3 and guard < 10 * len(xy) ** 2:
        guard += 1
        m = len(idx)
        for j in range(m):
            i0, i1, i2 = idx[j - 1], idx[j], idx[(j + 1) % m]
            a, b, c = xy[i0], xy[i1], xy[i2]
            if cross(a, b, c) <= 1e-14 * scale:
                continue            # a reflex or straight corner: not an ear
            inside = False
            for k in idx:
                if k in (i0, i1, i2):
                    continue
                p = xy[k]
                if cross(a, b, p) >= 0 and cross(b, c, p) >= 0 and cross(c, a, p) >= 0:
                    inside = True
                    break
            if not inside:
                out.append((i0, i1, i2))
                del idx[j]
                break
        else:
            raise ValueError("the water line is not a simple polygon (no ear found)")
    if len(idx) == 3:
        out.append(tuple(idx))
    return out


def extrude_waterline(T: np.ndarray, freeboard: float, *, tol: float = 1e-6) -> np.ndarray:
    """Close a mesh of the wetted surface only (open at its water line z = 0, as BEM meshes are)
    by its side continued vertically up to a deck at z = ``freeboard`` (m): on every open edge a
    wall of quadrilaterals (split in two) in rows about as tall as the rim's mean edge, and each
    loop's deck by ear clipping. The hull above the water is then a vertical-sided prism on the
    water plane: the water-plane area and its moments at rest are the mesh's own, so the
    stiffness at rest is the wetted mesh's; above the water line it is an assumption (stated in
    the docs). ValueError naming what is wrong: an open edge off z = 0 (within ``tol`` of the
    mesh's size), a rim that is not a set of simple loops."""
    T = np.asarray(T, float)
    rep = edge_report(T)
    P, rim = rep["points"], rep["rim"]
    if not len(rim):
        raise ValueError("the mesh is closed: nothing to extrude")
    size = float(np.ptp(P, axis=0).max())
    off = np.abs(P[rim][:, :, 2]).max(axis=1) > tol * size
    if np.any(off):
        raise ValueError(f"{int(off.sum())} open edge(s) lie off the water line z = 0 (e.g. "
                         f"{edges_text(P[rim[off]], 2)}): a hole, not the wetted surface's rim")
    if not (isinstance(freeboard, (int, float)) and math.isfinite(freeboard) and freeboard > 0):
        raise ValueError(f"freeboard: {freeboard!r}; give a positive height in m")
    loops = _loops(rim)
    edge_len = float(np.mean(np.linalg.norm(P[rim[:, 1]] - P[rim[:, 0]], axis=1)))
    rows = max(1, math.ceil(freeboard / edge_len))
    levels = np.linspace(0.0, freeboard, rows + 1)
    new = []
    for loop in loops:
        ring = P[loop]                     # the rim's own points (within tol of z = 0)
        m = len(ring)
        for r in range(rows):
            lo, hi = ring.copy(), ring.copy()
            if r:
                lo[:, 2] = levels[r]
            hi[:, 2] = levels[r + 1]
            for i in range(m):
                j = (i + 1) % m
                # the rim runs a → b in its wet triangle: the wall above runs b → a there
                a0, b0, a1, b1 = lo[i], lo[j], hi[i], hi[j]
                new += [[b0, a0, a1], [b0, a1, b1]]
        # the deck: the top ring in reversed order (its edges b' → a', opposite the wall's)
        top = ring[::-1].copy()
        top[:, 2] = freeboard
        xy = top[:, :2]
        area2 = float(np.sum(xy[:, 0] * np.roll(xy[:, 1], -1) - np.roll(xy[:, 0], -1) * xy[:, 1]))
        if area2 <= 0:
            raise ValueError("a water-line loop runs clockwise seen from above: the wetted "
                             "surface's normals point inward")
        for i, j, k in _ear_clip(xy):
            new.append([top[i], top[j], top[k]])
    return np.concatenate([T, np.asarray(new, float)])
