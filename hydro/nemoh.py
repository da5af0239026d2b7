"""Reader of NEMOH results (v2 and v3 ``Results/`` folders beside their ``Nemoh.cal``) into the
internal hydro database, and of the NEMOH-format hydrostatics files (``KH.dat``,
``Hydrostatics.dat``) that NEMOH's mesher and capytaine's ``export_hydrostatics`` write.

Files read (NEMOH user manuals v2/v3; checked on the WEC-Sim BEMIO examples, tests/data/bemio):

``Nemoh.cal``
    rho (kg/m³), g (m/s²), water depth (m; 0 = infinite), the bodies (mesh file, dofs, forces),
    the frequencies (v2: ``n, min, max`` in rad/s; v3: ``type, n, min, max``, type 1/2/3 =
    rad/s, Hz, s) and headings (``n, min, max`` in degrees); v3 also the unit of the first column
    of the result files ("output freq type", 1/2/3 = rad/s, Hz, s).
``Results/RadiationCoefficients.tec``
    one zone per radiating dof ("Motion of body b in DoF k", I = n_ω rows); each row the
    frequency then (A, B) for every influenced dof of all bodies. Dimensional (NEMOH multiplies
    by rho): A in kg, kg m, kg m²; B in kg/s, kg m/s, kg m²/s.
``Results/ExcitationForce.tec``, ``FKForce.tec``, ``DiffractionForce.tec``
    one zone per heading ("… beta = 0.000 deg"); each row the frequency then (|X|, arg X in
    radians) per dof: N (N m) per metre of wave amplitude.
``Mesh/KH[_b].dat``, ``Mesh/Hydrostatics[_b].dat`` (b = 0, 1, … per body of a multi-body run;
``KH.dat`` alone for one body; any letter case; v3 also ``Mechanics/Kh.dat``)
    the 6×6 hydrostatic stiffness, the centre of buoyancy (XF, YF, ZF), the point (XG, YG, ZG) the
    mesher was given as centre of gravity, the displacement V (m³).

Phase convention. NEMOH, like capytaine, uses time dependence e^{−iωt}: F(t) = Re[X e^{−iωt}] for
the wave whose elevation at the origin is Re[a e^{−iωt}], so X = |X| e^{i arg X} is already the
internal convention (no conjugation). Checked on RM3 against the WAMIT reader (which conjugates):
the surge force of a long wave has arg X = −π/2 in NEMOH's file, as after conjugation of WAMIT's
+π/2, and the heave phases of float and spar agree to a few degrees over the band
(tests/test_bem_formats.py; a conjugation error there flips their sign and fails the test).

Hydrostatics. NEMOH's mesher (v2 ``Mesh``, v3 ``hydrosCal``) writes KH about the point G it was
given (Mesh.cal), with the displaced mass m = rho V:

    KH33 = rho g A_wp, KH34 = rho g ∫(y − y_G) dA, KH35 = −rho g ∫(x − x_G) dA,
    KH44 = rho g ∫(y − y_G)² dA + rho g V (z_B − z_G),  KH55 = rho g ∫(x − x_G)² dA + rho g V (z_B − z_G)

(checked: RM3 float KH44 = 7.197e7 = rho g (7762 − 725.8 · 0.573), as WAMIT's .hst; v3 Cylinder
KH44 = −632.7 = rho g (∫y² dA + V z_B) with z_G = 0). ``hydrostatic_stiffness`` keeps KH as given
(block diagonal; attrs say so); ``waterplane_stiffness`` removes rho g V (z_B − z_G) from 44, 55,
moves the water-plane moments from (x_G, y_G) to the body's reference point where they differ, and
keeps only the entries 33, 34, 35, 44, 55, 45 — the treatment :mod:`hydro.wamit` gives WAMIT's
.hst (there too the gravity term is m g z_G with m = rho V).

Each body's own hydrostatics. Where a body's mesh file (as Nemoh.cal names it, e.g.
``mesh/float.dat``) is in the run folder, its displaced volume and centre of buoyancy are computed
from it (:func:`mesh_hydrostatics`) and compared with its Hydrostatics file: within 1 % the files
are used as above; otherwise the files belong to another mesh and the mesh's hydrostatics (V, B,
the water-plane stiffness, KH about G) are used, with a warning naming both. NEMOH v3.0.2's
hydrosCal writes the hydrostatics of all bodies together into every ``hydrostatics_<b>.dat``
(WEC-Sim's RM3 example: 1,612.5 m³ and z_B = −9.163 m for float and spar alike; their meshes give
725.8 and 886.7 m³, z_B −1.293 and −15.60 m, as NEMOH v2.3 and WAMIT). Without the meshes, files
that give every body the same volume and centre of buoyancy are refused, naming them and the fix.

Infinite-frequency added mass. NEMOH gives none (an IRF.tec from v3 with the IRF flag set holds
one, but most runs have none): ``added_mass_inf`` is estimated from A(ω) and B(ω) by Ogilvie's
relation (:func:`hydro.radiation.estimate_added_mass_inf`; attrs["added_mass_inf_source"]).

Reference point of each body: the point of its rotation dofs in Nemoh.cal. Water depth 0 in
Nemoh.cal means infinite depth (inf here).
"""
from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import xarray as xr

from .database import AXES, CONVENTION, dof_labels

_NUM = r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[EeDd][-+]?\d+)?"
_FREQ_UNITS = {1: "rad/s", 2: "Hz", 3: "s"}


class NemohFormatError(ValueError):
    """A NEMOH file cannot be read: the message names the file, the line, the value and what
    is accepted."""


def _numbers(text):
    """The leading numbers of a Nemoh.cal line (before its '!' comment)."""
    out = []
    for tok in text.split("!")[0].split():
        try:
            out.append(float(tok.replace("D", "E").replace("d", "e")))
        except ValueError:
            break
    return out


# ---------------------------------------------------------------------------------- Nemoh.cal
def parse_nemoh_cal(path) -> dict:
    """The settings of a ``Nemoh.cal`` (v2 or v3) as a dict: rho, g, water_depth (inf for 0),
    bodies (list of dicts: mesh, name, dofs [(type, direction (3,), point (3,))], forces),
    n_omega, omega_range (as written), freq_type (1/2/3 = rad/s, Hz, s), n_beta, beta_deg
    (the headings, degrees), output_freq_type, version (2 or 3)."""
    path = Path(path)
    raw = path.read_text(errors="replace").splitlines()
    lines = [(n, ln) for n, ln in enumerate(raw, 1) if ln.strip() and not ln.lstrip().startswith("---")]
    pos = 0

    def take(what, count=None, at_least=None):
        nonlocal pos
        if pos >= len(lines):
            raise NemohFormatError(f"{path}: ends before {what} (the file is truncated: a complete "
                                   "Nemoh.cal has the environment, the bodies, the load cases and "
                                   "the post-processing sections)")
        n, ln = lines[pos]
        pos += 1
        vals = _numbers(ln)
        if (count is not None and len(vals) < count) or (at_least is not None and len(vals) < at_least):
            need = count if count is not None else at_least
            raise NemohFormatError(f"{path}, line {n}: {ln.strip()!r} should start with {need} "
                                   f"number(s) ({what}); got {len(vals)}")
        return n, ln, vals

    n, _, vals = take("RHO (kg/m^3)", 1)
    rho = vals[0]
    out = {"rho": rho}
    nl, _, vals = take("G (m/s^2)", 1)
    out["g"] = vals[0]
    nd, _, vals = take("DEPTH (m)", 1)
    depth = vals[0]
    take("XEFF YEFF (m)", 2)
    for name, value, line, ok, accepted in (
            ("RHO", rho, n, np.isfinite(rho) and rho > 0, "a finite density > 0 kg/m^3 (sea water 1025)"),
            ("G", out["g"], nl, np.isfinite(out["g"]) and out["g"] > 0, "a finite gravity > 0 m/s^2"),
            ("DEPTH", depth, nd, np.isfinite(depth) and depth >= 0, "a depth >= 0 m (0 = infinite)")):
        if not ok:
            raise NemohFormatError(f"{path}, line {line}: {name} = {value!r}; accepted: {accepted}")
    out["water_depth"] = float("inf") if depth == 0 else float(depth)

    _, _, vals = take("number of bodies", 1)
    nb = int(vals[0])
    if nb < 1:
        raise NemohFormatError(f"{path}: number of bodies = {nb}; accepted: >= 1")
    bodies = []
    for b in range(nb):
        if pos >= len(lines):
            raise NemohFormatError(f"{path}: ends inside body {b + 1} of {nb} (truncated)")
        _, mesh_line = lines[pos]
        pos += 1
        mesh = mesh_line.split("!")[0].strip()
        take(f"body {b + 1}: number of points and panels", 2)
        _, _, vals = take(f"body {b + 1}: number of dofs", 1)
        dofs = []
        for _ in range(int(vals[0])):
            ln_no, ln, v = take(f"body {b + 1}: a dof (type, direction, point)", 7)
            dofs.append((int(v[0]), np.array(v[1:4]), np.array(v[4:7]), ln_no))
        _, _, vals = take(f"body {b + 1}: number of forces", 1)
        forces = []
        for _ in range(int(vals[0])):
            ln_no, ln, v = take(f"body {b + 1}: a force (type, direction, point)", 7)
            forces.append((int(v[0]), np.array(v[1:4]), np.array(v[4:7]), ln_no))
        _, _, vals = take(f"body {b + 1}: number of lines of additional information", 1)
        for _ in range(int(vals[0])):
            take(f"body {b + 1}: additional information", 0)
        stem = re.split(r"[\\/]", mesh)[-1]
        bodies.append({"mesh": mesh, "name": stem.rsplit(".", 1)[0] if "." in stem else stem,
                       "dofs": dofs, "forces": forces})
    out["bodies"] = bodies

    ln_no, ln, vals = take("load cases: number of wave frequencies, min, max", 3)
    if len(vals) >= 4:                                    # v3: type, n, min, max
        out["version"], out["freq_type"] = 3, int(vals[0])
        out["n_omega"], out["omega_range"] = int(vals[1]), (vals[2], vals[3])
    else:
        out["version"], out["freq_type"] = 2, 1
        out["n_omega"], out["omega_range"] = int(vals[0]), (vals[1], vals[2])
    if out["freq_type"] not in _FREQ_UNITS:
        raise NemohFormatError(f"{path}, line {ln_no}: frequency type {out['freq_type']}; accepted: "
                               "1 (rad/s), 2 (Hz), 3 (s)")
    if out["n_omega"] < 1:
        raise NemohFormatError(f"{path}, line {ln_no}: {out['n_omega']} wave frequencies; accepted: >= 1")
    _, _, vals = take("load cases: number of wave directions, min, max (deg)", 3)
    nbeta = int(vals[0])
    out["n_beta"] = nbeta
    out["beta_deg"] = np.linspace(vals[1], vals[2], nbeta) if nbeta > 1 else np.array([vals[1]])
    # post processing: IRF, pressure, Kochin, free surface, then (v3) RAO and output freq type
    out["output_freq_type"] = 1
    if out["version"] == 3 and pos + 5 < len(lines) + 1:
        rest = [(_numbers(ln), ln_no) for ln_no, ln in lines[pos:pos + 6]]
        if len(rest) >= 6 and rest[5][0]:
            out["output_freq_type"] = int(rest[5][0][0])
            if out["output_freq_type"] not in _FREQ_UNITS:
                raise NemohFormatError(f"{path}, line {rest[5][1]}: output freq type "
                                       f"{out['output_freq_type']}; accepted: 1 (rad/s), 2 (Hz), 3 (s)")
    return out


def _rigid_point(path, body, items, kind):
    """The rotation point of a body's 6 rigid dofs (or forces) in Nemoh.cal; raise unless they
    are surge, sway, heave, roll, pitch, yaw in that order, the rotations about one point."""
    expected = [(1, e) for e in np.eye(3)] + [(2, e) for e in np.eye(3)]
    got = [(t, d) for t, d, _, _ in items]
    ok = len(items) == 6 and all(t == te and np.allclose(d, de) for (t, d), (te, de) in zip(got, expected))
    pts = [p for t, _, p, _ in items if t == 2]
    if ok and not all(np.allclose(p, pts[0]) for p in pts):
        ok = False
    if not ok:
        desc = "; ".join(f"line {ln}: type {t} dir {d.tolist()} point {p.tolist()}" for t, d, p, ln in items)
        raise NemohFormatError(
            f"{path}: body {body['name']!r} has {len(items)} {kind} ({desc}); accepted: the 6 rigid-"
            "body modes in the order surge, sway, heave (type 1, directions x, y, z), roll, pitch, "
            "yaw (type 2, directions x, y, z, about one point). Generalised modes are not supported.")
    return np.asarray(pts[0], dtype=float)


# ----------------------------------------------------------------------------------- .tec files
def read_tec(path, n_values: int, n_zones: int, n_rows: int) -> tuple[list[str], np.ndarray]:
    """The zones of a NEMOH Tecplot result file: (zone titles, array (n_zones, n_rows, 1 +
    n_values)). Every zone must declare ``I = n_rows`` and hold exactly that many rows of
    1 + n_values finite numbers: a file cut short (even at a line end, where it still parses),
    a zone too many or too few, a damaged number, NaN or inf are errors naming the file, the line
    and what was expected."""
    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(f"NEMOH result file {str(path)!r} not found")
    titles, zones, current = [], [], None
    with open(path, errors="replace") as f:
        for n, line in enumerate(f, 1):
            s = line.strip()
            if not s or s.startswith('"') or s.upper().startswith("VARIABLES"):
                continue
            if s.lower().startswith("zone"):
                m = re.search(r't\s*=\s*"([^"]*)"', s, re.IGNORECASE)
                mi = re.search(r"\bI\s*=\s*(\d+)", s)
                if mi is None:
                    raise NemohFormatError(f"{path}, line {n}: zone header {s!r} has no 'I=<rows>'")
                if int(mi.group(1)) != n_rows:
                    raise NemohFormatError(f"{path}, line {n}: zone {s!r} declares I = {mi.group(1)} "
                                           f"rows; Nemoh.cal asks for {n_rows} frequencies")
                titles.append(m.group(1) if m else "")
                current = []
                zones.append((current, n))
                continue
            if current is None:
                continue
            try:
                vals = [float(p.replace("D", "E")) for p in s.split()]
            except ValueError:
                raise NemohFormatError(f"{path}, line {n}: {s[:80]!r} is not a row of numbers "
                                       f"(expected {1 + n_values}); the file is damaged") from None
            if len(vals) != 1 + n_values:
                raise NemohFormatError(f"{path}, line {n}: {len(vals)} numbers; expected {1 + n_values} "
                                       f"(frequency + {n_values} values for the dofs of Nemoh.cal): "
                                       "the file is truncated or damaged, or belongs to another run")
            if not np.all(np.isfinite(vals)):
                raise NemohFormatError(f"{path}, line {n}: non-finite value (NaN or inf) in {s[:80]!r}")
            if len(current) >= n_rows:
                raise NemohFormatError(f"{path}, line {n}: more than the I = {n_rows} rows its zone declares")
            current.append(vals)
    if len(zones) != n_zones:
        raise NemohFormatError(f"{path}: {len(zones)} zones; expected {n_zones} (from Nemoh.cal): the "
                               "file is truncated or belongs to another run")
    for rows, n in zones:
        if len(rows) != n_rows:
            raise NemohFormatError(f"{path}: the zone starting at line {n} has {len(rows)} rows; it "
                                   f"declares I = {n_rows}: the file is truncated")
    return titles, np.array([rows for rows, _ in zones], dtype=float)


def _omega_column(path, col, freq_type):
    """ω (rad/s) from the first column of a result file (unit per Nemoh.cal) and the order that
    sorts it ascending; raise unless the column is strictly monotonic and > 0."""
    col = np.asarray(col, dtype=float)
    d = np.diff(col)
    if np.any(col <= 0) or not (np.all(d > 0) or np.all(d < 0)):
        k = int(np.argmax(col <= 0)) if np.any(col <= 0) else int(np.argmax((d <= 0) if d[0] > 0 else (d >= 0))) + 1
        raise NemohFormatError(
            f"{path}: the frequency column ({_FREQ_UNITS[freq_type]}) must be > 0 and strictly "
            f"monotonic; row {k + 1} has {col[k]!r} after {col[k - 1] if k else None!r}: the file is "
            "damaged or edited (NEMOH writes its frequencies in order)")
    om = {1: col, 2: 2.0 * np.pi * col, 3: 2.0 * np.pi / col}[freq_type]
    return om, np.argsort(om)


# ------------------------------------------------------------------------------ hydrostatics
def _find(dirs, names):
    """The first existing file among `dirs` × `names`, matching names case-insensitively."""
    for d in dirs:
        if not d.is_dir():
            continue
        listing = {p.name.lower(): p for p in d.iterdir() if p.is_file()}
        for nm in names:
            if nm.lower() in listing:
                return listing[nm.lower()]
    return None


def hydrostatics_files(folder, body: int, n_bodies: int, extra_dirs=()):
    """(KH file, Hydrostatics file) of body `body` (0-based) in a NEMOH run `folder` (its Mesh/,
    mesh/, Mechanics/ or itself, any letter case) or in `extra_dirs`: ``KH_<b>.dat`` /
    ``Hydrostatics_<b>.dat``, and for a single body also ``KH.dat`` / ``Hydrostatics.dat``.
    Either may be None."""
    folder = Path(folder)
    dirs = [*map(Path, extra_dirs), folder / "Mesh", folder / "mesh", folder, folder / "Mechanics"]
    kh_names = [f"KH_{body}.dat"] + (["KH.dat"] if n_bodies == 1 else [])
    hs_names = [f"Hydrostatics_{body}.dat"] + (["Hydrostatics.dat"] if n_bodies == 1 else [])
    return _find(dirs, kh_names), _find(dirs, hs_names)


def read_kh(path) -> np.ndarray:
    """The 6×6 matrix of a NEMOH ``KH.dat`` (6 rows of 6 numbers)."""
    path = Path(path)
    rows = [ln.split() for ln in path.read_text(errors="replace").splitlines() if ln.strip()]
    try:
        M = np.array([[float(x.replace("D", "E")) for x in r] for r in rows], dtype=float)
    except ValueError:
        raise NemohFormatError(f"{path}: not a matrix of numbers (a KH.dat holds 6 rows of 6 numbers)") from None
    if M.shape != (6, 6):
        raise NemohFormatError(f"{path}: a {M.shape} table; a KH.dat holds 6 rows of 6 numbers "
                               "(truncated or another file?)")
    if not np.all(np.isfinite(M)):
        raise NemohFormatError(f"{path}: non-finite value (NaN or inf) in the stiffness")
    return M


def read_hydrostatics(path) -> dict:
    """A NEMOH ``Hydrostatics.dat``: {"cob": (3,), "cog": (3,), "volume": m³, optional
    "waterplane_area", "mass"}. The first three lines hold (XF, XG), (YF, YG), (ZF, ZG) in that
    order, read by position (capytaine 2.x's export labels all three "XF … XG")."""
    path = Path(path)
    lines = [ln for ln in path.read_text(errors="replace").splitlines() if ln.strip()]
    if len(lines) < 4:
        raise NemohFormatError(f"{path}: {len(lines)} lines; a Hydrostatics.dat has at least 4 (XF/XG, "
                               "YF/YG, ZF/ZG, Displacement): truncated?")
    F, G = [], []
    for k in range(3):
        nums = re.findall(rf"=\s*({_NUM})", lines[k])
        if len(nums) != 2:
            raise NemohFormatError(f"{path}, line {k + 1}: {lines[k].strip()!r}; expected 'XF = <number> "
                                   "- XG = <number>' (centre of buoyancy, centre of gravity)")
        F.append(float(nums[0]))
        G.append(float(nums[1]))
    out = {"cob": np.array(F), "cog": np.array(G)}
    for key, label in (("volume", "Displacement"), ("waterplane_area", "Waterplane area"), ("mass", "Mass")):
        m = re.search(rf"{label}\s*=\s*({_NUM})", "\n".join(lines), re.IGNORECASE)
        if m:
            out[key] = float(m.group(1).replace("D", "E"))
    if "volume" not in out or not (np.isfinite(out["volume"]) and out["volume"] > 0):
        raise NemohFormatError(f"{path}: no positive 'Displacement = <m^3>' line (got "
                               f"{out.get('volume')!r}); accepted: the displaced volume > 0")
    return out


def waterplane_part(C, volume, cob, point, ref, rho, g, *, mass=None, cog=None):
    """The water-plane stiffness about `ref` (6×6) from a body's hydrostatic stiffness `C` about
    `point` P, whose 44/55 hold rho g V (z_B − z_P) − m g (z_G − z_P) besides the water-plane terms
    (NEMOH's mesher: P = G, m = rho V, so the weight term is 0; capytaine: P = the rotation centre,
    m and G its mass and centre of mass — give `mass` and `cog` then).

    Removed: rho g V (z_B − z_P) − m g (z_G − z_P) from 44 and 55. The water-plane terms are then
    moved from (x_P, y_P) to (x_r, y_r) = ref[:2], with A = C33/(rho g), S_y = C34/(rho g),
    S_x = −C35/(rho g): ∫(y − y_r)² dA = ∫(y − y_P)² dA + 2 d_y S_y + d_y² A with d_y = y_P − y_r
    (likewise x), ∫(x − x_r)(y − y_r) dA = ∫(x − x_P)(y − y_P) dA + d_x S_y + d_y S_x + d_x d_y A.
    Only 33, 34, 35, 44, 55, 45 (and their symmetric entries) are kept."""
    rg = rho * g
    grav = 0.0 if mass is None or cog is None else mass * g * (cog[2] - point[2])
    extra = rg * volume * (cob[2] - point[2]) - grav
    A, Sy, Sx = C[2, 2] / rg, _sym(C, 2, 3) / rg, -_sym(C, 2, 4) / rg
    Iyy = (C[3, 3] - extra) / rg                             # ∫(y − y_P)² dA
    Ixx = (C[4, 4] - extra) / rg                             # ∫(x − x_P)² dA
    Ixy = -_sym(C, 3, 4) / rg                                # ∫(x − x_P)(y − y_P) dA
    dx, dy = point[0] - ref[0], point[1] - ref[1]
    W = np.zeros((6, 6))
    vals = {(2, 2): A, (2, 3): Sy + dy * A, (2, 4): -(Sx + dx * A),
            (3, 3): Iyy + 2 * dy * Sy + dy * dy * A,
            (4, 4): Ixx + 2 * dx * Sx + dx * dx * A,
            (3, 4): -(Ixy + dx * Sy + dy * Sx + dx * dy * A)}
    for (i, j), v in vals.items():
        W[i, j] = W[j, i] = rg * v
    return W


def _sym(C, i, j):
    return C[i, j] if C[i, j] != 0.0 else C[j, i]


# ------------------------------------------------------------------------- body meshes (.dat)
def read_mesh(path):
    """A NEMOH mesh file (``.dat``, the format Nemoh.cal names: a line ``2 Isym``, the nodes
    ``id x y z`` up to a line of zeros, the panels ``n1 n2 n3 n4`` (1-based; a triangle repeats a
    node) up to a line of zeros): (nodes (n, 3), panels (m, 4) 0-based, xOz symmetric). With
    Isym = 1 only the half y >= 0 is stored; :func:`mesh_hydrostatics` mirrors it."""
    path = Path(path)
    lines = [ln.split() for ln in path.read_text(errors="replace").splitlines() if ln.strip()]
    try:
        head = [int(float(x)) for x in lines[0][:2]]
        sym = len(head) > 1 and head[1] == 1
        k, nodes, ids = 1, [], []
        while int(float(lines[k][0])) != 0:
            ids.append(int(float(lines[k][0])))
            nodes.append([float(x.replace("D", "E")) for x in lines[k][1:4]])
            k += 1
        k += 1
        panels = []
        while k < len(lines) and any(int(float(x)) != 0 for x in lines[k][:4]):
            panels.append([int(float(x)) for x in lines[k][:4]])
            k += 1
    except (IndexError, ValueError):
        raise NemohFormatError(f"{path}: not a NEMOH mesh (a line '2 Isym', nodes 'id x y z' up to "
                               "a line '0 0. 0. 0.', panels 'n1 n2 n3 n4' up to '0 0 0 0'): "
                               "truncated or another format") from None
    V = np.array(nodes, dtype=float).reshape(-1, 3)
    P = np.array(panels, dtype=int).reshape(-1, 4)
    pos = {i: n for n, i in enumerate(ids)}
    try:
        P = np.vectorize(pos.__getitem__)(P) if P.size else P
    except KeyError as e:
        raise NemohFormatError(f"{path}: a panel names node {e.args[0]}, which is not in the node "
                               "list (truncated or damaged mesh)") from None
    if len(V) < 3 or len(P) < 1 or not np.all(np.isfinite(V)):
        raise NemohFormatError(f"{path}: {len(V)} nodes and {len(P)} panels (or a non-finite "
                               "coordinate); a NEMOH mesh holds a hull's panels")
    return V, P, sym


def mesh_hydrostatics(path, ref, rho, g, *, cog=None):
    """Displaced volume, centre of buoyancy and water-plane stiffness of one body from its own
    NEMOH mesh file (the wetted surface, z <= 0, open at the water plane; mirrored about xOz where
    the file says Isym = 1). Exact for the polyhedron closed by its water-plane polygon
    (the formulas of :func:`hydro.geometry.hull_hydrostatics`): V = Σ a·(b×c)/6 over the panels'
    triangles, x_B = Σ V_T (a+b+c)/4 / V, ∫_wp f dA = −Σ A_T,z · mean of f at the edge midpoints.
    The panel order (normals in or out) is taken from the sign of V.

    Returns {"volume", "cob" (3,), "waterplane_area", "waterplane_stiffness" (6, 6) about `ref`
    (33, 34, 35, 44, 55, 45), "hydrostatic_stiffness" (6, 6): about `cog` (default `ref`) as
    NEMOH's mesher writes KH: the water-plane terms about (x_G, y_G) and rho g V (z_B − z_G) on
    44/55 (mass rho V at G)}."""
    V, P, sym = read_mesh(path)
    T = np.concatenate([V[P[:, [0, 1, 2]]], V[P[:, [0, 2, 3]]]], axis=0)
    if sym:
        M = T[:, [0, 2, 1]] * np.array([1.0, -1.0, 1.0])          # mirrored, order reversed
        T = np.concatenate([T, M], axis=0)
    if np.max(T[..., 2]) > 1e-6 * max(np.ptp(T[..., 2]), 1.0):
        raise NemohFormatError(f"{path}: nodes above the water plane (z up to {np.max(T[..., 2]):.4g} "
                               "m); a NEMOH body mesh is the wetted surface, z <= 0")
    a, b, c = T[:, 0], T[:, 1], T[:, 2]
    vt = np.einsum("ij,ij->i", a, np.cross(b, c)) / 6.0
    sign = 1.0 if vt.sum() >= 0 else -1.0
    vt = sign * vt
    vol = float(vt.sum())
    if not vol > 0:
        raise NemohFormatError(f"{path}: the mesh encloses no volume ({vol!r} m³)")
    cob = (vt[:, None] * (a + b + c) / 4.0).sum(axis=0) / vol
    az = sign * np.cross(b - a, c - a)[:, 2] / 2.0
    mids = np.stack([(a + b) / 2, (b + c) / 2, (c + a) / 2], axis=1)
    rg = rho * g

    def water_plane(point):
        X, Y = mids[..., 0] - point[0], mids[..., 1] - point[1]

        def wp(f):
            return float(-(az * f.mean(axis=1)).sum())
        A, Sx, Sy = wp(np.ones_like(X)), wp(X), wp(Y)
        W = np.zeros((6, 6))
        W[2, 2] = rg * A
        W[2, 3] = W[3, 2] = rg * Sy
        W[2, 4] = W[4, 2] = -rg * Sx
        W[3, 3] = rg * wp(Y ** 2)
        W[4, 4] = rg * wp(X ** 2)
        W[3, 4] = W[4, 3] = -rg * wp(X * Y)
        return W, A

    W, area = water_plane(np.asarray(ref, dtype=float))
    G = np.asarray(ref if cog is None else cog, dtype=float)
    K, _ = water_plane(G)
    K[3, 3] += rg * vol * (cob[2] - G[2])
    K[4, 4] += rg * vol * (cob[2] - G[2])
    return {"volume": vol, "cob": cob, "waterplane_area": area, "waterplane_stiffness": W,
            "hydrostatic_stiffness": K}


def body_mesh_file(root, mesh):
    """The file of a body's mesh as Nemoh.cal names it (``mesh/float.dat``: either slash, any
    letter case of each part, relative to the run folder), or None."""
    parts = [q for q in re.split(r"[\\/]", mesh.strip()) if q and q != "."]
    here = Path(root)
    for part in parts:
        if not here.is_dir():
            return None
        found = next((q for q in here.iterdir() if q.name.lower() == part.lower()), None)
        if found is None:
            return None
        here = found
    return here if here.is_file() else None


_HS_RTOL = 0.01          # a hydrostatics file agrees with its body's mesh: V and z_B within 1 %


# ------------------------------------------------------------------------------------ reader
def find_nemoh_cal(path) -> Path:
    """The ``Nemoh.cal`` of a NEMOH run given as the file itself, its folder or its Results/."""
    p = Path(path)
    if p.is_file() and p.name.lower() == "nemoh.cal":
        return p
    for d in (p, p.parent):
        if d.is_dir():
            f = _find([d], ["Nemoh.cal"])
            if f is not None:
                return f
    raise FileNotFoundError(f"{str(path)!r}: no Nemoh.cal there or in its parent; give a NEMOH run "
                            "folder (with Nemoh.cal and Results/) or its Nemoh.cal")


def read_nemoh(path, body_names=None, *, rho=None, g=None, estimate_inf: bool = True) -> xr.Dataset:
    """Read a NEMOH v2/v3 run (its folder, its ``Nemoh.cal`` or its ``Results/``) into the
    internal database (module docstring: units, phase convention, hydrostatics, A∞).

    body_names: one name per body (default: the mesh file names of Nemoh.cal, e.g. "float",
    "spar"). rho, g: if given, must equal those of Nemoh.cal (the coefficients are dimensional:
    they cannot be rescaled here). Hydrostatics are required (``waterplane_stiffness``,
    ``displaced_volume`` and ``center_of_buoyancy`` are in the schema): a body without its KH and
    Hydrostatics file is an error naming the places looked in.
    """
    from .radiation import estimate_added_mass_inf

    cal = find_nemoh_cal(path)
    root = cal.parent
    info = parse_nemoh_cal(cal)
    for name, given, have in (("rho", rho, info["rho"]), ("g", g, info["g"])):
        if given is not None and not np.isclose(float(given), have, rtol=1e-6):
            raise ValueError(f"{name}={given} differs from the {name} = {have} of {cal}: NEMOH's "
                             f"coefficients are dimensional, computed with {name} = {have}; drop the "
                             f"{name} option or set it to {have}")
    bodies = info["bodies"]
    nb = len(bodies)
    names = [b["name"] for b in bodies]
    if body_names is not None:
        names = [body_names] if isinstance(body_names, str) else list(body_names)
        if len(names) != nb:
            raise ValueError(f"body names {names} ({len(names)}) do not match the {nb} bodies of {cal} "
                             f"(meshes {[b['mesh'] for b in bodies]})")
    elif len(set(names)) != nb:
        names = [f"body{k}" for k in range(nb)]
    ref = np.array([_rigid_point(cal, b, b["dofs"], "dofs") for b in bodies])
    fref = np.array([_rigid_point(cal, b, b["forces"], "forces") for b in bodies])
    if not np.allclose(ref, fref):
        raise NemohFormatError(f"{cal}: the moments are taken about {fref.tolist()} but the rotations "
                               f"are about {ref.tolist()}; accepted: the same point per body")
    n = 6 * nb
    labels = dof_labels(names)
    res = next((d for d in root.iterdir() if d.is_dir() and d.name.lower() == "results"), None)
    if res is None:
        raise FileNotFoundError(f"{root}: no Results/ folder beside {cal.name}; run NEMOH's solver "
                                "(and postprocessor) first")

    def result(name):
        f = _find([res], [name])
        if f is None:
            raise FileNotFoundError(f"{res}: no {name} (NEMOH's postprocessor writes it)")
        return f

    nw, ft = info["n_omega"], info["output_freq_type"]
    f_rad = result("RadiationCoefficients.tec")
    titles, R = read_tec(f_rad, 2 * n, n, nw)
    om, order = _omega_column(f_rad, R[0, :, 0], ft)
    for z in range(1, n):
        if not np.allclose(R[z, :, 0], R[0, :, 0], rtol=1e-6):
            raise NemohFormatError(f"{f_rad}: zone {z + 1} ({titles[z]!r}) has other frequencies than zone 1")
    # zone j = radiating dof j; columns 1 + 2i, 2 + 2i = A_ij, B_ij (force i)
    A = np.transpose(R[:, :, 1::2], (1, 2, 0))[order]
    B = np.transpose(R[:, :, 2::2], (1, 2, 0))[order]
    om = om[order]

    nbeta = info["n_beta"]

    def excitation(name):
        f = result(name)
        t, X = read_tec(f, 2 * n, nbeta, nw)
        if not np.allclose(X[0, :, 0], R[0, :, 0], rtol=1e-6):
            raise NemohFormatError(f"{f}: its frequencies differ from those of {f_rad}")
        beta = []
        for k, title in enumerate(t):
            m = re.search(rf"beta\s*=\s*({_NUM})", title)
            beta.append(float(m.group(1)) if m else float(info["beta_deg"][k]))
        if not np.allclose(beta, info["beta_deg"], atol=1e-3):
            raise NemohFormatError(f"{f}: headings {beta} deg; Nemoh.cal gives {info['beta_deg'].tolist()}")
        # |X| e^{i arg X}: NEMOH's e^{−iωt} convention is the internal one (module docstring)
        Xc = X[:, :, 1::2] * np.exp(1j * X[:, :, 2::2])
        return np.transpose(Xc, (1, 0, 2))[order], np.deg2rad(beta)

    X, beta = excitation("ExcitationForce.tec")
    ds = xr.Dataset(coords={"omega": om, "wave_direction": beta, "body": names,
                            "influenced_dof": labels, "radiating_dof": labels, "axis": list(AXES)})
    fm = ("omega", "influenced_dof", "radiating_dof")
    ds["added_mass"] = (fm, A)
    ds["radiation_damping"] = (fm, B)
    ds["excitation"] = (("omega", "wave_direction", "influenced_dof"), X)
    if _find([res], ["FKForce.tec"]) and _find([res], ["DiffractionForce.tec"]):
        ds["froude_krylov"] = (ds["excitation"].dims, excitation("FKForce.tec")[0])
        ds["diffraction"] = (ds["excitation"].dims, excitation("DiffractionForce.tec")[0])
    ds["reference_point"] = (("body", "axis"), ref)

    C = np.zeros((n, n))
    W = np.zeros((n, n))
    vol, cob, cogs, used = np.zeros(nb), np.zeros((nb, 3)), np.zeros((nb, 3)), []
    rho_, g_ = info["rho"], info["g"]
    files = [hydrostatics_files(root, b, nb) for b in range(nb)]
    meshes = [body_mesh_file(root, bodies[b]["mesh"]) for b in range(nb)]
    hs_read = [read_hydrostatics(hs) if hs is not None else None for _, hs in files]
    from_mesh, notes = [], []
    for b in range(nb):
        (kh, hs), h, mesh = files[b], hs_read[b], meshes[b]
        o = 6 * b
        m = None
        if mesh is not None:
            m = mesh_hydrostatics(mesh, ref[b], rho_, g_, cog=h["cog"] if h is not None else ref[b])
        if h is not None and kh is not None and (m is None or _agrees(h, m)):
            K = read_kh(kh)
            C[o:o + 6, o:o + 6] = K
            W[o:o + 6, o:o + 6] = waterplane_part(K, h["volume"], h["cob"], h["cog"], ref[b], rho_, g_)
            vol[b], cob[b], cogs[b] = h["volume"], h["cob"], h["cog"]
            used += [str(kh), str(hs)]
            continue
        if m is None:
            want = (f"KH_{b}.dat and Hydrostatics_{b}.dat" + (" (or KH.dat and Hydrostatics.dat)" if nb == 1 else ""))
            raise FileNotFoundError(
                f"{root}: no hydrostatics for body {b + 1} ({names[b]!r}): looked for {want} in "
                f"{root / 'Mesh'}, {root} and {root / 'Mechanics'} (any letter case), and for its "
                f"mesh {bodies[b]['mesh']!r} (Nemoh.cal) to compute them from. NEMOH's mesher "
                "writes them; copy each body's files to those names")
        # the body's own mesh: its hydrostatics replace files that belong to another mesh
        C[o:o + 6, o:o + 6] = m["hydrostatic_stiffness"]
        W[o:o + 6, o:o + 6] = m["waterplane_stiffness"]
        vol[b], cob[b] = m["volume"], m["cob"]
        cogs[b] = h["cog"] if h is not None else ref[b]
        used.append(str(mesh))
        from_mesh.append(names[b])
        if h is not None:
            notes.append(f"{hs} gives {names[b]!r} V = {h['volume']:.6g} m³, z_B = {h['cob'][2]:.4g} m; "
                         f"its mesh {mesh} encloses V = {m['volume']:.6g} m³, z_B = {m['cob'][2]:.4g} m")
    if not from_mesh and nb > 1:
        _refuse_union(root, cal, names, files, hs_read, bodies)
    if notes:
        import warnings

        from .database import HydroDatabaseWarning
        warnings.warn(
            f"{cal}: the hydrostatics files do not belong to their bodies' meshes ("
            + "; ".join(notes) + "): hydrostatics computed from each body's own mesh instead "
            "(NEMOH v3.0.2's hydrosCal writes those of all bodies together into every "
            "hydrostatics_<b>.dat). To silence this, write each body's own KH_<b>.dat and "
            "Hydrostatics_<b>.dat (or remove the wrong ones).", HydroDatabaseWarning, stacklevel=2)
    ds["displaced_volume"] = (("body",), vol)
    ds["center_of_buoyancy"] = (("body", "axis"), cob)
    ds["hydrostatic_stiffness"] = (fm[1:], C)
    ds["hydrostatic_stiffness"].attrs["includes"] = (
        "NEMOH KH as given, per body about the point G of its Hydrostatics.dat: water-plane terms and "
        "rho g V (z_B - z_G) in 44/55 (mass rho V at G)" + (
            f"; for {', '.join(from_mesh)}: the same terms computed from the body's own mesh "
            "(hydro.nemoh.mesh_hydrostatics)" if from_mesh else ""))
    ds["waterplane_stiffness"] = (fm[1:], W)
    ds["waterplane_stiffness"].attrs["includes"] = (
        "water-plane terms only (33, 34, 35, 44, 55, 45 about the reference point); rho g V (z_B - z_G) "
        "removed from 44/55, all other entries dropped")
    ds.attrs = {"rho": float(info["rho"]), "g": float(info["g"]),
                "water_depth": float(info["water_depth"]), "convention": CONVENTION,
                "source": "hydro.nemoh.read_nemoh", "nemoh_version": int(info["version"]),
                "nemoh_files": ", ".join([str(cal), str(f_rad)] + used),
                "nemoh_conversion": "none: NEMOH's exp(-i omega t) is the internal convention; "
                                    "X = |X| exp(i angle)",
                "nemoh_center_of_gravity": "; ".join(f"{nm}: {np.array2string(cogs[k], precision=6)}"
                                                     for k, nm in enumerate(names)),
                "nemoh_hydrostatics": ("from each body's mesh (the hydrostatics files belong to "
                                       f"another mesh or are missing): {', '.join(from_mesh)}"
                                       if from_mesh else "the KH and Hydrostatics files")}
    if estimate_inf:
        ds["added_mass_inf"] = (fm[1:], estimate_added_mass_inf(ds))
        ds.attrs["added_mass_inf_source"] = (
            "estimated (NEMOH gives no A_inf): median over the radiation band of A(omega) + "
            "(1/omega) int K(t) sin(omega t) dt, hydro.radiation.estimate_added_mass_inf")
    return ds


def _agrees(h, m) -> bool:
    """A Hydrostatics.dat agrees with its body's mesh: V and z_B within 1 % (of V, of V^(1/3))."""
    L = m["volume"] ** (1.0 / 3.0)
    return (abs(h["volume"] - m["volume"]) <= _HS_RTOL * m["volume"]
            and np.all(np.abs(h["cob"] - m["cob"]) <= _HS_RTOL * L))


def _refuse_union(root, cal, names, files, hs_read, bodies):
    """Refuse files that give every body the same displaced volume and centre of buoyancy: two
    bodies that do not overlap cannot share both; it is the hydrostatics of all of them together
    (NEMOH v3.0.2's hydrosCal writes that into each hydrostatics_<b>.dat)."""
    h0 = hs_read[0]
    L = h0["volume"] ** (1.0 / 3.0)
    if all(np.isclose(h["volume"], h0["volume"], rtol=1e-6)
           and np.allclose(h["cob"], h0["cob"], atol=1e-6 * L) for h in hs_read[1:]):
        listed = ", ".join(str(hs) for _, hs in files)
        raise NemohFormatError(
            f"{cal}: the hydrostatics files {listed} give all {len(names)} bodies {names} the same "
            f"displaced volume {h0['volume']:.6g} m³ and centre of buoyancy "
            f"{np.round(h0['cob'], 4).tolist()} m: the hydrostatics of all the bodies together, "
            "not of each (NEMOH v3.0.2's hydrosCal writes that into every hydrostatics_<b>.dat). "
            "Fix: put each body's mesh where Nemoh.cal names it ("
            + ", ".join(f"'{b['mesh']}'" for b in bodies)
            + f", relative to {root}), from which each body's hydrostatics are computed, or write "
            "each body's own KH_<b>.dat and Hydrostatics_<b>.dat (NEMOH's mesher run on one body)")


def is_nemoh(path) -> bool:
    """Whether `path` is a NEMOH run: a Nemoh.cal, or a folder (or Results/) beside one."""
    try:
        find_nemoh_cal(path)
        return True
    except FileNotFoundError:
        return False
