"""The internal hydrodynamic database: schema, validation, NetCDF round trip, capytaine import.

A database is an ``xarray.Dataset`` with one complex-amplitude convention, capytaine's
time dependence ``exp(-i omega t)``: a wave of real amplitude a and heading beta has elevation
``eta = Re[a exp(i(k(x cos beta + y sin beta) - omega t))]`` and causes the excitation force
``F(t) = Re[a X(omega, beta) exp(-i omega t)]``.

Coordinates
    omega (omega) rad/s, finite, > 0, ascending; wave_direction (wave_direction) rad, 0 = waves
    towards +x; body (body) names; influenced_dof / radiating_dof labels ``"<body>__<Mode>"``
    (Mode in Surge, Sway, Heave, Roll, Pitch, Yaw; 6 per body, bodies in ``body`` order);
    axis = ["x", "y", "z"].
Data variables (dims in this order)
    added_mass (omega, influenced_dof, radiating_dof)        A_ij(omega): force i per accel. of j
    radiation_damping (omega, influenced_dof, radiating_dof) B_ij(omega)
    added_mass_inf (influenced_dof, radiating_dof)           A_inf (required)
    added_mass_zero (influenced_dof, radiating_dof)          A_0 (only where the source gives it)
    excitation (omega, wave_direction, influenced_dof)       complex, N (N m) per m of amplitude
    froude_krylov, diffraction (same dims, optional)
    hydrostatic_stiffness (influenced_dof, radiating_dof)    as the source gives it (attrs say)
    waterplane_stiffness (influenced_dof, radiating_dof)     only the linear water-plane terms
    displaced_volume (body) m^3; center_of_buoyancy (body, axis) m; reference_point (body, axis) m
    mean_drift (omega, wave_direction, influenced_dof)       optional, real: the mean (second-order)
        wave drift force per unit wave amplitude squared, D_i(omega, beta): a regular wave of
        amplitude a, frequency omega and heading beta pushes dof i with the steady force
        F_i = D_i a^2 (N/m^2 for translations, N m/m^2 for rotations), along +x/+y/+z (about
        the axes for moments) at the body's reference_point, inertial axes. It depends on the
        body's first-order motions: the attrs say which (``motions``: "fixed" = diffraction only,
        or "free" = the bodies freely floating with the inertia the attrs name), how (``method``:
        "far field" (momentum, Maruo/Newman: surge, sway, yaw only) or "near field" (pressure
        integration)) and which dofs it gives (``dofs``, comma-separated dof labels: the others
        are 0, not computed)
    kochin_diffraction (omega, wave_direction, theta),
    kochin_radiation (omega, radiating_dof, theta)            optional, complex, both or neither:
        the far-field amplitudes (Kochin functions, capytaine 3.0's normalisation, about the
        origin) of the diffraction and of each dof's radiation of the whole layout, on the
        directions ``theta`` (rad, θ_i = 2π i/N, 0 = towards +x), from which the far-field mean
        drift of any motion of the bodies follows (:func:`hydro.drift.far_field_drift`)
Attributes
    rho (kg/m^3), g (m/s^2), water_depth (m, inf = deep), convention = "exp(-i omega t)",
    source, and provenance strings.

Complex variables are stored in NetCDF with a trailing ``complex`` dimension ["re", "im"]
(:func:`to_netcdf` / :func:`open_database`).
"""
from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import xarray as xr

MODES = ("Surge", "Sway", "Heave", "Roll", "Pitch", "Yaw")
AXES = ("x", "y", "z")
CONVENTION = "exp(-i omega t)"
_SEP = "__"

MATRIX_DIMS = ("influenced_dof", "radiating_dof")
FREQ_MATRIX_DIMS = ("omega",) + MATRIX_DIMS
EXCITATION_DIMS = ("omega", "wave_direction", "influenced_dof")

#: variable -> dims; the variables every database must have
REQUIRED = {
    "added_mass": FREQ_MATRIX_DIMS,
    "radiation_damping": FREQ_MATRIX_DIMS,
    "added_mass_inf": MATRIX_DIMS,
    "excitation": EXCITATION_DIMS,
    "waterplane_stiffness": MATRIX_DIMS,
    "displaced_volume": ("body",),
    "center_of_buoyancy": ("body", "axis"),
    "reference_point": ("body", "axis"),
}
#: variable -> dims; optional variables, checked when present
OPTIONAL = {
    "added_mass_zero": MATRIX_DIMS,
    "froude_krylov": EXCITATION_DIMS,
    "diffraction": EXCITATION_DIMS,
    "hydrostatic_stiffness": MATRIX_DIMS,
    "mean_drift": EXCITATION_DIMS,
    "kochin_diffraction": ("omega", "wave_direction", "theta"),
    "kochin_radiation": ("omega", "radiating_dof", "theta"),
}
REQUIRED_ATTRS = ("rho", "g", "water_depth")

#: the water densities (kg/m³) and gravities (m/s²) a database is accepted with: fresh water 1000,
#: sea water 1025, dense brines ~1200; g 9.78–9.83 on Earth, 10 in textbook examples. Outside them
#: is a unit slip (ρ 1.025 in t/m³, 102.5 or g 0.981 off by 10), refused by :func:`check_values`
RHO_RANGE = (800.0, 1300.0)
G_RANGE = (9.0, 10.5)


class HydroDatabaseWarning(UserWarning):
    """A database is usable but suspicious (asymmetric matrices, negative damping, coarse grid)."""


def dof_labels(bodies) -> list[str]:
    """The dof labels ``"<body>__<Mode>"`` of `bodies` in schema order (6 per body)."""
    return [f"{b}{_SEP}{m}" for b in bodies for m in MODES]


def dof_index(db: xr.Dataset) -> dict[str, int]:
    """Map each dof label of `db` to its position (0 … 6 n_body − 1) along influenced_dof."""
    return {str(d): k for k, d in enumerate(db["influenced_dof"].values)}


def select_bodies(db: xr.Dataset, names) -> xr.Dataset:
    """The sub-database of the bodies `names` (in that order), cross-body terms among them kept.

    Raises KeyError naming the missing bodies and the available ones.
    """
    names = [names] if isinstance(names, str) else list(names)
    _check_bodies(db, names)
    dofs = dof_labels(names)
    out = db.sel(body=names, influenced_dof=dofs)
    if "radiating_dof" in out.dims:
        out = out.sel(radiating_dof=dofs)
    return out


def _check_bodies(db, names):
    available = [str(b) for b in db["body"].values] if "body" in db.coords else []
    missing = [n for n in names if n not in available]
    if missing:
        raise KeyError(f"bodies {missing} are not in the hydro database; available bodies: "
                       f"{available}. Fix the body names or regenerate the database with them.")


# ----------------------------------------------------------------------------------------- validate
def validate(db: xr.Dataset, bodies=None, *, sym_rtol: float = 0.05,
             damping_noise: float = 0.02, source=None, warn: bool = True) -> xr.Dataset:
    """Check `db` against the schema; raise on errors, warn on suspicious data. Returns `db`.

    Errors (ValueError / KeyError): a required variable, dimension, coordinate or attribute is
    missing or has the wrong dims; a value out of range (:func:`check_values`: rho, g, depth,
    omega finite/positive/ascending, headings in radians, volumes, heave stiffness); dof labels not
    ``dof_labels(body)``; ``added_mass_inf`` absent; a body named in `bodies` absent.

    Warnings (:class:`HydroDatabaseWarning`):
    - asymmetry of A(ω), B(ω), A∞: the largest ``|M_ij − M_ji| / sqrt(d_i d_j)`` over ω, with
      d_i = max_ω |M_ii(ω)| (a scale with the units of M_ij), above `sym_rtol`;
    - negative damping: ``B_ii(ω) < −damping_noise · max_ω |B_ii|`` (BEM damping at high ω is
      noise of about ±1 % of its peak, hence the default 2 %); the frequency and dof are named.
      Dofs whose damping peak is below 1e-6 of the largest of their kind (translation or
      rotation), e.g. yaw of an axisymmetric body, are noise and not checked.

    ``warn=False`` runs the errors only (:func:`hydro.prepare.open_any_database` does, behind
    every reader; the warnings come when a model uses the database, :class:`HydroSpec`).

    Each warning is given once per database per process (a database: its file `source`, or its
    arrays' content without one), not at every load. A shipped database's documented data issue
    (:data:`KNOWN_DATA_ISSUES`: the file, the check, the dofs and the measure up to its documented
    size) is not a warning: the user cannot act on it; ``mfm info`` reports it
    (:func:`known_data_issues`). A larger measure, another pair or another file still warns.
    """
    if "added_mass_inf" not in db:
        raise ValueError(
            "the hydro database has no 'added_mass_inf' (A_inf, required for the Cummins equation). "
            "Get it from capytaine by solving the radiation problems at omega=numpy.inf as well "
            "(then hydro.database.from_capytaine), or from WAMIT by including period 0 in the run "
            "(rows with period 0 in the .1 file).")
    for name, dims in REQUIRED.items():
        if name not in db:
            raise ValueError(f"the hydro database has no variable {name!r} (dims {dims}); "
                             f"required variables: {sorted(REQUIRED)}.")
    for name, dims in {**REQUIRED, **OPTIONAL}.items():
        if name in db and tuple(db[name].dims) != dims:
            raise ValueError(f"variable {name!r} has dims {tuple(db[name].dims)}; expected {dims} "
                             f"(transpose it, e.g. db[{name!r}].transpose(*{dims})).")
    for a in REQUIRED_ATTRS:
        if a not in db.attrs:
            raise ValueError(f"the hydro database has no attribute {a!r}; required: {REQUIRED_ATTRS}.")
    check_values(db, source)
    if db.attrs.get("convention", CONVENTION) != CONVENTION:
        raise ValueError(f"attribute convention = {db.attrs['convention']!r}; the database must use "
                         f"{CONVENTION!r} (conjugate the complex amplitudes at the reader).")
    om = np.asarray(db["omega"].values, dtype=float)
    body_names = [str(b) for b in db["body"].values]
    expected = dof_labels(body_names)
    for dim in MATRIX_DIMS:
        got = [str(d) for d in db[dim].values]
        if got != expected:
            raise ValueError(f"coordinate {dim} = {got} does not match the bodies {body_names}: "
                             f"expected {expected}.")
    if list(db["axis"].values) != list(AXES):
        raise ValueError(f"coordinate axis = {list(db['axis'].values)}; expected {list(AXES)}.")
    if not np.iscomplexobj(db["excitation"].values):
        raise ValueError("variable 'excitation' must be complex; if it was read from NetCDF with a "
                         "'complex' dim, open it with hydro.database.open_database.")
    if "mean_drift" in db and np.iscomplexobj(db["mean_drift"].values):
        raise ValueError("variable 'mean_drift' must be real (the mean force per unit amplitude "
                         "squared, N/m^2); a complex one is a transfer function of two headings "
                         "or frequencies (a QTF): keep its real part at beta_1 = beta_2 only if "
                         "its imaginary part is round-off.")
    _check_kochin(db, source)
    if bodies is not None:
        _check_bodies(db, [bodies] if isinstance(bodies, str) else list(bodies))
    _check_finite(db, om)

    if not warn:
        return db
    labels = expected
    found = [_asymmetry(name, np.asarray(db[name].values, dtype=float), labels, om, sym_rtol)
             for name in ("added_mass", "radiation_damping", "added_mass_inf")]
    found.append(_negative_damping(np.asarray(db["radiation_damping"].values, dtype=float),
                                   labels, om, damping_noise))
    _give_warnings([f for f in found if f is not None], db, source)
    return db


def _check_kochin(db: xr.Dataset, source=None) -> None:
    """The Kochin functions, when present: both, complex, finite, on directions θ_i = 2π i/N
    (the far-field integrals are periodic trapezoid sums on that grid)."""
    have = [v for v in ("kochin_diffraction", "kochin_radiation") if v in db]
    if not have:
        return
    where = _where(source)
    if len(have) != 2:
        raise ValueError(f"{where}has {have[0]!r} without "
                         f"{({'kochin_diffraction', 'kochin_radiation'} - set(have)).pop()!r}: the "
                         "far-field drift needs both (regenerate with [hydro.bem] drift = "
                         "\"kochin\")")
    for v in have:
        if not np.iscomplexobj(db[v].values):
            raise ValueError(f"{where}variable {v!r} must be complex; if it was read from NetCDF "
                             "with a 'complex' dim, open it with hydro.database.open_database.")
        if not np.isfinite(db[v].values).all():
            raise ValueError(f"{where}variable {v!r} has non-finite values")
    th = np.asarray(db["theta"].values, dtype=float)
    n = th.size
    if n < 8 or not np.allclose(th, 2 * np.pi * np.arange(n) / n, rtol=0, atol=1e-9):
        raise ValueError(f"{where}coordinate theta ({n} values from {th[:1].tolist()} to "
                         f"{th[-1:].tolist()}) must be the uniform directions 2π i/N, i = 0…N−1, "
                         "N ≥ 8 (the far-field integrals are periodic trapezoid sums)")


def _where(source) -> str:
    return f"hydro database {str(source)!r}: " if source is not None else "hydro database: "


def _magnitude_hint(value, typical) -> str:
    """' (… off by 10?)' where `value` is `typical` times a power of ten (10, 10³ …), else ''."""
    if not (np.isfinite(value) and value > 0):
        return ""
    e = np.log10(value / typical)
    k = int(np.round(e))
    if k != 0 and abs(e - k) < 0.05:
        return f": {value:g} is {typical:g} × 10^{k}, a unit slip"
    return ""


def check_values(db: xr.Dataset, source=None) -> None:
    """The values every database must have, whatever reader made it (run by :func:`validate`,
    which :func:`hydro.prepare.open_any_database` runs on every file it reads: the project's
    NetCDF, capytaine's, NEMOH, WAMIT). Each error names the file (`source`), the variable, the
    value and what is accepted:

    - attributes ``rho`` within :data:`RHO_RANGE` kg/m³ and ``g`` within :data:`G_RANGE` m/s²
      (ρ < 0, ρ 1.025 in t/m³, g 0.981: a slip by 10 or 10³ is named as one); ``water_depth`` > 0
      or inf;
    - coordinate ``omega``: finite, > 0, strictly ascending (labels out of order put every
      coefficient at another frequency); ``wave_direction``: finite, radians within [−2π, 2π]
      (headings in degrees are refused);
    - ``displaced_volume`` finite and >= 0 per body (a thin plate has 0); the heave water-plane
      stiffness C33 >= 0 per body (ρ g A_wp: negative means inverted normals or a sign slip).
    """
    where = _where(source)
    for name, (lo, hi), unit, typical, fix in (
            ("rho", RHO_RANGE, "kg/m³", 1025.0, "1025 for sea water, 1000 for fresh water"),
            ("g", G_RANGE, "m/s²", 9.81, "9.81")):
        if name not in db.attrs:
            continue
        try:
            v = float(db.attrs[name])
        except (TypeError, ValueError):
            raise ValueError(f"{where}attribute {name} = {db.attrs[name]!r} is not a number; "
                             f"accepted: {lo:g}–{hi:g} {unit} ({fix})") from None
        if not (np.isfinite(v) and lo <= v <= hi):
            hint = _magnitude_hint(v, typical) or _magnitude_hint(v, 1000.0 if name == "rho" else 9.81)
            raise ValueError(
                f"{where}attribute {name} = {v!r} {unit}; accepted: {lo:g}–{hi:g} {unit} ({fix})"
                f"{hint}. The coefficients of a BEM database are computed with its {name}: fix the "
                f"value where it came from (the file's attribute, or hydro.{name} / {name}= for a "
                "WAMIT run, whose data are scaled by it) or regenerate the database.")
    if "water_depth" in db.attrs:
        try:
            h = float(db.attrs["water_depth"])
        except (TypeError, ValueError):
            h = float("nan")
        if not h > 0:
            raise ValueError(f"{where}attribute water_depth = {db.attrs['water_depth']!r} m; "
                             "accepted: > 0 m, or inf for deep water")
    if "omega" in db.coords:
        om = np.asarray(db["omega"].values, dtype=float)
        bad = ~np.isfinite(om) | (om <= 0)
        if bad.any():
            k = int(np.argmax(bad))
            raise ValueError(f"{where}coordinate omega[{k}] = {float(om[k])!r} rad/s; accepted: finite "
                             "frequencies > 0 rad/s (omega = 0 and inf belong in added_mass_zero "
                             "and added_mass_inf)")
        d = np.diff(om)
        if np.any(d <= 0):
            k = int(np.argmax(d <= 0))
            raise ValueError(
                f"{where}coordinate omega is not strictly ascending: omega[{k}] = {float(om[k])!r}, "
                f"omega[{k + 1}] = {float(om[k + 1])!r} rad/s; accepted: distinct frequencies in "
                "ascending order. Labels out of order put the coefficients at other frequencies: "
                "regenerate the database (or, if only the order is wrong and every label is right, "
                "db.sortby('omega'))")
    if "wave_direction" in db.coords:
        beta = np.atleast_1d(np.asarray(db["wave_direction"].values, dtype=float))
        bad = ~np.isfinite(beta) | (np.abs(beta) > 2 * np.pi * (1 + 1e-9))
        if bad.any():
            k = int(np.argmax(bad))
            raise ValueError(
                f"{where}coordinate wave_direction[{k}] = {float(beta[k])!r} rad; accepted: headings in "
                f"radians within [−2π, 2π]. Degrees? Convert them: numpy.deg2rad ({float(beta[k])!r}° = "
                f"{np.deg2rad(beta[k]):.6g} rad)")
    if "displaced_volume" in db:
        vol = np.atleast_1d(np.asarray(db["displaced_volume"].values, dtype=float))
        names = [str(b) for b in db["body"].values] if "body" in db.coords else list(range(len(vol)))
        bad = ~np.isfinite(vol) | (vol < 0)
        if bad.any():
            k = int(np.argmax(bad))
            raise ValueError(
                f"{where}displaced_volume of body {names[k]!r} = {float(vol[k])!r} m³; accepted: a finite "
                "volume >= 0 m³ (the hull's submerged volume; a negative one is a mesh with inward "
                "normals or a sign slip): fix the mesh and regenerate the database")
    if "waterplane_stiffness" in db and db["waterplane_stiffness"].ndim == 2:
        W = np.asarray(db["waterplane_stiffness"].values, dtype=float)
        labels = [str(x) for x in db["influenced_dof"].values] if "influenced_dof" in db.coords else None
        for i in range(2, W.shape[0], 6):
            if np.isfinite(W[i, i]) and W[i, i] < 0:
                lab = labels[i] if labels else i
                raise ValueError(
                    f"{where}waterplane_stiffness[{lab}, {lab}] = {float(W[i, i])!r} N/m; accepted: >= 0 "
                    "(ρ g times the water-plane area): a negative heave stiffness is a mesh with "
                    "inward normals or a sign slip: fix the source and regenerate the database")


# The data issues of the shipped databases that the checks above find, documented (with why they
# are not fixed) in hydro/data/README.md, "Known warnings": file (relative to hydro/data) ->
# {(variable, dof_i, dof_j): the measure as measured, rounded up}. Only these (the same file,
# variable and dofs, a measure no larger) are kept from the warnings; mfm info reports them.
KNOWN_DATA_ISSUES = {
    # RM3's WAMIT files (not ours: NREL/Sandia's run; no geometry or mesh to re-solve here):
    # asymmetry of the float's sway-roll coupling (and the spar-float roll-sway in B). HydroSpec
    # symmetrises A, B, A∞ (reciprocity) before any use; RM3 runs in head seas (y-plane modes)
    "rm3/rm3.out": {("added_mass", "float__Sway", "float__Roll"): 0.17,
                    ("radiation_damping", "spar__Roll", "float__Sway"): 0.5,
                    ("added_mass_inf", "float__Sway", "float__Roll"): 0.16},
    # M4 134 (ours, capytaine dx = 0.03 m with lids): an irregular frequency the lid does not
    # remove, at 19.25 rad/s, 2.5x the highest peak frequency of the seed's seas (Tp >= 0.8 s);
    # fixing it needs a BEM re-solve (a finer lid), ~hours on 2 cores
    "m4_134.nc": {("negative_damping", "float7__Heave", "float7__Heave"): 0.022},
    # its sensitivity variant (rows 0.80 m apart; the same hulls, mesh and lid): the same irregular
    # frequency, at 19 rad/s, -0.021 of the peak (issue 35 item 3)
    "sensitivity/m4_134_spacing080.nc": {("negative_damping", "float7__Heave", "float7__Heave"): 0.022},
    # the Wu & Yuan databases (ours, capytaine): the WEC's surge-pitch / sway-roll damping
    # coupling at 1.257 rad/s, unconverged at the mesh used (the symmetric part is what every
    # computation uses); a finer mesh is a BEM re-solve of the 12-WEC platform, ~hours
    "wu_yuan_m1.nc": {("radiation_damping", "wec2__Surge", "wec2__Pitch"): 0.12},
    "wu_yuan_m1_drift.nc": {("radiation_damping", "wec2__Surge", "wec2__Pitch"): 0.12},
    "wu_yuan_m1_td.nc": {("radiation_damping", "wec6__Surge", "wec6__Pitch"): 0.06},
    "wu_yuan_m2.nc": {("radiation_damping", "wec11__Sway", "wec11__Roll"): 0.12},
    "wu_yuan_m3.nc": {("radiation_damping", "wec6__Sway", "wec6__Roll"): 0.12},
    "wu_yuan_m4.nc": {("radiation_damping", "wec6__Sway", "wec6__Roll"): 0.12},
    "wu_yuan_m5.nc": {("radiation_damping", "wec3__Surge", "wec3__Pitch"): 0.12},
    # the lone WEC over its band (0.2-2.5 rad/s): the same WEC's coupling, largest at 1.8 rad/s
    # against the band's damping peaks (0.0551; 0.022 at 1.257 rad/s)
    "wu_yuan_wec.nc": {("radiation_damping", "wec__Surge", "wec__Pitch"): 0.06},
}
_SHIPPED = Path(__file__).resolve().parent / "data"
_WARNED: set = set()          # (database, message): each warning once per database per process


def _shipped_name(source):
    """`source`'s path relative to hydro/data, or None for a file elsewhere (or none)."""
    if source is None:
        return None
    try:
        return Path(source).resolve().relative_to(_SHIPPED).as_posix()
    except ValueError:
        return None


def known_data_issues(source) -> list[str]:
    """The documented data issues of the database file `source` (none for a file that is not
    shipped): one line each, for ``mfm info``."""
    name = _shipped_name(source)
    return [(f"radiation_damping of {i} negative, down to -{size:g} of its peak" if
             var == "negative_damping" else
             f"{var} asymmetric at ({i}, {j}): |M_ij - M_ji|/sqrt(d_i d_j) up to {size:g}")
            + " (hydro/data/README.md, Known warnings)"
            for (var, i, j), size in KNOWN_DATA_ISSUES.get(name, {}).items()]


def _give_warnings(found, db, source):
    # a pair in either order (argmax of a symmetric measure takes (i, j) or (j, i) by dof order)
    known = {(var, *sorted(ij)): size for (var, *ij), size
             in KNOWN_DATA_ISSUES.get(_shipped_name(source), {}).items()}
    if source is not None:
        key = str(Path(source).resolve())
    else:
        import hashlib

        h = hashlib.sha1()
        for name in ("added_mass", "radiation_damping", "added_mass_inf"):
            h.update(np.ascontiguousarray(db[name].values, dtype=float).tobytes())
        key = h.hexdigest()
    for (var, i, j), size, message in found:
        if size <= known.get((var, *sorted((i, j))), -1.0) or (key, message) in _WARNED:
            continue
        _WARNED.add((key, message))
        warnings.warn(message, HydroDatabaseWarning, stacklevel=3)   # validate's caller


def _check_finite(db, om):
    """NaN or inf in a coefficient would surface later as a LinAlgError or NaN motions deep in
    jax; name the variable and the first bad entry here instead."""
    for name in (*REQUIRED, *OPTIONAL):
        if name not in db:
            continue
        da = db[name]
        vals = np.asarray(da.values)
        bad = ~np.isfinite(vals)
        if not bad.any():
            continue
        first = np.unravel_index(int(np.argmax(bad)), vals.shape)
        where = []
        for dim, i in zip(da.dims, first):
            label = db[dim].values[i] if dim in db.coords else i
            if dim == "omega":
                where.append(f"omega = {float(label):.6g} rad/s")
            elif dim == "wave_direction":
                where.append(f"wave_direction = {float(label):.6g} rad")
            else:
                where.append(f"{dim} = {str(label)!r}")
        fix = ("regenerate the database (a BEM problem that failed leaves NaN) or fix the file "
               "it was read from")
        if da.dims and da.dims[0] == "omega":
            fix += f", or drop that frequency: db.sel(omega=db.omega != {float(om[first[0]])!r})"
        raise ValueError(
            f"hydro database variable {name!r} has {int(bad.sum())} non-finite value(s) (NaN or "
            f"inf); the first is {vals[first]!r} at {', '.join(where) or 'its only entry'}. Every "
            f"coefficient must be finite: {fix}.")


def _asymmetry(name, M, labels, om, rtol):
    """The largest asymmetry of `M` above `rtol` as ((name, dof_i, dof_j), size, message), or None."""
    M3 = M if M.ndim == 3 else M[None]
    d = np.abs(np.diagonal(M3, axis1=1, axis2=2)).max(axis=0)
    d = np.maximum(d, 1e-12 * max(d.max(), 1e-300))          # keeps zero diagonals (e.g. yaw) finite
    asym = np.abs(M3 - np.swapaxes(M3, 1, 2)) / np.sqrt(np.outer(d, d))[None]
    k, i, j = np.unravel_index(np.argmax(asym), asym.shape)
    if asym[k, i, j] > rtol:
        where = f" at omega = {om[k]:.4g} rad/s" if M.ndim == 3 else ""
        return ((name, labels[i], labels[j]), float(asym[k, i, j]),
            f"{name} is not symmetric: largest |M_ij - M_ji|/sqrt(d_i d_j) = {asym[k, i, j]:.3g} > "
            f"{rtol:g} for ({labels[i]}, {labels[j]}){where}: M_ij = {M3[k, i, j]:.6g}, "
            f"M_ji = {M3[k, j, i]:.6g}. The BEM data may be unconverged there (every computation "
            "uses the symmetric part).")
    return None


def _negative_damping(B, labels, om, noise):
    """The most negative damping beyond `noise` as (("negative_damping", dof, dof), −its fraction
    of the peak, message), or None; the message also names every other dof negative beyond it,
    with its worst value (the RM3 hulls revolved by tools/rm3_bem_mesh.py: the float's heave was
    named, the spar's pitch, as far off, was not)."""
    diag = np.diagonal(B, axis1=1, axis2=2)                  # (omega, dof)
    peak = np.abs(diag).max(axis=0)
    # a dof whose damping is negligible beside the others of its kind (translation / rotation),
    # e.g. yaw of an axisymmetric body (≈ 1e-10 of roll), is pure noise: not checked
    rot = (np.arange(len(peak)) % 6) >= 3
    kind_max = np.where(rot, peak[rot].max(initial=0.0), peak[~rot].max(initial=0.0))
    peak = np.where(peak > 1e-6 * kind_max, peak, 0.0)
    bad = diag < -noise * peak[None]
    if np.any(bad & (peak[None] > 0)):
        rel = np.where(peak > 0, diag / np.where(peak > 0, peak, 1.0), 0.0)
        k, i = np.unravel_index(np.argmin(rel), rel.shape)
        return (("negative_damping", labels[i], labels[i]), float(-rel[k, i]),
            f"radiation_damping diagonal is negative beyond the noise tolerance {noise:g} of its "
            f"peak: B[{labels[i]}] = {diag[k, i]:.4g} at omega = {om[k]:.4g} rad/s "
            f"({rel[k, i]:.3g} of its peak {peak[i]:.4g}).{_also_negative(diag, rel, bad, peak, i, labels, om)} "
            "Irregular frequency or unconverged mesh? Use a lid / finer mesh, or taper the "
            "damping before the impulse response.")
    return None


def _also_negative(diag, rel, bad, peak, worst, labels, om) -> str:
    """' Also negative: B[dof] = … at omega = … (… of its peak), …' for every dof but ``worst``
    with a negative damping beyond the noise (each at its most negative), or ''."""
    parts = []
    for i in range(diag.shape[1]):
        if i == worst or peak[i] <= 0 or not bad[:, i].any():
            continue
        k = int(np.argmin(rel[:, i]))
        parts.append(f"B[{labels[i]}] = {diag[k, i]:.4g} at omega = {om[k]:.4g} rad/s "
                     f"({rel[k, i]:.3g} of its peak)")
    return f" Also negative: {'; '.join(parts)}." if parts else ""


# ------------------------------------------------------------------------------------ NetCDF I/O
def split_complex(ds: xr.Dataset) -> xr.Dataset:
    """Complex variables -> real with a trailing ``complex`` dim ["re", "im"]."""
    out = ds.copy()
    for name in list(out.data_vars):
        da = out[name]
        if np.iscomplexobj(da.values):
            out[name] = xr.DataArray(np.stack([da.values.real, da.values.imag], axis=-1),
                                     dims=da.dims + ("complex",), attrs=da.attrs)
    if any("complex" in out[v].dims for v in out.data_vars):
        out = out.assign_coords(complex=["re", "im"])
    return out


def merge_complex(ds: xr.Dataset) -> xr.Dataset:
    """Inverse of :func:`split_complex`; also accepts capytaine's leading ``complex`` dim."""
    if "complex" not in ds.dims:
        return ds
    out = ds.copy()
    for name in list(out.data_vars):
        da = out[name]
        if "complex" in da.dims:
            dims = tuple(d for d in da.dims if d != "complex")
            val = da.sel(complex="re").transpose(*dims).values + 1j * da.sel(complex="im").transpose(*dims).values
            out[name] = xr.DataArray(val, dims=dims, attrs=da.attrs)
    return out.drop_vars("complex")


# Every NetCDF file of the project is read whole by :func:`read_netcdf` and written by
# :func:`write_netcdf`, never with a bare ``xr.open_dataset(path)`` / ``ds.to_netcdf(path)``:
#
# - the netCDF-C 4.10 / HDF5 2.2 libraries of the netCDF4 wheel crash (segmentation fault) when a
#   file that is already open in the process (a user's ``xr.open_dataset`` in a notebook) is opened
#   a second time, read, closed, and opened a third time: HDF5 shares one file object between the
#   handles of one path, and the close of the second handle leaves it in a state the third open
#   dereferences. Reading the bytes with Python and decoding them from memory never gives HDF5 a
#   second handle on the path, however many times the file is read;
# - HDF5 locks and truncates a file it opens for writing: writing over a result that a reader holds
#   open fails ("Permission denied") after the truncation has destroyed it. A temporary file in the
#   same directory, renamed over the path (atomic on POSIX), leaves the reader its old file and
#   every later reader the complete new one.


def read_netcdf(path, group: str | None = None) -> xr.Dataset:
    """The NetCDF file at `path` (or its ``group``, a path such as ``"mfm_fits/k…"``) as an
    in-memory ``xarray.Dataset`` (no file left open): its bytes read with Python and decoded from
    memory, so the HDF5 library never opens the path (see the note above: a second HDF5 handle on
    a file the process holds open can crash it)."""
    path = Path(path)
    data = path.read_bytes()
    try:
        with xr.open_dataset(data, engine="netcdf4", group=group) as ds:
            return ds.load()
    except (OSError, ValueError) as e:
        raise ValueError(f"{str(path)!r} is not a readable NetCDF file ({e})") from None


def read_netcdf_attrs(path) -> dict:
    """The global attributes of the NetCDF file at `path`, its variables left undecoded (read from
    memory as :func:`read_netcdf`, so no HDF5 handle on the path)."""
    path = Path(path)
    data = path.read_bytes()
    try:
        with xr.open_dataset(data, engine="netcdf4") as ds:
            return dict(ds.attrs)
    except (OSError, ValueError) as e:
        raise ValueError(f"{str(path)!r} is not a readable NetCDF file ({e})") from None


def write_netcdf(ds: xr.Dataset, path, **kwargs) -> Path:
    """``ds.to_netcdf`` atomically: written to a temporary file beside `path`, then renamed over it
    (a reader holding the old file keeps it; nobody ever sees a half-written one). `kwargs` go to
    ``Dataset.to_netcdf`` (e.g. ``encoding``)."""
    import os

    path = Path(path)
    tmp = path.with_name(f".{path.name}.tmp{os.getpid()}")
    try:
        ds.to_netcdf(tmp, **kwargs)
        os.replace(tmp, path)
    finally:
        if tmp.exists():
            tmp.unlink()
    return path


def to_netcdf(db: xr.Dataset, path) -> Path:
    """Write `db` to NetCDF at `path` (complex values split into a trailing ``complex`` dim),
    atomically (:func:`write_netcdf`)."""
    path = Path(path)
    ds = split_complex(db)
    for c in ("body", "influenced_dof", "radiating_dof", "axis"):
        if c in ds.coords:
            ds = ds.assign_coords({c: np.asarray(ds[c].values).astype(str)})
    ds.attrs = {k: (str(v) if isinstance(v, (bool, type(None))) else v) for k, v in ds.attrs.items()}
    write_netcdf(ds, path)
    return path


def open_database(path) -> xr.Dataset:
    """Read a database written by :func:`to_netcdf` (loaded into memory, complex rejoined)."""
    return _ours(read_netcdf(path))


def _ours(ds: xr.Dataset) -> xr.Dataset:
    """A dataset of :func:`to_netcdf` as read from the file → the database (complex rejoined)."""
    ds = merge_complex(ds)
    for c in ("body", "influenced_dof", "radiating_dof", "axis"):
        if c in ds.coords:
            ds = ds.assign_coords({c: np.asarray(ds[c].values).astype(str)})
    return ds


# ---------------------------------------------------------------------------------- capytaine
def from_capytaine(ds: xr.Dataset, body_names=None, *, source=None) -> xr.Dataset:
    """Convert a capytaine 3 dataset to the internal schema.

    `ds` as produced by capytaine's ``BEMSolver.fill_dataset`` / ``cpt.assemble_dataset``, or read
    from a ``cpt.export_dataset`` NetCDF (the split ``complex`` dim is rejoined here). Steps:
    transpose to (omega, influenced_dof, radiating_dof); omega = inf → ``added_mass_inf``, omega = 0
    → ``added_mass_zero``; ``excitation = Froude_Krylov_force + diffraction_force``; the rotation
    centres → ``reference_point``; ``mean_drift`` and the Kochin functions
    (``hydro.bem.solve(drift=…)``) carried;
    ``displaced_volume``, ``center_of_buoyancy``,
    ``waterplane_stiffness``, ``hydrostatic_stiffness`` are carried when present (the project's BEM
    generator ``mfm hydro`` writes them with the schema names). A single body's bare dof names
    ("Heave") get the body name (capytaine's ``body`` coordinate, else `body_names`, else "body0").
    The finite ω > 0 must be strictly ascending as capytaine writes them (ω = 0 and ∞ anywhere):
    labels out of order are refused, naming `source` (the file), not sorted into wrong places.
    """
    ds = merge_complex(ds)
    freq_dim = next((d for d in ("omega", "freq", "period", "wavenumber", "wavelength")
                     if d in ds.dims), None)
    if freq_dim is None:
        raise ValueError(f"the capytaine dataset has no frequency dimension; dims: {dict(ds.sizes)}")
    if freq_dim != "omega":
        ds = ds.swap_dims({freq_dim: "omega"})
    for name in ("added_mass", "radiation_damping"):
        if name not in ds:
            raise ValueError(f"the capytaine dataset has no {name!r}: solve the radiation problems.")
    if "waterplane_stiffness" not in ds:
        raise ValueError("the capytaine dataset has no 'waterplane_stiffness' (the linear water-plane "
                         "part of the hydrostatics, which mfm needs): regenerate the database with "
                         "`mfm hydro`, which adds it.")

    # body names and dof labels
    dofs_in = [str(d) for d in ds["influenced_dof"].values]
    if all(_SEP in d for d in dofs_in):
        names = list(dict.fromkeys(d.split(_SEP)[0] for d in dofs_in))
        if body_names is not None:
            raise ValueError("body_names is only for single-body capytaine datasets whose dofs have "
                             f"no body prefix; this one has bodies {names}.")
        rename = {d: d for d in dofs_in}
    else:
        if body_names is not None:
            names = [body_names] if isinstance(body_names, str) else list(body_names)
        elif "body" in ds.coords and ds["body"].ndim == 0:
            names = [str(ds["body"].values)]
        else:
            names = ["body0"]
        if len(names) != 1:
            raise ValueError(f"body_names={body_names!r}: a single-body dataset needs one name.")
        rename = {d: f"{names[0]}{_SEP}{d}" for d in dofs_in}
    labels = dof_labels(names)
    have = set(rename.values())
    missing = [d for d in labels if d not in have]
    if missing:
        raise ValueError(f"the capytaine dataset lacks the dofs {missing}; the schema needs all 6 rigid "
                         "modes per body: build the bodies with cpt.rigid_body_dofs(rotation_center=…).")

    def mat(da):
        da = da.assign_coords(influenced_dof=[rename[str(d)] for d in da["influenced_dof"].values],
                              radiating_dof=[rename[str(d)] for d in da["radiating_dof"].values])
        dims = ("omega",) * ("omega" in da.dims) + MATRIX_DIMS
        return da.sel(influenced_dof=labels, radiating_dof=labels).transpose(*dims)

    def vec(da):
        da = da.assign_coords(influenced_dof=[rename[str(d)] for d in da["influenced_dof"].values])
        return da.sel(influenced_dof=labels).transpose("omega", "wave_direction", "influenced_dof")

    om = np.asarray(ds["omega"].values, dtype=float)
    finite = np.isfinite(om) & (om > 0)
    if not np.any(np.isinf(om)):
        raise ValueError("the capytaine dataset has no omega = inf: add numpy.inf to the omega values "
                         "of the radiation problems to get added_mass_inf (required).")
    d = np.diff(om[finite])
    if np.any(d <= 0):
        k = int(np.argmax(d <= 0))
        raise ValueError(
            f"{_where(source)}the finite omega are not strictly ascending: {float(om[finite][k])!r} then "
            f"{float(om[finite][k + 1])!r} rad/s (values {om.tolist()[:8]}…); accepted: distinct "
            "frequencies in ascending order, as capytaine writes them (0 and inf anywhere). Labels "
            "out of order put the coefficients at other frequencies: regenerate the database")
    order = np.argsort(om[finite])
    ofin = om[finite][order]

    def freq(da):
        return da.isel(omega=np.flatnonzero(finite)[order]).assign_coords(omega=ofin)

    out = xr.Dataset(coords={"omega": ofin, "body": names, "influenced_dof": labels,
                             "radiating_dof": labels, "axis": list(AXES)})
    drop = [c for c in ("freq", "period", "wavenumber", "wavelength", "g", "rho", "water_depth",
                        "forward_speed", "body", "space_coordinate", "rotation_center")]
    A = mat(ds["added_mass"]).drop_vars(drop, errors="ignore")
    B = mat(ds["radiation_damping"]).drop_vars(drop, errors="ignore")
    out["added_mass"] = freq(A).astype(float)
    out["radiation_damping"] = freq(B).astype(float)
    out["added_mass_inf"] = A.isel(omega=int(np.flatnonzero(np.isinf(om))[0])).drop_vars("omega").astype(float)
    if np.any(om == 0):
        out["added_mass_zero"] = A.isel(omega=int(np.flatnonzero(om == 0)[0])).drop_vars("omega").astype(float)
    if "Froude_Krylov_force" in ds and "diffraction_force" in ds:
        fk = freq(vec(ds["Froude_Krylov_force"]).drop_vars(drop, errors="ignore")).astype(complex)
        df = freq(vec(ds["diffraction_force"]).drop_vars(drop, errors="ignore")).astype(complex)
        out["froude_krylov"], out["diffraction"] = fk, df
        out["excitation"] = fk + df
    if "mean_drift" in ds:
        out["mean_drift"] = freq(vec(ds["mean_drift"]).drop_vars(drop, errors="ignore")).astype(float)
        out["mean_drift"].attrs.update(ds["mean_drift"].attrs)
    if "kochin_diffraction" in ds and "kochin_radiation" in ds:
        out = out.assign_coords(theta=("theta", np.asarray(ds["theta"].values, float),
                                       dict(ds["theta"].attrs)))
        kd = ds["kochin_diffraction"].drop_vars(drop, errors="ignore")
        out["kochin_diffraction"] = freq(kd.transpose("omega", "wave_direction", "theta")
                                         ).astype(complex)
        kr = ds["kochin_radiation"].drop_vars(drop, errors="ignore")
        kr = kr.assign_coords(radiating_dof=[rename[str(d)] for d in kr["radiating_dof"].values])
        out["kochin_radiation"] = freq(kr.sel(radiating_dof=labels).transpose(
            "omega", "radiating_dof", "theta")).astype(complex)
        for v in ("kochin_diffraction", "kochin_radiation"):
            out[v].attrs.update(ds[v].attrs)
    for name in ("waterplane_stiffness", "hydrostatic_stiffness"):
        if name in ds:
            out[name] = mat(ds[name]).drop_vars(drop, errors="ignore").astype(float)
            out[name].attrs.update(ds[name].attrs)
    for name in ("displaced_volume", "center_of_buoyancy", "reference_point"):
        if name in ds:
            da = ds[name]
            if "body" not in da.dims:
                if len(names) != 1:
                    continue
                da = da.drop_vars("body", errors="ignore").expand_dims(body=names)
            if "space_coordinate" in da.dims:
                da = da.rename(space_coordinate="axis")
            out[name] = da.drop_vars([c for c in da.coords if c not in da.dims]).assign_coords(
                body=names, **({"axis": list(AXES)} if "axis" in da.dims else {}))
    if "reference_point" not in out and "rotation_center" in ds.coords:
        rc = np.asarray(ds["rotation_center"].values, dtype=float).reshape(len(names), 3)
        out["reference_point"] = (("body", "axis"), rc)

    attrs = {k: v for k, v in ds.attrs.items() if isinstance(v, (str, int, float, np.number))}
    for a in ("rho", "g", "water_depth"):
        if a in ds.coords and ds[a].size == 1:
            attrs[a] = float(ds[a].values)
    attrs.update(convention=CONVENTION, source=attrs.get("source", "capytaine"))
    out.attrs = attrs
    return out
