"""Hydro databases from capytaine: all bodies solved together, cached, with our hydrostatics.

``solve(bodies, omega=..., dx=...)`` turns plain-dict body specs (see ``hydro.geometry``) into one
capytaine problem set — radiation of every rigid dof of every body and diffraction for every
heading, solved on the union of all hulls so that the hydrodynamic interactions are included —
and returns capytaine's own dataset (complex amplitudes for time dependence e^{-iωt}; its ``added_mass`` and
``radiation_damping`` carry capytaine's dims and dof labels "<body>__<Mode>") augmented with the
schema variables of the mfm hydro database:

- ``displaced_volume(body)`` m³, ``center_of_buoyancy(body, axis)`` m, ``reference_point(body,
  axis)`` m (the rotation centre of that body's dofs),
- ``waterplane_stiffness(influenced_dof, radiating_dof)``: ONLY the water-plane terms about each
  body's (x_r, y_r), block diagonal (``hydro.geometry.hull_hydrostatics``),
- ``hydrostatic_stiffness(influenced_dof, radiating_dof)``: buoyancy only, block diagonal: the
  water-plane terms + ρgV(z_B − z_r) in C44, C55 and C46 = −ρgV(x_B − x_r), C56 = −ρgV(y_B − y_r);
  no weight terms (the masses are not inputs here).
- ``mean_drift(omega, wave_direction, influenced_dof)`` only with ``drift=``: capytaine's far-field
  mean drift of a single body, held or freely floating (:func:`_far_field_drift`).

Settings: lid on the water plane against irregular frequencies; ω = ∞ (radiation only) appended
when ``infinite_frequency``; finite or infinite depth; symmetry "auto" uses the rotation symmetry
of a single body of revolution on the z axis, else the xOz (y = 0) reflection when the layout is
symmetric — all floats then form one capytaine body whose ``ReflectionSymmetricMesh`` holds them
all, each float keeping its own rigid dofs (``DofOnSubmesh``), because a capytaine ``Multibody``
keeps the symmetry only when every body lies on y = 0.

Results are cached under ``cache_dir`` (default ``~/.cache/mfm/bem``, or ``$MFM_BEM_CACHE``) by a
SHA-256 of the normalised specs (mesh files by content), the settings and the capytaine version;
``attrs["cache_status"]`` is "hit" when the returned dataset was read from the cache.
"""
from __future__ import annotations

import datetime
import hashlib
import json
import logging
import math
import os
from pathlib import Path

import numpy as np
import xarray as xr

from hydro import geometry as geo
from hydro.database import read_netcdf, write_netcdf
from hydro.waves import wavenumber

LOG = logging.getLogger(__name__)

SCHEMA_VERSION = "mfm-bem-1"
AXES = ("x", "y", "z")
CONVENTION = "exp(-i omega t)"
HYDROSTATIC_TERMS = (
    "buoyancy only, per body about its reference point (x_r, y_r, z_r): water-plane terms + "
    "rho g V (z_B - z_r) in C44 and C55, C46 = -rho g V (x_B - x_r), C56 = -rho g V (y_B - y_r); "
    "no weight terms (-m g z_G, m g x_G): masses are not inputs of the BEM"
)
WATERPLANE_TERMS = (
    "water-plane terms only, per body about (x_r, y_r): C33 = rho g A, "
    "C34 = C43 = rho g int(y-y_r), "
    "C35 = C53 = -rho g int(x-x_r), C44 = rho g int(y-y_r)^2, C55 = rho g int(x-x_r)^2, "
    "C45 = C54 = -rho g int(x-x_r)(y-y_r); exact for the panelled water-plane polygon"
)


# ------------------------------------------------------------------------------------------------
# Inputs

# The lowest k h at which capytaine 3.0's finite-depth Green function can be evaluated. Its
# Delhommeau.find_best_exponential_decomposition (capytaine/green_functions/delhommeau.py, the
# default method "python") raises NotImplementedError "cannot evaluate finite depth Green function
# for kh<0.1" when kh <= 0.1, and above that fits a sum of exponentials to the finite-depth kernel
# (capytaine/tools/prony_decomposition.py, 4..30 terms, mean square error < 1e-4) and raises
# GreenFunctionEvaluationError "cannot evaluate finite depth Green function for kh=…" when no fit
# is found. Measured (100 tries each, the fit's sample points are jittered at random): every fit
# fails for kh <= 0.1375, every one succeeds for 0.138 <= kh <= 3e5. 0.14 keeps a margin.
KH_MIN = 0.14


def _check_positive(name, v, allow_inf=False):
    try:
        f = float(v)
    except (TypeError, ValueError):
        f = float("nan")
    if not (f > 0 and (math.isfinite(f) or (allow_inf and f == math.inf))):
        accepted = "a positive number or inf" if allow_inf else "a positive finite number"
        raise ValueError(f"{name} = {v!r}: expected {accepted}.")
    return f


def _check_omega(omega):
    w = np.atleast_1d(np.asarray(omega, dtype=float)).ravel()
    if w.size == 0 or not np.all(np.isfinite(w)) or np.any(w <= 0):
        raise ValueError(f"omega = {omega!r}: give finite angular frequencies > 0 in rad/s (the "
                         f"infinite frequency is added by infinite_frequency=True; for the "
                         f"zero-frequency limit use a small positive omega).")
    return np.unique(w)


def check_finite_depth(omegas, water_depth, g, *, deep_from=math.inf, green_function=None):
    """Refuse, before any solve, the frequencies at which capytaine cannot evaluate the
    finite-depth Green function: asks the solver's own Green function (its Prony decomposition at
    each k h, k from ω² = g k tanh(k h); ≈ 1 ms each, cached by capytaine for the solve that
    follows) rather than trusting a constant, so a later capytaine that does better or worse is
    judged by what it does. Without this check capytaine logs and skips each failing problem
    and the run ends, after all the other frequencies (~45 minutes for a fine mesh), with NaN.

    omegas: the finite frequencies (rad/s); those ≥ ``deep_from`` are solved in deep water and
    not checked. green_function: the solver's (``BEMSolver().engine.green_function``); default a
    new ``Delhommeau()``. Raises ValueError naming the frequencies, their k h, the limit (KH_MIN,
    measured) and the lowest ω that works at this depth.
    """
    if not math.isfinite(water_depth):
        return
    w = np.asarray([x for x in np.atleast_1d(omegas) if math.isfinite(x) and x < deep_from], float)
    if w.size == 0:
        return
    if green_function is None:
        from capytaine.green_functions.delhommeau import Delhommeau

        green_function = Delhommeau()
    kh = wavenumber(w, water_depth, g) * water_depth
    bad = []
    for om, x in zip(w, kh):
        try:
            green_function.find_best_exponential_decomposition(float(x))
        except Exception as e:  # noqa: BLE001 - NotImplementedError or GreenFunctionEvaluationError
            bad.append((float(om), float(x), f"{type(e).__name__}: {e}"))
    if bad:
        w_ok = math.sqrt(g * KH_MIN / water_depth * math.tanh(KH_MIN))
        shown = ", ".join(f"{om:.4g} rad/s (kh = {x:.4g})" for om, x, _ in bad[:5])
        raise ValueError(
            f"omega: at water_depth = {water_depth:g} m capytaine cannot evaluate the finite-depth "
            f"Green function at {len(bad)} frequenc{'y' if len(bad) == 1 else 'ies'}: {shown}"
            f"{' ...' if len(bad) > 5 else ''} ({bad[0][2]}). capytaine's finite-depth kernel "
            f"needs kh ≥ {KH_MIN} (measured for capytaine 3.0: it fails for kh ≤ 0.1375); give "
            f"omega ≥ {w_ok:.4g} rad/s at this depth. Nothing was solved.")


def _check_directions(wave_directions):
    b = np.atleast_1d(np.asarray(wave_directions, dtype=float)).ravel()
    if b.size == 0 or not np.all(np.isfinite(b)):
        raise ValueError(f"wave_directions = {wave_directions!r}: give finite headings in rad "
                         f"(0 = waves travelling towards +x).")
    return np.unique(b)


def _file_digest(path):
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for chunk in iter(lambda: f.read(1 << 20), b""):
            h.update(chunk)
    return h.hexdigest()


def code_version() -> str:
    """The version of the code that turns specs into BEM results: the installed package version
    and a digest of the sources that mesh the hulls and post-process capytaine's results
    (hydro/bem.py, hydro/geometry.py), so that an edit to either invalidates cached results
    even while the package version stays the same."""
    try:
        from importlib.metadata import version

        pkg = version("mfm")
    except Exception:  # noqa: BLE001 - not installed (run from a checkout)
        pkg = "unknown"
    h = hashlib.sha256()
    for name in ("bem.py", "geometry.py"):
        h.update((Path(__file__).parent / name).read_bytes())
    return f"{pkg}+{h.hexdigest()[:12]}"


def settings_hash(specs, settings):
    """SHA-256 (hex) of the normalised body specs (mesh files by content), the settings, the
    capytaine version and :func:`code_version`."""
    import capytaine as cpt

    bodies = []
    for s in specs:
        s = dict(s)
        if s["shape"] == "mesh":
            s["file"] = _file_digest(s["file"])  # content, not path
        bodies.append(s)
    key = {"schema": SCHEMA_VERSION, "capytaine": cpt.__version__, "code": code_version(),
           "bodies": bodies, "settings": settings}
    text = json.dumps(key, sort_keys=True, allow_nan=True, default=float)
    return hashlib.sha256(text.encode()).hexdigest()


def default_cache_dir():
    """``$MFM_BEM_CACHE`` or ``~/.cache/mfm/bem``."""
    return Path(os.environ.get("MFM_BEM_CACHE", Path.home() / ".cache" / "mfm" / "bem"))


# ------------------------------------------------------------------------------------------------
# Building the capytaine body


def _rigid_dofs(name, reference_point):
    import capytaine as cpt

    dofs = cpt.rigid_body_dofs(rotation_center=tuple(reference_point))
    return {f"{name}__{m}": dofs[m] for m in geo.MODES}


def layout_symmetry(specs):
    """The symmetry a layout allows: "rotation" (one body of revolution on the z axis), "xOz"
    (every body either its own mirror image about y = 0 — a body of revolution on y = 0, or a
    mesh whose hull as placed is symmetric, ``hydro.geometry.mesh_symmetric`` — or a body of
    revolution paired with its mirror image), or "none".

    A mesh body never gives "rotation": capytaine's RotationSymmetricMesh needs the hull as n
    copies of one wedge, which a mesh file is not (its panels would have to be re-made by
    revolving a meridian: give the body as shape "revolution" for that). Two mirrored mesh files
    are not paired either (each must be symmetric itself): pairing them would need the second
    file's panels to be the first's mirrored, which files made apart seldom are."""
    if all(s["shape"] in geo.REVOLVED for s in specs):
        if len(specs) == 1 and specs[0]["origin"][:2] == [0.0, 0.0]:
            return "rotation"
    if _mirror_pairs(specs) is not None:
        return "xOz"
    return "none"


def _on_xoz(spec):
    """Whether a body is its own mirror image about y = 0 (solved as its half y ≥ 0)."""
    if spec["shape"] == "mesh":
        return geo.mesh_symmetric(spec)
    return spec["origin"][1] == 0.0


def _mirror_pairs(specs):
    """Map index of each body at y > 0 to its mirror partner's index (y < 0); None if some body
    off y = 0 has no partner. Bodies on y = 0 are absent from the map."""
    pairs, used = {}, set()
    for i, s in enumerate(specs):
        y = s["origin"][1]
        if _on_xoz(s):
            continue
        if s["shape"] == "mesh":
            return None
        if y > 0:
            for j, t in enumerate(specs):
                if j not in used and j != i and geo.mirror_partner(s, t):
                    pairs[i] = j
                    used.add(j)
                    break
            else:
                return None
    if len(used) != sum(1 for s in specs if s["shape"] != "mesh" and s["origin"][1] < 0):
        return None
    return pairs


def build_body(specs, dx, *, lid=True, symmetry="auto"):
    """The capytaine body of a layout and the hull of each body (for its hydrostatics).

    Returns ``(body, symmetry_used, hulls)``: ``body`` a ``FloatingBody`` or ``Multibody`` whose
    dofs are named "<name>__<Mode>" (6 per body, in spec order), ``symmetry_used`` in
    {"rotation", "xOz", "none"}, ``hulls`` a list of full capytaine meshes, one per body.
    """
    import capytaine as cpt
    from capytaine.bodies.dofs import DofOnSubmesh

    allowed = layout_symmetry(specs)
    if symmetry in (None, False, "none"):
        used = "none"
    elif symmetry == "auto":
        used = allowed
    elif symmetry in ("xOz", "rotation"):
        ok = allowed == symmetry or (symmetry == "xOz" and allowed == "rotation"
                                     and specs[0]["origin"][1] == 0.0)
        if not ok:
            raise ValueError(f"symmetry = {symmetry!r} does not hold for this layout (it allows "
                             f"{allowed!r}); use symmetry='auto' or 'none'.")
        used = symmetry
    else:
        raise ValueError(f"symmetry = {symmetry!r}: expected 'auto', 'xOz', 'rotation' or 'none'.")

    full = [geo.body_meshes(s, dx, "full", lid=lid and used == "none") for s in specs]
    hulls = [f[0] for f in full]

    if used == "rotation":
        s = specs[0]
        wedge, lid_wedge, n = geo.body_meshes(s, dx, "wedge", lid=lid)
        mesh = cpt.RotationSymmetricMesh(wedge, n=n, name=s["name"])
        lid_mesh = None if lid_wedge is None else cpt.RotationSymmetricMesh(lid_wedge, n=n)
        body = cpt.FloatingBody(mesh=mesh, lid_mesh=lid_mesh, name=s["name"],
                                dofs=_rigid_dofs(s["name"], s["reference_point"]))
        return body, used, hulls

    if used == "xOz":
        pairs = _mirror_pairs(specs)
        lower = set(pairs.values())
        parts, lid_parts, kinds = [], [], []
        for i, s in enumerate(specs):
            if i in lower:
                continue
            if _on_xoz(s):
                h, lm, _ = geo.body_meshes(s, dx, "half", lid=lid)
                kinds.append((i, "half"))
            else:
                h, lm, _ = geo.body_meshes(s, dx, "full", lid=lid)
                kinds.append((i, "upper"))
            parts.append(h)
            if lm is not None:
                lid_parts.append(lm)
        half, masks = cpt.Mesh.join_meshes(*parts, return_masks=True)
        mesh = cpt.ReflectionSymmetricMesh(half, plane="xOz", name="layout")
        zero = np.zeros(half.nb_faces, dtype=bool)
        full_mask = {}
        for (i, kind), m in zip(kinds, masks):
            m = np.asarray(m, dtype=bool)
            if kind == "half":
                full_mask[i] = np.concatenate([m, m])
            else:
                full_mask[i] = np.concatenate([m, zero])
                full_mask[pairs[i]] = np.concatenate([zero, m])
        dofs = {}
        for i, s in enumerate(specs):
            for k, d in _rigid_dofs(s["name"], s["reference_point"]).items():
                dofs[k] = DofOnSubmesh(d, full_mask[i])
        lid_mesh = None
        if lid_parts:
            lid_half = lid_parts[0] if len(lid_parts) == 1 else cpt.Mesh.join_meshes(*lid_parts)
            lid_mesh = cpt.ReflectionSymmetricMesh(lid_half, plane="xOz")
        body = cpt.FloatingBody(mesh=mesh, lid_mesh=lid_mesh, dofs=dofs, name="layout")
        return body, used, hulls

    members = []
    for s, (h, lm, _) in zip(specs, full):
        dofs = cpt.rigid_body_dofs(rotation_center=tuple(s["reference_point"]))
        members.append(cpt.FloatingBody(mesh=h, lid_mesh=lm, name=s["name"],
                                        dofs={m: dofs[m] for m in geo.MODES}))
    if len(members) == 1:
        s, b = specs[0], members[0]
        body = cpt.FloatingBody(mesh=b.mesh, lid_mesh=b.lid_mesh, name=s["name"],
                                dofs=_rigid_dofs(s["name"], s["reference_point"]))
    else:
        body = cpt.Multibody(members, name="layout")
    return body, used, hulls


# ------------------------------------------------------------------------------------------------
# Solving


def _solve_problems(body, omegas, directions, *, water_depth, rho, g, progress, n_threads,
                    keep_details=False):
    """Radiation (all dofs) and diffraction (all headings, finite ω only) problems, solved one
    frequency at a time so that the LU factorisation is shared by the problems of one ω.
    ``water_depth``: one depth, or one per ω (finite depth where it matters, deep water above)."""
    import capytaine as cpt
    from tqdm.auto import tqdm

    dof_names = list(body.dofs)
    depths = list(water_depth) if np.ndim(water_depth) else [water_depth] * len(omegas)
    groups = []
    for w, water_depth in zip(omegas, depths):
        pbs = [cpt.RadiationProblem(body=body, omega=w, radiating_dof=d, water_depth=water_depth,
                                    rho=rho, g=g) for d in dof_names]
        if np.isfinite(w):
            pbs += [cpt.DiffractionProblem(body=body, omega=w, wave_direction=b,
                                           water_depth=water_depth, rho=rho, g=g)
                    for b in directions]
        groups.append(pbs)
    _warn_once([p for grp in groups for p in grp if math.isfinite(float(p.omega))])
    solver = cpt.BEMSolver()
    results = []
    for pbs in tqdm(groups, desc="BEM frequencies", unit="ω", disable=not progress):
        results += solver.solve_all(pbs, progress_bar=False, n_threads=n_threads,
                                    _check_wavelength=False, keep_details=keep_details)
    return solver, results


def _warn_once(problems):
    """capytaine's wavelength/mesh, depth and irregular-frequency warnings, once for the whole
    set of finite frequencies rather than once per frequency."""
    try:
        from capytaine.bem.problems_checks import (
            _check_wavelength_and_irregular_frequencies, _check_wavelength_and_mesh_resolution,
            _check_wavelength_and_water_depth)
    except ImportError:  # private helpers: a later capytaine may move them; the solve goes on
        return
    if problems:
        _check_wavelength_and_mesh_resolution(problems)
        _check_wavelength_and_water_depth(problems)
        _check_wavelength_and_irregular_frequencies(problems)


# ------------------------------------------------------------------------------------------------
# Mean drift (far field)

DRIFT_MOTIONS = ("fixed", "free")
#: Kochin functions are evaluated on this many directions over the circle (1°): the far-field
#: integral ∫|H|² cos θ dθ is a trapezoid sum of a smooth periodic function, exact to round-off
#: long before 1° for the bodies here (kR < 10)
DRIFT_N_THETA = 360


def rigid_mass_matrix(mass, com, inertia, reference_point):
    """The 6×6 rigid-body mass matrix about `reference_point` (inertial axes): [[m I, −m S(r)],
    [m S(r), J + m (|r|² I − r rᵀ)]] with r = com − reference_point, S(r) the cross-product
    matrix (S(r) v = r × v) and J (3×3) the inertia about the centre of mass."""
    r = np.asarray(com, float) - np.asarray(reference_point, float)
    S = np.array([[0.0, -r[2], r[1]], [r[2], 0.0, -r[0]], [-r[1], r[0], 0.0]])
    M = np.zeros((6, 6))
    M[:3, :3] = mass * np.eye(3)
    M[:3, 3:] = -mass * S
    M[3:, :3] = mass * S
    M[3:, 3:] = np.asarray(inertia, float) + mass * (r @ r * np.eye(3) - np.outer(r, r))
    return M


def gravity_stiffness(mass, com, reference_point, g):
    """The weight's part of the linear restoring matrix about `reference_point` (the buoyancy's
    part is ``hydrostatic_stiffness``): C44 = C55 = −m g (z_G − z_r), C46 = m g (x_G − x_r),
    C56 = m g (y_G − y_r) (WAMIT's convention, hydro.wamit)."""
    r = np.asarray(com, float) - np.asarray(reference_point, float)
    C = np.zeros((6, 6))
    C[3, 3] = C[4, 4] = -mass * g * r[2]
    C[3, 5] = mass * g * r[0]
    C[4, 5] = mass * g * r[1]
    return C


def _results_at(results, w):
    """capytaine's results at the frequency ``w``: the radiation ones by radiating dof and the
    diffraction ones by heading."""
    import capytaine as cpt

    rad = {str(r.radiating_dof): r for r in results
           if isinstance(r.problem, cpt.RadiationProblem) and float(r.omega) == w}
    dif = {float(r.wave_direction): r for r in results
           if isinstance(r.problem, cpt.DiffractionProblem) and float(r.omega) == w}
    return rad, dif


def _far_field_drift(ds, results, directions, *, motions, inertia, reference_point, rho, g):
    """``mean_drift`` (omega, wave_direction, influenced_dof) of ONE body by capytaine 3.0's
    far-field formula (``capytaine.post_pro.far_field_mean_drift_force``: Maruo's momentum flux
    for surge and sway, Newman's for yaw, from the Kochin functions of the diffraction and the
    radiation potentials; Delhommeau's thesis eq. 2.170), per unit wave amplitude squared.

    motions "fixed": the body held (diffraction only); "free": freely floating,
    X = [−ω²(M + A) − iωB + C]⁻¹ F with M the rigid mass matrix of `inertia` (mass, com, inertia
    about the CoM) and C = hydrostatic_stiffness + the weight's terms. Heave, roll, pitch are 0
    (the far field gives the horizontal plane only). The yaw moment is moved from the Kochin
    functions' origin (x, y) = (0, 0) to `reference_point`: M_r = M_0 − (x_r F_y − y_r F_x).
    NaN at ω = ∞ (as the excitation)."""
    import capytaine as cpt
    from capytaine.post_pro.kochin import compute_kochin

    dtheta = 2 * np.pi / DRIFT_N_THETA
    # capytaine wants θ beyond [0, 2π] on both sides and every heading strictly inside
    theta = dtheta * np.arange(-1, DRIFT_N_THETA + 2)
    betas = np.mod(np.asarray(directions, float), 2 * np.pi)
    om_all = np.asarray(ds["omega"].values, float)
    dofs = [str(d) for d in ds["radiating_dof"].values]
    if ([d.split("__")[-1] for d in dofs] != list(geo.MODES)
            or [str(d) for d in ds["influenced_dof"].values] != dofs):
        # M and C below are in MODES order
        raise RuntimeError(f"capytaine's dofs {dofs} are not the rigid modes {geo.MODES} in order")
    out = np.full((om_all.size, len(directions), 6), np.nan)
    for iw, w in enumerate(om_all):
        if not np.isfinite(w):
            continue
        rad, dif = _results_at(results, w)
        any_r = next(iter(dif.values()))
        h = float(any_r.water_depth)
        Hd = np.array([compute_kochin(dif[float(b)], theta) for b in directions])
        Hr = np.array([compute_kochin(rad[d], theta) for d in dofs])
        if motions == "free":
            M = rigid_mass_matrix(inertia["mass"], inertia["com"], inertia["inertia"], reference_point)
            C = (np.asarray(ds["hydrostatic_stiffness"].values, float)
                 + gravity_stiffness(inertia["mass"], inertia["com"], reference_point, g))
            A = np.asarray(ds["added_mass"].values[iw], float)
            B = np.asarray(ds["radiation_damping"].values[iw], float)
            F = np.asarray(ds["excitation_force"].sel(omega=w).transpose(
                "wave_direction", "influenced_dof").values, complex)
            Z = -w * w * (M + A) - 1j * w * B + C
            X = np.linalg.solve(Z, F.T).T                     # (n_β, 6), m or rad per m of wave
        else:
            X = np.zeros((len(directions), len(dofs)), complex)
        data = xr.Dataset(
            {"kochin_diffraction": (("omega", "wave_direction", "theta"), Hd[None]),
             "kochin_radiation": (("omega", "radiating_dof", "theta"), Hr[None])},
            coords={"omega": [w], "wavenumber": ("omega", [float(any_r.wavenumber)]),
                    "water_depth": h, "rho": rho, "g": g, "theta": theta,
                    "wave_direction": betas, "radiating_dof": dofs})
        Xda = xr.DataArray(X[None], dims=("omega", "wave_direction", "radiating_dof"),
                           coords={"omega": [w], "wave_direction": betas, "radiating_dof": dofs})
        f = cpt.post_pro.far_field_mean_drift_force(Xda, data)
        diag = lambda v: np.real(np.diagonal(f[v].values[0]))          # noqa: E731  β_k = β_l
        fx, fy, mz = diag("drift_force_surge"), diag("drift_force_sway"), diag("drift_force_yaw")
        xr_, yr_ = float(reference_point[0]), float(reference_point[1])
        out[iw, :, 0], out[iw, :, 1] = fx, fy
        out[iw, :, 5] = mz - (xr_ * fy - yr_ * fx)
        out[iw, :, 2:5] = 0.0
    return out


#: ``drift = "kochin"``: the Kochin functions are stored on this many directions θ_i = 2π i / N
#: (2°): the far-field integrals are periodic trapezoid sums, exact for |H|²'s harmonics below N/2
#: (a body of radius R radiates harmonics up to ≈ kR + 10: Wu & Yuan's platform, kR ≈ 10 at 5 s)
KOCHIN_N_THETA = 180


def _kochin_functions(ds, results, directions, n_theta):
    """The Kochin functions of the diffraction (omega, wave_direction, theta) and of each radiating
    dof (omega, radiating_dof, theta) of the whole layout (capytaine 3.0's
    ``post_pro.kochin.compute_kochin``, its normalisation) on θ_i = 2π i / n_theta: the far field
    of any motion ξ of the bodies is H_D + Σ_j ξ_j H_j (:func:`hydro.drift.far_field_drift`).
    NaN at ω = ∞."""
    from capytaine.post_pro.kochin import compute_kochin

    theta = 2 * np.pi * np.arange(n_theta) / n_theta
    om_all = np.asarray(ds["omega"].values, float)
    dofs = [str(d) for d in ds["radiating_dof"].values]
    Hd = np.full((om_all.size, len(directions), n_theta), np.nan + 0j)
    Hr = np.full((om_all.size, len(dofs), n_theta), np.nan + 0j)
    for iw, w in enumerate(om_all):
        if not np.isfinite(w):
            continue
        rad, dif = _results_at(results, w)
        Hd[iw] = [compute_kochin(dif[float(b)], theta) for b in directions]
        Hr[iw] = [compute_kochin(rad[d], theta) for d in dofs]
    return theta, Hd, Hr


def _block_diag(blocks):
    n = 6 * len(blocks)
    out = np.zeros((n, n))
    for k, b in enumerate(blocks):
        out[6 * k:6 * k + 6, 6 * k:6 * k + 6] = b
    return out


def _augment(ds, specs, hulls, *, rho, g):
    """Add the schema's hydrostatic variables, per body, from each body's own hull."""
    names = [s["name"] for s in specs]
    dofs = [f"{n}__{m}" for n in names for m in geo.MODES]
    hs = [geo.hull_hydrostatics(h, s["reference_point"], rho=rho, g=g)
          for s, h in zip(specs, hulls)]
    ds = ds.drop_vars([v for v in ("rotation_center", "space_coordinate") if v in ds.variables])
    ds = ds.assign_coords(body=("body", names), axis=("axis", list(AXES)))
    ds["displaced_volume"] = xr.DataArray([h["volume"] for h in hs], dims=["body"],
                                          attrs={"units": "m^3"})
    ds["center_of_buoyancy"] = xr.DataArray(np.array([h["center_of_buoyancy"] for h in hs]),
                                            dims=["body", "axis"],
                                            attrs={"units": "m", "frame": "inertial, at rest"})
    ds["reference_point"] = xr.DataArray(np.array([s["reference_point"] for s in specs]),
                                         dims=["body", "axis"],
                                         attrs={"units": "m",
                                                "meaning": "rotation centre of the body's dofs"})
    # Use capytaine's own dof coordinates when present so that the variables align on them.
    idof = ds["influenced_dof"].values.astype(str) if "influenced_dof" in ds.coords else dofs
    if list(idof) != dofs:
        order = [dofs.index(d) for d in idof]
    else:
        order = list(range(len(dofs)))
    for var, key, terms in (("hydrostatic_stiffness", "hydrostatic_stiffness", HYDROSTATIC_TERMS),
                            ("waterplane_stiffness", "waterplane_stiffness", WATERPLANE_TERMS)):
        M = _block_diag([h[key] for h in hs])[np.ix_(order, order)]
        ds[var] = xr.DataArray(M, dims=["influenced_dof", "radiating_dof"],
                               coords={"influenced_dof": list(idof), "radiating_dof": list(idof)},
                               attrs={"units": "N/m, N, N m/rad", "terms": terms})
    return ds


def solve(bodies, *, omega, dx, wave_directions=(0.0,), water_depth=np.inf, rho=1000.0, g=9.81,
          lid=True, symmetry="auto", infinite_frequency=True, cache_dir=None, cache=True,
          progress=True, n_threads=None, deep_water_kh=None, drift=None, drift_inertia=None):
    """Radiation and diffraction of a layout of rigid bodies, all solved together.

    Parameters
    ----------
    bodies : list of body spec dicts (see ``hydro.geometry``), or one spec.
    omega : array (n_ω,) of angular frequencies, rad/s, finite and > 0 (sorted, de-duplicated).
    dx : panel size, m (meridian spacing and water-line arc length per panel).
    wave_directions : headings β, rad (0 = waves travelling towards +x).
    water_depth : m, ``inf`` for deep water.
    deep_water_kh : with a finite ``water_depth``, solve the frequencies where k h ≥ this value
        (and ω = ∞) in deep water: tanh(k h) ≥ tanh 5 = 0.99991 at 5, so the depth changes nothing
        there that the panels resolve, and the finite-depth Green function costs ≈ 3× the deep
        one. None (default): every frequency at ``water_depth``. The dataset keeps the physical
        ``water_depth`` and records the split (attrs ``deep_water_kh``, ``deep_water_omega_min``).
    rho, g : kg/m³, m/s².
    lid : water-plane lid against irregular frequencies.
    symmetry : "auto", "xOz", "rotation" or "none" (see the module docstring).
    infinite_frequency : also solve radiation at ω = ∞ (excitation is NaN there).
    cache_dir, cache : where the NetCDF results are kept; ``cache=False`` always solves.
    progress : tqdm progress bar over the frequencies.
    n_threads : threads per solve (None: capytaine's default, all cores).
    drift : None, or "fixed" / "free": also the far-field mean drift ``mean_drift`` of a single
        body (:func:`_far_field_drift`), with the body held ("fixed") or freely floating ("free",
        which needs ``drift_inertia`` = {"mass": kg, "com": [x, y, z] m, "inertia": 3×3 kg m²
        about the CoM}). A layout of several bodies is refused there: the far field gives the
        total force on all of them, not each body's. "kochin": the layout's Kochin functions
        (:func:`_kochin_functions`, any number of bodies) ``kochin_diffraction`` (omega,
        wave_direction, theta) and ``kochin_radiation`` (omega, radiating_dof, theta) on
        :data:`KOCHIN_N_THETA` directions, from which the far-field drift of any motion of the
        bodies follows (:func:`hydro.drift.far_field_drift`: the model's own,
        :func:`mfm.frequency.drift.model_mean_drift`).

    Returns
    -------
    xarray.Dataset: capytaine's dataset (``added_mass``, ``radiation_damping`` with dims (omega,
    influenced_dof, radiating_dof) as capytaine 3.0 assembles them, ``Froude_Krylov_force``,
    ``diffraction_force``, ``excitation_force`` (omega, wave_direction, influenced_dof) for
    e^{-iωt}; ω = inf appended last when ``infinite_frequency``) plus ``displaced_volume``,
    ``center_of_buoyancy``, ``reference_point``, ``hydrostatic_stiffness``,
    ``waterplane_stiffness``, and attrs with every setting, the versions, the date and ``hash``.
    """
    import capytaine as cpt

    specs = geo.normalize_specs(bodies)
    omegas = _check_omega(omega)
    directions = _check_directions(wave_directions)
    dx = _check_positive("dx", dx)
    water_depth = _check_positive("water_depth", water_depth, allow_inf=True)
    rho = _check_positive("rho", rho)
    g = _check_positive("g", g)
    if deep_water_kh is not None:
        deep_water_kh = _check_positive("deep_water_kh", deep_water_kh)
    if drift not in (None, "kochin", *DRIFT_MOTIONS):
        raise ValueError(f"drift = {drift!r}: expected None, 'fixed', 'free' or 'kochin'.")
    if drift in DRIFT_MOTIONS and len(specs) != 1:
        raise ValueError(f"drift = {drift!r} with {len(specs)} bodies: capytaine's far-field mean "
                         "drift is the total force on all bodies together, not each body's; solve "
                         "the drift of one body at a time, or store the layout's Kochin functions "
                         "(drift = 'kochin') for the drift of a model's own motions")
    if drift == "free":
        try:
            drift_inertia = {"mass": _check_positive("drift_inertia['mass']", drift_inertia["mass"]),
                             "com": [float(v) for v in drift_inertia["com"]],
                             "inertia": np.asarray(drift_inertia["inertia"], float).tolist()}
        except (TypeError, KeyError) as e:
            raise ValueError(f"drift = 'free' needs drift_inertia = {{'mass': kg, 'com': [x, y, z], "
                             f"'inertia': 3x3 about the CoM}}; got {drift_inertia!r} ({e})") from None
        if len(drift_inertia["com"]) != 3 or np.shape(drift_inertia["inertia"]) != (3, 3):
            raise ValueError(f"drift_inertia: com must have 3 coordinates and inertia be 3x3; got "
                             f"{drift_inertia!r}")
    elif drift_inertia is not None:
        raise ValueError(f"drift_inertia is only for drift = 'free' (drift = {drift!r})")
    if symmetry not in ("auto", "xOz", "rotation", "none", None, False):
        raise ValueError(f"symmetry = {symmetry!r}: expected 'auto', 'xOz', 'rotation' or 'none'.")
    symmetry = "none" if symmetry in (None, False) else symmetry
    for s in specs:
        keel = _keel(s, dx)
        if keel <= -water_depth:
            raise ValueError(f"body {s['name']!r}: its keel at z = {keel:.4g} m reaches the "
                             f"sea bed (water_depth = {water_depth} m); increase water_depth.")

    settings = {"omega": [float(w) for w in omegas],
                "wave_directions": [float(b) for b in directions],
                "water_depth": water_depth, "rho": rho, "g": g, "dx": dx, "lid": bool(lid),
                "symmetry": symmetry, "infinite_frequency": bool(infinite_frequency)}
    if drift is not None:              # only then: the cache keys of every other solve unchanged
        settings["drift"] = {"motions": drift, "inertia": drift_inertia,
                             "n_theta": KOCHIN_N_THETA if drift == "kochin" else DRIFT_N_THETA}
    deep_from = math.inf  # the lowest ω solved in deep water
    if deep_water_kh is not None and math.isfinite(water_depth):
        settings["deep_water_kh"] = deep_water_kh
        kh = wavenumber(omegas, water_depth, g) * water_depth
        deep_from = float(min((w for w, k in zip(omegas, kh) if k >= deep_water_kh), default=math.inf))
    check_finite_depth(omegas, water_depth, g, deep_from=deep_from)
    digest = settings_hash(specs, settings)
    path = None
    if cache:
        cdir = Path(cache_dir) if cache_dir is not None else default_cache_dir()
        path = cdir / f"bem-{digest[:20]}.nc"
        if path.exists():
            ds = load(path)
            if ds.attrs.get("hash") == digest:
                ds.attrs["cache_status"] = "hit"
                ds.attrs["cache_file"] = str(path)
                return ds
            LOG.warning("cache file %s does not hold hash %s; solving again", path, digest)

    body, used, hulls = build_body(specs, dx, lid=lid, symmetry=symmetry)
    all_w = list(omegas) + ([np.inf] if infinite_frequency else [])
    split = deep_water_kh is not None and math.isfinite(water_depth)
    depths = [np.inf if split and w >= deep_from else water_depth for w in all_w]
    solver, results = _solve_problems(body, all_w, directions, water_depth=depths, rho=rho,
                                      g=g, progress=progress, n_threads=n_threads,
                                      keep_details=drift is not None)
    # capytaine warns that a layout body has no unique rotation centre while it fills its
    # `rotation_center` coordinate; we drop that coordinate for `reference_point(body, axis)`.
    cpt_log = logging.getLogger("capytaine.bodies.bodies")
    level = cpt_log.level
    cpt_log.setLevel(logging.ERROR)
    try:
        attrs = {k: str(v) for k, v in solver.exportable_settings.items()}
        # capytaine makes water_depth a dimension when it varies: assemble each depth apart and
        # join them along ω (the physical depth is the attrs' water_depth)
        parts = []
        for d in dict.fromkeys(float(r.water_depth) for r in results):
            part = cpt.assemble_dataset([r for r in results if float(r.water_depth) == d],
                                        hydrostatics=False, attrs=attrs)
            parts.append(part.drop_vars("water_depth", errors="ignore"))
        ds = parts[0] if len(parts) == 1 else xr.concat(parts, dim="omega",
                                                        data_vars="minimal", coords="minimal",
                                                        compat="override", combine_attrs="override")
        if len(parts) > 1:
            ds = ds.sortby("omega")
    finally:
        cpt_log.setLevel(level)
    ds = _augment(ds, specs, hulls, rho=rho, g=g)
    if drift == "kochin":
        theta, Hd, Hr = _kochin_functions(ds, results, directions, KOCHIN_N_THETA)
        ds = ds.assign_coords(theta=("theta", theta, {"units": "rad", "meaning": "direction of "
                                                      "the far field, 0 = towards +x"}))
        what = ("Kochin function (far-field amplitude) of capytaine 3.0's "
                "post_pro.kochin.compute_kochin about the origin")
        ds["kochin_diffraction"] = xr.DataArray(
            Hd, dims=("omega", "wave_direction", "theta"),
            attrs={"long_name": f"diffraction {what}, per unit wave amplitude",
                   "units": "m^2/s per m"})
        ds["kochin_radiation"] = xr.DataArray(
            Hr, dims=("omega", "radiating_dof", "theta"),
            attrs={"long_name": f"radiation {what}, per unit motion of the dof (the far field of "
                                "motions ξ is Σ_j ξ_j H_j, as capytaine's far-field drift takes it)",
                   "units": "m^2/s per m or rad"})
    elif drift is not None:
        D = _far_field_drift(ds, results, directions, motions=drift, inertia=drift_inertia,
                             reference_point=specs[0]["reference_point"], rho=rho, g=g)
        ds["mean_drift"] = xr.DataArray(
            D, dims=("omega", "wave_direction", "influenced_dof"),
            coords={"influenced_dof": [f"{specs[0]['name']}__{m}" for m in geo.MODES]},
            attrs={"units": "N/m^2 (forces), N m/m^2 (moments): mean force per unit wave "
                            "amplitude squared, at the body's reference_point",
                   "method": "far field (capytaine.post_pro.far_field_mean_drift_force, Kochin "
                             f"functions on {DRIFT_N_THETA} directions)",
                   "motions": drift if drift == "fixed" else
                   f"free: {json.dumps(drift_inertia)}",
                   "dofs": ", ".join(f"{specs[0]['name']}__{m}" for m in ("Surge", "Sway", "Yaw"))})
    _check_finite(ds)
    n_hull = body.mesh.nb_faces
    n_lid = 0 if body.lid_mesh is None else body.lid_mesh.nb_faces
    ds.attrs.update({
        "source": "hydro.bem.solve (capytaine)",
        "convention": CONVENTION,
        "rho": rho, "g": g, "water_depth": float(water_depth),
        "bodies": json.dumps(specs),
        "omega_rad_s": json.dumps(settings["omega"]),
        "wave_directions_rad": json.dumps(settings["wave_directions"]),
        "dx": repr(dx), "lid": str(bool(lid)), "symmetry": symmetry, "symmetry_used": used,
        "infinite_frequency": str(bool(infinite_frequency)),
        "deep_water_kh": "none" if not split else repr(deep_water_kh),
        "deep_water_omega_min": "none" if not split else repr(deep_from),
        "nb_hull_panels": str(n_hull), "nb_lid_panels": str(n_lid),
        "capytaine_version": cpt.__version__, "numpy_version": np.__version__,
        "xarray_version": xr.__version__, "schema": SCHEMA_VERSION, "mfm_code_version": code_version(),
        "date": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"),
        "hash": digest,
        "hydrostatic_stiffness_terms": HYDROSTATIC_TERMS,
        "waterplane_stiffness_terms": WATERPLANE_TERMS,
        "cache_status": "computed",
    })
    if path is not None:
        path.parent.mkdir(parents=True, exist_ok=True)
        tmp = path.with_suffix(f".tmp{os.getpid()}.nc")
        save(ds, tmp)
        os.replace(tmp, path)  # atomic: a concurrent reader never sees a half-written file
        ds.attrs["cache_file"] = str(path)
    return ds


def _check_finite(ds):
    """Refuse (and never cache) results capytaine left as NaN: it skips problems it cannot solve
    (finite depth with kh < KH_MIN; `n_threads` without threadpoolctl) with a log line only."""
    finite_w = np.isfinite(ds["omega"].values)
    bad = []
    for v in ("added_mass", "radiation_damping", "excitation_force"):
        if v not in ds:
            continue
        vals = ds[v].values if v != "excitation_force" else ds[v].values[finite_w]
        if not np.all(np.isfinite(vals)):
            w = ds["omega"].values[~np.isfinite(vals).reshape(vals.shape[0], -1).all(axis=1)]
            bad.append(f"{v} at omega = {np.array2string(w[:5], precision=4)}")
    if bad:
        raise RuntimeError("capytaine returned NaN for " + "; ".join(bad) + ": it skipped those "
                           f"problems (finite depth needs k h ≥ {KH_MIN}, i.e. a higher omega_min; "
                           "n_threads needs threadpoolctl installed). Nothing was cached.")


def _keel(spec, dx):
    if spec["shape"] in geo.REVOLVED:
        return float(np.min(geo.meridian(spec, spec.get("dx", dx))[:, 1]))
    hull = geo.body_meshes(spec, dx, "full", lid=False)[0]
    return float(np.min(hull.vertices[:, 2]))


# ------------------------------------------------------------------------------------------------
# NetCDF


def _attr_value(v):
    """NetCDF attrs take str and numbers only: booleans, None and containers become text."""
    if isinstance(v, (bool, np.bool_)) or v is None:
        return str(v)
    if isinstance(v, (int, float, np.integer, np.floating, str)):
        return v
    return json.dumps(v, default=str) if isinstance(v, (list, tuple, dict)) else str(v)


def save(ds, path):
    """Write a dataset from ``solve`` to NetCDF: complex values split along a trailing-first
    ``complex`` = ["re", "im"] dim (capytaine's ``separate_complex_values``), dof labels as
    strings, attrs made NetCDF-safe (``water_depth`` stays a float, inf included)."""
    from capytaine.io.xarray import separate_complex_values

    out = separate_complex_values(ds)
    out.attrs = {k: _attr_value(v) for k, v in ds.attrs.items() if k not in ("cache_file",)}
    if out.attrs.get("cache_status") == "hit":
        out.attrs["cache_status"] = "computed"
    encoding = {}
    for c in ("radiating_dof", "influenced_dof", "body", "axis"):
        if c in out.coords:
            out[c] = out[c].astype(str)
            encoding[c] = {"dtype": "U"}
    write_netcdf(out, path, encoding=encoding)


def load(path):
    """Read a NetCDF written by ``save`` (or capytaine's ``export_dataset``), complex values
    merged back; read whole into memory (``hydro.database.read_netcdf``: safe while the process
    holds the file open). Needs no capytaine: reading a database is for the base install
    (capytaine is the ``bem`` extra, needed only to make one)."""
    from .checks import check_netcdf_file
    from .database import merge_complex

    return merge_complex(read_netcdf(check_netcdf_file(path)))
