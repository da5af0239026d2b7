"""``mfm hydro CONFIG``: the hydro database of a config, generated with capytaine from the hulls
described in the config itself.

A config describes each wet body's hull in a ``[bodies.geometry]`` table (the body spec of
:mod:`hydro.geometry` without ``name``, which is the body's name)::

    [[bodies]]
    name = "float1"
    com = [0.0, 0.0, -0.0634]
    ...
    [bodies.geometry]
    shape = "cylinder"          # cylinder | sphere | hemisphere | revolution | mesh
    radius = 0.10               # m
    draft = 0.0746              # m
    base = "flat"               # flat | hemisphere | rounded (+ knuckle_radius)
    # origin = [x, y, 0]        # default [com_x, com_y, 0]: the axis under the CoM
    # reference_point = [x, y, z]   # default: the body's CoM at q = 0
    # profile = [[8, 0], [8, -18.67], [16, -18.67], [16, -26.67], [0, -26.67]]
    #                           # shape "revolution": the meridian (r, z) from the water line
    #                           #   down to the keel on the axis (stepped columns, heave plates)
    # file = "hull.stl"         # shape "mesh": relative to the config
    # dx = 0.5                  # this body's panel size (m), in place of [hydro.bem] dx

and the BEM settings in ``[hydro.bem]`` (every key checked, unknown keys are errors)::

    [hydro]
    database = "../hydro/data/m4_111.nc"   # where `mfm hydro` writes (relative to the config)
    [hydro.bem]
    omega_min = 0.25            # rad/s  } a linear grid of n_omega frequencies, or instead
    omega_max = 25.0            # rad/s  }
    n_omega = 100               #        }
    # omega = [0.5, 1.0, 2.0]   # an explicit list (rad/s)
    headings_deg = [0.0]        # wave headings, degrees (0 = waves travelling to +x); default [0]
    water_depth = 1.0           # m, or "inf"; default "inf"
    dx = 0.03                   # panel size, m (required)
    lid = true                  # water-plane lid against irregular frequencies; default true
    symmetry = "auto"           # auto | xOz | rotation | none; default auto
    infinite_frequency = true   # also ω = ∞ (A∞, which mfm.load needs); default true
    deep_water_kh = 5.0         # finite depth only where k h < 5, deep water above (and ∞):
                                #   ≈ 3× faster; default: the finite depth everywhere
    rho = 1000.0                # kg/m³; default [hydro] rho, else 1000
    g = 9.81                    # m/s²; default [hydro] g, else [model] gravity
    equilibrium_check = true    # refuse a hull that cannot float its body (below); default true
    drift = "free"              # also the far-field mean drift (database variable mean_drift) of
                                #   the one wet body: "fixed" (held) or "free" (freely floating
                                #   with its config mass, com, inertia); or "kochin": the layout's
                                #   Kochin functions (any number of bodies), from which the drift
                                #   of the model's own motions is made where it is asked for
                                #   (mfm.frequency.drift); default: none
    notes = "..."               # free text

Before any solve, ``mfm hydro`` checks each mesh hull (:func:`check_hulls`): closed below the water
line with outward normals, no panel centre on another panel, a lid when ``lid = true`` (every
refusal names the edges or panels), the lowest frequency against what capytaine's finite-depth
Green function accepts (``hydro.bem.check_finite_depth``), and that a mesh body free in heave
floats at the draft its ``origin`` gives (ρV against its mass, the centre of buoyancy against
its centre of mass).

Bodies without a ``geometry`` table are dry (not in the database). The reference point of each
body's 6 modes defaults to its CoM at q = 0: the MFM applies loads about the CoM, and
:mod:`mfm.loads.water` maps any reference point anyway.

The file is written atomically (a temporary file, checked by loading it the way ``mfm.load``
does, then renamed), so a failed or interrupted run never leaves a partial database.
"""
from __future__ import annotations

import hashlib
import json
import math
import numbers
import os
import re
import time
import tomllib
from pathlib import Path

import numpy as np

from .config import load_config, read_config
from ..errors import ConfigError

BEM_KEYS = {"omega_min", "omega_max", "n_omega", "omega", "headings_deg", "water_depth", "dx",
            "lid", "symmetry", "infinite_frequency", "rho", "g", "deep_water_kh", "notes",
            "equilibrium_check", "drift"}
DRIFTS = ("fixed", "free", "kochin")
GEOMETRY_KEYS = {"shape", "radius", "draft", "base", "knuckle_radius", "profile", "origin",
                 "reference_point", "file", "dx"}
SYMMETRIES = ("auto", "xOz", "rotation", "none")


# capytaine 3.0's finite-depth Green function fails for kh <= 0.1375 (measured; the source and
# the measurement are quoted at hydro.bem.KH_MIN); its own message says "kh<0.1", which let a run
# with kh 0.113 start and fail after 45 minutes
KH_MIN = 0.14
EQUILIBRIUM_VOLUME_TOL = 0.05   # |ρV − m| / m of a body free in heave
EQUILIBRIUM_HEEL_TOL_DEG = 1.0  # the heel (or trim) at rest of a free floater, degrees


class HullWarning(UserWarning):
    """A mesh hull that may be placed wrongly (not refused: the body need not float alone)."""

# ------------------------------------------------------------------------------------------------
# Settings


def _wavenumber(omega: float, depth: float, g: float) -> float:
    """k of ω² = g k tanh(k h) (Newton from the deep-water k)."""
    k = max(omega * omega / g, omega / math.sqrt(g * depth))
    for _ in range(50):
        t = math.tanh(k * depth)
        f = g * k * t - omega * omega
        df = g * t + g * k * depth * (1.0 - t * t)
        step = f / df
        k -= step
        if abs(step) < 1e-14 * k:
            break
    return k


def _num(v, where, *, positive=True, integer=False):
    if isinstance(v, bool) or not isinstance(v, numbers.Real) or not math.isfinite(v):
        raise ConfigError(f"{where}: {v!r} is not a finite number")
    if integer and int(v) != v:
        raise ConfigError(f"{where}: {v!r} is not a whole number")
    if positive and v <= 0:
        raise ConfigError(f"{where}: {v!r} must be > 0")
    return int(v) if integer else float(v)


def _bool(v, where):
    if not isinstance(v, bool):
        raise ConfigError(f"{where}: {v!r} is not true or false")
    return v


def bem_settings(raw: dict | None, *, hydro: dict | None = None, gravity: float = 9.81,
                 overrides: dict | None = None) -> dict:
    """Validate the ``[hydro.bem]`` table (plus ``overrides``) → the keyword arguments of
    ``hydro.bem.solve`` (omega in rad/s, wave_directions in rad, ...) and a JSON-able record
    of the settings as given (``"record"``)."""
    raw = dict(raw or {})
    if overrides:
        ov = dict(overrides)
        if "omega" in ov:
            for k in ("omega_min", "omega_max", "n_omega"):
                raw.pop(k, None)
        if any(k in ov for k in ("omega_min", "omega_max", "n_omega")):
            raw.pop("omega", None)
        bad = sorted(set(ov) - BEM_KEYS)
        if bad:
            raise ConfigError(f"overrides: unknown key(s) {bad}; accepted keys: {sorted(BEM_KEYS)}")
        raw.update(ov)
    bad = sorted(set(raw) - BEM_KEYS)
    if bad:
        raise ConfigError(f"hydro.bem: unknown key(s) {bad}; accepted keys: {sorted(BEM_KEYS)}")
    w = "hydro.bem"
    grid = [k for k in ("omega_min", "omega_max", "n_omega") if k in raw]
    if "omega" in raw:
        if grid:
            raise ConfigError(f"{w}: give either omega (a list, rad/s) or omega_min, omega_max, "
                              f"n_omega (a linear grid), not both; found omega and {grid}")
        om = raw["omega"]
        if not isinstance(om, list) or not om:
            raise ConfigError(f"{w}.omega: {om!r} is not a non-empty list of frequencies (rad/s)")
        omega = np.array([_num(v, f"{w}.omega[{i}]") for i, v in enumerate(om)])
        # a list typed by hand: a repeat or a step back is a typo (hydro.bem.solve would sort and
        # de-duplicate it silently, solving fewer frequencies than the list shows)
        for i in range(1, len(omega)):
            if omega[i] <= omega[i - 1]:
                what = "repeats" if omega[i] == omega[i - 1] else "is below"
                raise ConfigError(f"{w}.omega[{i}]: {omega[i]:g} rad/s {what} omega[{i - 1}] = "
                                  f"{omega[i - 1]:g}; accepted: strictly increasing frequencies "
                                  f"(rad/s). Remove the repeat or put the list in increasing order")
    else:
        if len(grid) != 3:
            missing = sorted({"omega_min", "omega_max", "n_omega"} - set(grid))
            raise ConfigError(f"{w}: missing {missing}; give omega_min, omega_max (rad/s) and "
                              f"n_omega for a linear grid, or omega = [...]")
        lo = _num(raw["omega_min"], f"{w}.omega_min")
        hi = _num(raw["omega_max"], f"{w}.omega_max")
        n = _num(raw["n_omega"], f"{w}.n_omega", integer=True)
        if hi < lo or (n > 1 and hi == lo):
            raise ConfigError(f"{w}.omega_max: {hi} must be > omega_min ({lo})")
        if n == 1 and hi != lo:
            # linspace(lo, hi, 1) is [lo]: omega_max would be dropped without a word
            raise ConfigError(f"{w}.n_omega: 1 with omega_min = {lo:g} and omega_max = {hi:g} "
                              f"rad/s solves omega_min only; accepted: n_omega >= 2 for a grid "
                              f"from omega_min to omega_max, or n_omega = 1 with omega_max = "
                              f"omega_min (one frequency; or omega = [{lo:g}])")
        omega = np.linspace(lo, hi, n)
    hd = raw.get("headings_deg", [0.0])
    if isinstance(hd, numbers.Real) and not isinstance(hd, bool):
        hd = [hd]
    if not isinstance(hd, list) or not hd:
        raise ConfigError(f"{w}.headings_deg: {hd!r} is not a non-empty list of headings (degrees)")
    headings = [_num(v, f"{w}.headings_deg[{i}]", positive=False) for i, v in enumerate(hd)]
    depth = raw.get("water_depth", "inf")
    if isinstance(depth, str):
        if depth.strip().lower() not in ("inf", "infinite", "infinity"):
            raise ConfigError(f"{w}.water_depth: {depth!r}; give a depth in m or \"inf\"")
        depth = math.inf
    else:
        depth = _num(depth, f"{w}.water_depth")
    if "dx" not in raw:
        raise ConfigError(f"{w}.dx: missing; the panel size in m (e.g. 0.03 for the M4 floats)")
    dx = _num(raw["dx"], f"{w}.dx")
    lid = _bool(raw.get("lid", True), f"{w}.lid")
    inf = _bool(raw.get("infinite_frequency", True), f"{w}.infinite_frequency")
    sym = raw.get("symmetry", "auto")
    if sym not in SYMMETRIES:
        raise ConfigError(f"{w}.symmetry: {sym!r}; accepted: {list(SYMMETRIES)}")
    hydro = hydro or {}
    rho = raw.get("rho", hydro.get("rho") if hydro.get("rho") is not None else 1000.0)
    g = raw.get("g", hydro.get("g") if hydro.get("g") is not None else gravity)
    rho = _num(rho, f"{w}.rho")
    g = _num(g, f"{w}.g")
    if math.isfinite(depth):
        w0 = float(np.min(omega))
        kh = _wavenumber(w0, depth, g) * depth
        if kh < KH_MIN:
            w_min = math.sqrt(g * KH_MIN / depth * math.tanh(KH_MIN))
            key = "omega" if "omega" in raw else "omega_min"
            raise ConfigError(f"{w}.{key}: ω = {w0:g} rad/s gives kh = {kh:.3g} at water_depth "
                              f"{depth:g} m; capytaine's finite-depth Green function needs "
                              f"kh >= {KH_MIN} (ω >= {w_min:.4g} rad/s here; capytaine 3.0 fails "
                              f"for kh <= 0.1375, measured: hydro.bem.KH_MIN): raise the lowest "
                              f"frequency")
    deep_kh = raw.get("deep_water_kh")
    if deep_kh is not None:
        deep_kh = _num(deep_kh, f"{w}.deep_water_kh")
        if not math.isfinite(depth):
            raise ConfigError(f"{w}.deep_water_kh: {deep_kh:g} with water_depth \"inf\": every "
                              "frequency is already solved in deep water; remove the key or give "
                              "a finite water_depth")
    _bool(raw.get("equilibrium_check", True), f"{w}.equilibrium_check")
    drift = raw.get("drift", False)
    if drift is not False and drift not in DRIFTS:
        raise ConfigError(f"{w}.drift: {drift!r}; accepted: \"fixed\" (the body held), \"free\" "
                          "(freely floating with its config mass and inertia), \"kochin\" (the "
                          "layout's Kochin functions: the drift of the model's own motions), or "
                          "false / absent (no mean drift)")
    record = {k: raw[k] for k in sorted(raw)}
    kwargs = {"omega": omega, "dx": dx, "wave_directions": [math.radians(b) for b in headings],
              "water_depth": depth, "rho": rho, "g": g, "lid": lid, "symmetry": sym,
              "infinite_frequency": inf, "deep_water_kh": deep_kh}
    if drift:          # only then, so that the up-to-date key of every other database is unchanged
        kwargs["drift"] = drift
    return {"kwargs": kwargs, "record": record, "headings_deg": headings,
            "equilibrium_check": raw.get("equilibrium_check", True)}


# ------------------------------------------------------------------------------------------------
# Geometry


def _geometry_error(msg: str, where: str) -> str:
    """hydro.geometry's message with ``body spec #i`` replaced by ``bodies[i] ('name').geometry.<key>``."""
    text = re.sub(r"^body spec(?: #\d+)?: ", "", msg)
    m = re.search(r"'([A-Za-z_]+)'", text)
    key = m.group(1) if m and m.group(1) in GEOMETRY_KEYS else None
    return f"{where}.geometry{'.' + key if key else ''}: {text}"


def body_specs(config_path, raw: dict | None = None, bodies=None) -> list[dict]:
    """The hydro.geometry body specs of a config's wet bodies (those with a ``geometry`` table),
    in the order of the config's ``[[bodies]]``, normalised (defaults filled in)."""
    from hydro import geometry as geo

    config_path = Path(config_path)
    if raw is None:
        raw = tomllib.loads(config_path.read_text())
    if bodies is None:
        bodies = load_config(config_path)[1]
    com = {b.name: np.asarray(b.com, dtype=float) for b in bodies}
    specs = []
    for i, rb in enumerate(raw.get("bodies", [])):
        if "geometry" not in rb:
            continue
        name = rb["name"]
        where = f"bodies[{i}] ({name!r})"
        gtab = rb["geometry"]
        if not isinstance(gtab, dict):
            raise ConfigError(f"{where}.geometry: expected a table such as {{ shape = \"cylinder\", "
                              f"radius = 0.1, draft = 0.07, base = \"flat\" }}")
        bad = sorted(set(gtab) - GEOMETRY_KEYS)
        if bad:
            raise ConfigError(f"{where}.geometry.{bad[0]}: unknown key(s) {bad}; accepted keys: "
                              f"{sorted(GEOMETRY_KEYS)} (the name is the body's)")
        c = com[name]
        spec = dict(gtab)
        spec["name"] = name
        spec.setdefault("origin", [float(c[0]), float(c[1]), 0.0])
        spec.setdefault("reference_point", [float(v) for v in c])
        if spec.get("shape") == "mesh" and isinstance(spec.get("file"), str):
            f = Path(spec["file"])
            spec["file"] = str(f if f.is_absolute() else config_path.parent / f)
        try:
            specs.append(geo.normalize_spec(spec, i))
        except (ValueError, TypeError) as e:
            raise ConfigError(_geometry_error(str(e), where)) from None
    if not specs:
        raise ConfigError(f"{config_path}: no body has a [bodies.geometry] table; `mfm hydro` needs "
                          "the hull of each wet body (see mfm.bemgen)")
    try:
        geo.normalize_specs(specs)
    except ValueError as e:
        raise ConfigError(f"bodies: {e}") from None
    return specs


# ------------------------------------------------------------------------------------------------
# Hull checks (before any solve)


def _heave_free(b) -> str | None:
    """Why body ``b`` carries its own weight in heave (its heave coordinate free, no spring), or
    None: a free or planar root moving in heave without heave stiffness, or a vertical prismatic
    joint without stiffness (RM3's float on its spar). A fixed, revolute or sprung body hangs
    partly on its parent and need not float on its own."""
    j = b.joint
    stiff = np.asarray(j.stiffness, float)
    if b.parent is None and j.kind in ("free", "planar") and "heave" in j.dofs:
        k = stiff[j.dofs.index("heave")] if stiff.size == len(j.dofs) else 0.0
        return None if k != 0.0 or j.locked else f"a {j.kind} root moving in heave"
    if j.kind == "prismatic" and j.axis is not None and not j.locked:
        axis = np.asarray(j.axis, float)
        if abs(abs(axis[2]) - np.linalg.norm(axis)) <= 1e-9 and not np.any(stiff != 0.0):
            return "a vertical prismatic joint without stiffness"
    return None


def _group(b, bodies) -> list:
    """``b`` and the bodies whose weight it carries: its descendants, except those free in heave
    themselves (and theirs), which float on their own."""
    out, todo = [b], [b]
    while todo:
        p = todo.pop()
        for c in bodies:
            if c.parent == p.name and _heave_free(c) is None:
                out.append(c)
                todo.append(c)
    return out


def check_hulls(specs, bodies, raw, settings) -> None:
    """Check the hulls of a config before any solve (cheap: meshes and hydrostatics, no BEM).

    1. Each mesh body (``hydro.geometry.mesh_hull``): the file's mesh closed (below the water line
       once placed) with outward normals, no panel collocation point on another panel; and with
       ``lid = true`` a lid found (``mesh_lid``). Errors name ``bodies[i] ('name').geometry.file``
       (or ``.dx`` / ``hydro.bem.lid``) and the edges or panels.
    2. Equilibrium, for the groups that hold a mesh body and float on their own: a body free in
       heave (:func:`_heave_free`: a free/planar root moving in heave, or a vertical prismatic
       joint, without stiffness) with the bodies whose weight it carries (:func:`_group`: its
       descendants except those free in heave themselves). Its buoyancy must carry its weight,
       |ρ ΣV − Σm| ≤ 5 % of Σm (V from each hull as placed, cut at z = 0), else the body sinks
       or rises from the draft the BEM is solved at. And when the group is rigid (fixed joints
       only) and its root turns in roll or pitch, the heel at rest θ = ρgV d / K (d the
       horizontal distance of the centre of buoyancy from the vertical through the centre of
       mass, K the buoyancy and water-plane stiffness about the centre of mass, roll and pitch
       apart) must stay ≤ 1°. Bodies on a hinge (revolute), fixed to a parent that is held, or
       sprung are not checked alone: they hang partly on their parent. Groups of bodies of
       revolution only are not checked here (their draft is stated, not derived from a file).
       A config with load tables (moorings, PTOs, joint loads, body matrices, ...) gets warnings
       (``HullWarning``) instead of errors: those loads may carry the difference.
       ``[hydro.bem] equilibrium_check = false`` turns errors into warnings too.
    3. A mesh whose file looks centred on the body's centre of mass (the public RM3 files are)
       placed with the default origin (z = 0) is named with the fix ``origin = [x, y, z_com]``
       (issue 51: a 712 m³ base became 275 m³ cut at the water line, silently).
    """
    from hydro import geometry as geo

    import warnings

    kw = settings["kwargs"]
    rho, dx = kw["rho"], kw["dx"]
    index = {rb.get("name"): i for i, rb in enumerate(raw.get("bodies", []))}
    by_name = {b.name: b for b in bodies}
    spec_of = {s["name"]: s for s in specs}

    def where(name):
        return f"bodies[{index.get(name, '?')}] ({name!r}).geometry"

    hulls = {}
    for s in specs:
        if s["shape"] != "mesh":
            continue
        try:
            hulls[s["name"]] = geo.mesh_hull(s)
        except ValueError as e:
            raise ConfigError(f"{where(s['name'])}.file: {e}") from None
        if kw["lid"]:
            try:
                geo.mesh_lid(s, hulls[s["name"]], dx)
            except ValueError as e:
                raise ConfigError(f"hydro.bem.lid (or {where(s['name'])}.dx): {e}") from None

    loads = sorted(k for k in raw if k not in ("model", "bodies", "hydro"))
    strict = bool(settings.get("equilibrium_check", True)) and not loads
    why_soft = (f" (a warning, not an error: the config's {loads} may carry the difference)"
                if loads else " (a warning: [hydro.bem] equilibrium_check = false)")

    def complain(msg):
        if strict:
            raise ConfigError(msg + " Nothing was solved. If the body is meant to float so (held "
                              "by something this config does not hold), set [hydro.bem] "
                              "equilibrium_check = false.")
        warnings.warn(msg + why_soft, HullWarning, stacklevel=3)

    def hydrostatics(name, origin=None):
        sp = spec_of[name] if origin is None else dict(spec_of[name], origin=origin)
        if sp["shape"] == "mesh":
            h = hulls[name] if origin is None else geo.mesh_hull(sp)
        else:
            h = geo.body_meshes(sp, dx, "full", lid=False)[0]
        return h

    def centred_hint(name):
        """The origin that puts the file's origin at the CoM, when it makes ρV ≈ m (or None)."""
        b, sp = by_name[name], spec_of[name]
        c = np.asarray(b.com, float)
        if sp["origin"][2] == c[2]:
            return None
        alt = [sp["origin"][0], sp["origin"][1], float(c[2])]
        try:
            h = geo.hull_hydrostatics(hydrostatics(name, alt), c, rho=rho, g=kw["g"])
        except ValueError:
            return None
        return alt, rho * h["volume"]

    for b in bodies:
        why = _heave_free(b)
        if why is None:
            continue
        group = _group(b, bodies)
        names = [m.name for m in group]
        if not any(spec_of.get(n, {}).get("shape") == "mesh" for n in names):
            continue
        mass = sum(m.mass for m in group)
        G = sum(m.mass * np.asarray(m.com, float) for m in group) / mass
        wet = [n for n in names if n in spec_of]
        hs = {n: geo.hull_hydrostatics(hydrostatics(n), G, rho=rho, g=kw["g"]) for n in wet}
        V = sum(h["volume"] for h in hs.values())
        err = (rho * V - mass) / mass
        who = (f"{b.name!r}" if len(group) == 1 else
               f"{b.name!r} with the bodies it carries {names[1:]}")
        if abs(err) > EQUILIBRIUM_VOLUME_TOL:
            mesh_names = [n for n in wet if spec_of[n]["shape"] == "mesh"]
            n0 = mesh_names[0]
            sp = spec_of[n0]
            hint = ("Set origin's z so that the mesh floats at its draft (origin is added to the "
                    "file's coordinates; z = 0 is the still-water line).")
            alt = centred_hint(n0) if len(wet) == 1 else None
            if alt is not None and abs(alt[1] - mass) <= EQUILIBRIUM_VOLUME_TOL * mass:
                o = alt[0]
                hint = (f"The file looks centred on the body's centre of mass: placed at origin = "
                        f"[{o[0]:g}, {o[1]:g}, {o[2]:g}] (z of the com) it displaces ρV = "
                        f"{alt[1]:.6g} kg ({(alt[1] - mass) / mass:+.1%}); give origin = "
                        f"[{o[0]:g}, {o[1]:g}, {o[2]:g}] in its [bodies.geometry].")
            complain(f"{where(n0)}.origin: {who} is free in heave ({why}) but its hull"
                     f"{'s' if len(wet) > 1 else ''} as placed (file {os.path.basename(sp['file'])!r}"
                     f" at origin {sp['origin']}, cut at z = 0) displace{'' if len(wet) > 1 else 's'}"
                     f" V = {V:.6g} m³, ρV = {rho * V:.6g} kg, against its mass m = {mass:.6g} kg "
                     f"({err:+.1%}; accepted: within ±{EQUILIBRIUM_VOLUME_TOL:.0%}): it would not "
                     f"float at the draft the BEM is solved at. {hint}")
            continue
        rigid = all(m.joint.kind == "fixed" for m in group[1:])
        if b.parent is not None or not rigid:
            continue
        B = sum(h["volume"] * np.asarray(h["center_of_buoyancy"]) for h in hs.values()) / V
        H = sum(h["hydrostatic_stiffness"] for h in hs.values())
        # buoyancy ρgV at x_B about G: a pitch moment ρgV (x_B − x_G) against K55, a roll moment
        # ρgV (y_B − y_G) against K44 (hydrostatic_stiffness about G holds both the water plane
        # and ρgV (z_B − z_G); the weight has no moment about G)
        for axis, dof, k, off in (("pitch", "pitch", 4, B[0] - G[0]), ("roll", "roll", 3, B[1] - G[1])):
            if dof not in b.joint.dofs:
                continue
            K = H[k, k]
            if K <= 0.0:
                continue       # unstable at rest: a matter of the masses, not of the mesh here
            theta = math.degrees(math.atan2(rho * kw["g"] * V * abs(off), K))
            if theta > EQUILIBRIUM_HEEL_TOL_DEG:
                n0 = [n for n in wet if spec_of[n]["shape"] == "mesh"][0]
                complain(f"{where(n0)}.origin: {who} turns in {axis} ({b.joint.kind} root) and "
                         f"its centre of buoyancy {np.round(B, 4).tolist()} m lies {abs(off):.4g} m "
                         f"({'x' if k == 4 else 'y'}) from the vertical through its centre of "
                         f"mass {np.round(G, 4).tolist()} m: it would {axis} by {theta:.2f}° at "
                         f"rest (accepted: ≤ {EQUILIBRIUM_HEEL_TOL_DEG:g}°; K = {K:.4g} N m/rad). "
                         f"Check the mesh's origin x, y and the bodies' com.")


# ------------------------------------------------------------------------------------------------
# Generation


PATHS_NOTE = ("relative to the folder of the config (mfm_config): the config itself, --out in "
              "generated_by, and each mesh file in bodies")


def relative_to_config(path, config_path) -> str:
    """``path`` relative to the folder of ``config_path`` (POSIX separators), as a database made
    by ``mfm hydro`` records it (``mfm_paths``): no folder of the machine that made it."""
    folder = os.path.dirname(os.path.abspath(config_path))
    return Path(os.path.relpath(os.path.abspath(path), folder)).as_posix()


def _specs_relative(specs, config_path) -> list[dict]:
    """Body specs with each mesh ``file`` relative to the config's folder."""
    out = []
    for s in specs:
        s = dict(s)
        if s.get("shape") == "mesh" and isinstance(s.get("file"), str):
            s["file"] = relative_to_config(s["file"], config_path)
        out.append(s)
    return out


def _sha256(path) -> str:
    return hashlib.sha256(Path(path).read_bytes()).hexdigest()


def geometry_record(specs) -> list[dict]:
    """The normalised body specs with each mesh file replaced by its SHA-256 (content, not
    path): what a database's hulls are, whatever the file is called or where it lies."""
    out = []
    for s in specs:
        s = dict(s)
        if s.get("shape") == "mesh":
            s["file_sha256"] = _sha256(s.pop("file"))
        out.append(s)
    return out


def geometry_hash(specs) -> str:
    """SHA-256 of :func:`geometry_record` (recorded as ``mfm_geometry_sha256``)."""
    text = json.dumps(geometry_record(specs), sort_keys=True, default=float)
    return hashlib.sha256(text.encode()).hexdigest()


def bem_inputs(specs, kwargs) -> dict:
    """What the BEM's answer depends on, and nothing else: the hulls (:func:`geometry_record`:
    shapes, sizes, positions, per-body panel sizes, STL files by content) and the arguments of
    ``hydro.bem.solve`` as resolved from ``[hydro.bem]`` and its defaults (frequencies, headings,
    depth, ρ, g, panel size, lid, symmetry, A∞, deep_water_kh). Not the config's other tables, its
    comments or the version of the code."""
    solve = {k: (np.asarray(v, float).tolist() if k in ("omega", "wave_directions") else v)
             for k, v in kwargs.items()}
    return {"geometry": geometry_record(specs), "solve": solve}


def bem_inputs_key(specs, kwargs) -> str:
    """SHA-256 of :func:`bem_inputs` (recorded as ``mfm_bem_inputs_sha256``): a database is up to
    date with a config exactly when the two keys agree."""
    text = json.dumps(bem_inputs(specs, kwargs), sort_keys=True, default=float)
    return hashlib.sha256(text.encode()).hexdigest()


def config_bem_inputs(config_path, overrides=None):
    """(specs, kwargs of ``hydro.bem.solve``, output path) of a config with ``[hydro.bem]``."""
    config_path = Path(config_path)
    options, bodies = load_config(config_path)
    raw = tomllib.loads(config_path.read_text())
    hydro = options.get("hydro") or {}
    settings = bem_settings(hydro.get("bem"), hydro=hydro, gravity=options["gravity"],
                            overrides=overrides)
    out = (Path(os.path.normpath(config_path.parent / hydro["database"]))
           if hydro.get("database") else None)
    specs = body_specs(config_path, raw, bodies)
    return specs, _drift_inertia(settings["kwargs"], specs, bodies), out


def _drift_inertia(kw, specs, bodies) -> dict:
    """`kw` (hydro.bem.solve's arguments) with ``drift_inertia`` added for ``drift = "free"``: the
    one wet body's config mass, com and inertia (its own, as a freely floating body)."""
    if kw.get("drift") in ("fixed", "free"):
        if len(specs) != 1:
            raise ConfigError(f"hydro.bem.drift: {kw['drift']!r} with {len(specs)} wet bodies "
                              f"({[s['name'] for s in specs]}): capytaine's far-field mean drift "
                              "is the total force on all bodies, not each body's; it is computed "
                              "for a config with one wet body (drift = \"kochin\" stores the "
                              "layout's Kochin functions, for the drift of the model's own "
                              "motions)")
        if kw["drift"] == "free":
            b = next(b for b in bodies if b.name == specs[0]["name"])
            kw["drift_inertia"] = {"mass": float(b.mass), "com": [float(v) for v in b.com],
                                   "inertia": np.asarray(b.inertia, float).tolist()}
    return kw


def _code_version() -> str:
    from hydro.bem import code_version

    return code_version()


def _spec_diff(old: list, new: list) -> list[str]:
    """Human differences between two lists of body specs (recorded vs current)."""
    o = {s.get("name"): s for s in old}
    n = {s.get("name"): s for s in new}
    diffs = []
    for name in n:
        if name not in o:
            diffs.append(f"body {name!r} is in the config but not in the database")
            continue
        for k in sorted(set(o[name]) | set(n[name])):
            a, b = o[name].get(k), n[name].get(k)
            if json.dumps(a, sort_keys=True, default=float) != json.dumps(b, sort_keys=True, default=float):
                what = "contents" if k == "file_sha256" else repr(a)
                diffs.append(f"body {name!r} {k}: {what} in the database, "
                             f"{'other contents' if k == 'file_sha256' else repr(b)} in the config")
    diffs += [f"body {name!r} is in the database but not in the config" for name in o if name not in n]
    return diffs


def _short(v) -> str:
    text = repr(v)
    return text if len(text) <= 60 else text[:57] + "..."


def database_is_stale(config_path, database=None, *, parsed=None) -> tuple[bool, str]:
    """Whether the hydro database of a config was made from other hulls or BEM settings than the
    config has now (an edited radius, draft, position, STL file or ``[hydro.bem]`` key).

    Compares the config's ``[bodies.geometry]`` specs (normalised; STL files by content) and its
    ``[hydro.bem]`` table with what ``mfm hydro`` recorded in the database's attrs
    (``mfm_geometry_sha256`` / ``mfm_geometry``, else hydro.bem's ``bodies`` record for files
    made before those existed; ``mfm_bem_settings``). Reads only the file's attributes (fast; no
    capytaine, no jax).

    database: the NetCDF to check (default: the config's ``[hydro] database``).
    parsed: the config as :func:`mfm.io.config.read_config` gives it, where the caller has read
    it already (:func:`mfm.io.build.load`: the file is read and parsed once).

    Returns ``(stale, reason)``: ``(True, "…")`` names each difference and the fix (``mfm hydro
    CONFIG --force``); ``(False, "…")`` says why it is up to date or why it cannot be checked (a
    WAMIT database, or a config without ``[bodies.geometry]`` tables: nothing recorded to compare).
    """
    config_path = Path(config_path)
    raw, options, bodies = read_config(config_path) if parsed is None else parsed
    hydro = options.get("hydro") or {}
    if database is None:
        if not hydro.get("database"):
            return False, f"{config_path} has no [hydro] database: nothing to check"
        database = config_path.parent / hydro["database"]
    database = Path(database)
    if database.suffix != ".nc":
        return False, f"{database} is not a NetCDF made by `mfm hydro` (WAMIT?): not checked"
    if not any("geometry" in b for b in raw.get("bodies", [])):
        return False, (f"{config_path} has no [bodies.geometry] table: the database was not made "
                       "from this config's hulls; not checked")
    from hydro.checks import check_netcdf_file
    from hydro.database import read_netcdf_attrs

    attrs = read_netcdf_attrs(check_netcdf_file(database))
    specs = body_specs(config_path, raw, bodies)
    if "mfm_bem_inputs_sha256" in attrs and hydro.get("bem") is not None:
        kwargs = bem_settings(hydro.get("bem"), hydro=hydro, gravity=options["gravity"])["kwargs"]
        if attrs["mfm_bem_inputs_sha256"] == bem_inputs_key(specs, kwargs):
            return False, (f"{os.path.normpath(database)} was made from the BEM inputs of "
                           f"{config_path} (hulls and [hydro.bem] settings)")
        diffs = []
        if "mfm_bem_inputs" in attrs:
            old, new = json.loads(attrs["mfm_bem_inputs"]), bem_inputs(specs, kwargs)
            diffs += _spec_diff(old["geometry"], new["geometry"])
            new_solve = json.loads(json.dumps(new["solve"], default=float))
            diffs += [f"BEM input {k}: {_short(old['solve'].get(k))} in the database, "
                      f"{_short(new_solve.get(k))} from the config"
                      for k in sorted(set(old["solve"]) | set(new_solve))
                      if old["solve"].get(k) != new_solve.get(k)]
        return True, (f"hydro database {os.path.normpath(database)!r} is stale: it was made from "
                      f"other BEM inputs than {str(config_path)!r} gives now: "
                      + ("; ".join(diffs) or "the recorded key differs")
                      + f". Regenerate it: mfm hydro {config_path} --force")
    diffs = []
    if "mfm_geometry" in attrs:
        diffs += _spec_diff(json.loads(attrs["mfm_geometry"]), geometry_record(specs))
    elif "bodies" in attrs:                 # made before mfm_geometry: specs without file digests
        old = json.loads(attrs["bodies"])
        diffs += _spec_diff(old, [dict(s) for s in specs])
    else:
        return False, f"{database} records no hull geometry (not made by hydro.bem): not checked"
    # a config without [hydro.bem] reads a database another config made (the hydro-coupled
    # scenario of Hallak reads the fully coupled one's): its hulls are compared, not settings
    if "mfm_bem_settings" in attrs and hydro.get("bem") is not None:
        settings = bem_settings(hydro.get("bem"), hydro=hydro, gravity=options["gravity"])["record"]
        recorded = json.loads(attrs["mfm_bem_settings"])
        for k in sorted(set(recorded) | set(settings)):
            if recorded.get(k) != settings.get(k):
                diffs.append(f"[hydro.bem] {k}: {recorded.get(k)!r} in the database, "
                             f"{settings.get(k)!r} in the config")
    if diffs:
        return True, (f"hydro database {os.path.normpath(database)!r} is stale: it was made from other hulls or "
                      f"settings than {str(config_path)!r} has now: " + "; ".join(diffs)
                      + f". Regenerate it: mfm hydro {config_path} --force")
    return False, f"{os.path.normpath(database)} matches the hulls and [hydro.bem] settings of {config_path}"


def _check_database(path: Path, config_path: Path, options: dict, bodies) -> None:
    """Load ``path`` the way ``mfm.load(config)`` does (open_any_database → from_capytaine →
    schema checks → the config's bodies on the tree)."""
    from ..mechanics.compile import compile_tree
    from ..loads.water import load_hydro_spec

    model = compile_tree(bodies, name=options["name"], gravity=options["gravity"])
    hyd = dict(options.get("hydro") or {})
    hyd["database"] = str(Path(path).resolve())
    load_hydro_spec(model, bodies, hyd, Path(config_path).parent)


def _check_finite(ds, infinite_frequency) -> None:
    """Every radiation coefficient finite, and the excitation at every finite ω: capytaine logs
    and skips a problem that fails (e.g. a missing optional dependency) and leaves NaN there."""
    bad = []
    for v in ("added_mass", "radiation_damping"):
        a = np.asarray(ds[v].values)
        if not np.all(np.isfinite(a)):
            w = ds["omega"].values[~np.all(np.isfinite(a.reshape(a.shape[0], -1)), axis=1)]
            bad.append(f"{v} at ω = {w[:5].tolist()}{' ...' if len(w) > 5 else ''}")
    finite = np.isfinite(ds["omega"].values)
    x = np.asarray(ds["excitation_force"].values)[finite]
    if not np.all(np.isfinite(x)):
        bad.append("excitation_force at finite ω")
    if bad:
        raise RuntimeError("mfm hydro: the BEM results hold NaN (capytaine skipped problems; see its "
                           "warnings above): " + "; ".join(bad) + ". Nothing was written; if "
                           "hydro.bem cached this result, delete the cache file or pass cache=False.")


def _deep_from(kw) -> float:
    """The lowest ω that ``hydro.bem.solve`` solves in deep water (``deep_water_kh``), else ∞."""
    if kw.get("deep_water_kh") is None or not math.isfinite(kw["water_depth"]):
        return math.inf
    h = kw["water_depth"]
    return float(min((w for w in kw["omega"] if _wavenumber(w, h, kw["g"]) * h
                      >= kw["deep_water_kh"]), default=math.inf))


def _human(nbytes: int) -> str:
    return f"{nbytes / 1e6:.2f} MB" if nbytes >= 1e5 else f"{nbytes / 1e3:.1f} kB"


def generate(config_path, *, out=None, force=False, progress=True, n_threads=None,
             overrides=None, cache=True, cache_dir=None) -> Path:
    """Solve the BEM of a config's hulls and write its hydro database.

    config_path: a TOML config whose wet bodies carry ``[bodies.geometry]`` and whose ``[hydro]``
        table has ``database`` (the output, relative to the config) and ``bem`` (the settings).
    out: write here instead of ``[hydro] database`` (a ``.nc`` path).
    force: overwrite an existing file. Without it an existing file made from the same config
        contents and settings is kept ("up to date"); any other existing file is an error.
    progress: tqdm bar over the frequencies. n_threads: capytaine threads (None: all cores).
    overrides: dict of ``[hydro.bem]`` keys replacing the config's (e.g. a coarse ``dx`` for a
        test, or ``omega``); recorded in the file.
    cache, cache_dir: the result cache of ``hydro.bem.solve``.

    Returns the path written. Prints a one-line summary.
    """
    from hydro import bem

    config_path = Path(config_path)
    options, bodies = load_config(config_path)
    text = config_path.read_text()
    raw = tomllib.loads(text)
    hydro = options.get("hydro") or {}
    out_given = out is not None
    if out is None:
        if not hydro.get("database"):
            raise ConfigError(f"{config_path}: no [hydro] database path; add [hydro] database = "
                              "\"<file>.nc\" (relative to the config) or pass out=")
        out = Path(os.path.normpath(config_path.parent / hydro["database"]))
    out = Path(out)
    if out.suffix != ".nc":
        raise ConfigError(f"out: {str(out)!r}: `mfm hydro` writes NetCDF; give a path ending in .nc")
    if hydro.get("bem") is None and not overrides:
        raise ConfigError(
            f"{config_path}: no [hydro.bem] table, so `mfm hydro` does not know how to solve its "
            f"hulls; its database {hydro.get('database')!r} was not made by `mfm hydro` (see "
            "hydro/data/README.md for how each shipped file was made). To make one, add "
            "[hydro.bem] (dx, and omega_min, omega_max, n_omega or omega = [...]; see "
            "configs/m4_111.toml) and a [bodies.geometry] table for each wet body")
    settings = bem_settings(hydro.get("bem"), hydro=hydro, gravity=options["gravity"],
                            overrides=overrides)
    specs = body_specs(config_path, raw, bodies)
    kw = settings["kwargs"]
    _drift_inertia(kw, specs, bodies)
    config_sha = hashlib.sha256(text.encode()).hexdigest()
    # the up-to-date stamp: what the BEM's answer depends on (the hulls, STL files by content, and
    # the solver's resolved arguments), not the rest of the config or the code's version
    geometry_sha = geometry_hash(specs)
    code = _code_version()
    key = bem_inputs_key(specs, kw)

    if out.exists() and not force:
        stored = None
        try:
            from hydro.database import read_netcdf_attrs

            stored = read_netcdf_attrs(out).get("mfm_bem_inputs_sha256")
        except Exception:  # noqa: BLE001 - unreadable: treat as foreign
            pass
        if stored == key:
            print(f"mfm hydro: {out} is up to date (made from the same hulls and BEM settings); "
                  f"use --force to solve again")
            return out
        stale, why = (False, "")
        try:
            stale, why = database_is_stale(config_path, out)
        except Exception:  # noqa: BLE001 - the reason is optional
            pass
        raise FileExistsError(f"mfm hydro: {str(out)!r} exists and was not made from the BEM "
                              f"inputs of this config (its hull files and [hydro.bem] settings)"
                              + (f" ({why})" if stale else "") + "; use --force to overwrite it")

    try:
        import capytaine  # noqa: F401 - the BEM solver is an optional extra
    except ImportError:
        raise ModuleNotFoundError(
            "mfm hydro: the BEM solver capytaine is not installed (it is the optional 'bem' "
            "extra, needed to make databases, never to read them); install it with: "
            "pip install -e \".[bem]\" (from the repository root), or pip install "
            "\"capytaine>=3.0\" trimesh threadpoolctl") from None
    if n_threads is not None:
        try:
            import threadpoolctl  # noqa: F401 - capytaine needs it to honour n_threads
        except ImportError:
            # capytaine would skip every problem (a logged warning each) and return NaNs
            print(f"mfm hydro: n_threads={n_threads} needs the package threadpoolctl, which is "
                  f"missing; using the default threads (set OMP_NUM_THREADS to limit them)")
            n_threads = None
    # the hulls before any solve: a bad mesh or a body that cannot float at its draft is named now,
    # not after the whole run (issue 51)
    check_hulls(specs, bodies, raw, settings)
    try:
        bem.check_finite_depth(kw["omega"], kw["water_depth"], kw["g"],
                               deep_from=_deep_from(kw))
    except ValueError as e:
        key = "omega" if "omega" in (hydro.get("bem") or {}) else "omega_min"
        raise ConfigError(f"hydro.bem.{key}: {e}") from None
    t0 = time.perf_counter()
    ds = bem.solve(specs, n_threads=n_threads, progress=progress, cache=cache,
                   cache_dir=cache_dir, **kw)
    wall = time.perf_counter() - t0
    _check_finite(ds, kw["infinite_frequency"])
    # paths as seen from the config's folder: a file a user shares carries no folder of their
    # machine (hydro.bem.solve records the specs it was given, mesh files as absolute paths)
    command = f"mfm hydro {config_path.name}" + (
        f" --out {relative_to_config(out, config_path)}" if out_given else "")
    ds.attrs.update({
        "bodies": json.dumps(_specs_relative(json.loads(ds.attrs["bodies"]), config_path))
        if "bodies" in ds.attrs else json.dumps(_specs_relative(specs, config_path)),
        "generated_by": command,
        "mfm_config": config_path.name,
        "mfm_paths": PATHS_NOTE,
        "mfm_config_sha256": config_sha,
        "mfm_bem_settings": json.dumps(settings["record"], sort_keys=True, default=str),
        "mfm_overrides": json.dumps(overrides or {}, sort_keys=True, default=str),
        "mfm_bem_inputs_sha256": key,
        "mfm_bem_inputs": json.dumps(bem_inputs(specs, kw), sort_keys=True, default=float),
        "mfm_geometry": json.dumps(geometry_record(specs), sort_keys=True, default=float),
        "mfm_geometry_sha256": geometry_sha,
        "mfm_code_version": code,
        "mfm_headings_deg": json.dumps(settings["headings_deg"]),
        "mfm_wall_time_s": round(wall, 1),
        "mfm_n_threads": str(n_threads),
        "mfm_omp_num_threads": os.environ.get("OMP_NUM_THREADS", ""),
    })
    out.parent.mkdir(parents=True, exist_ok=True)
    tmp = out.with_name(f".{out.stem}.tmp{os.getpid()}.nc")
    try:
        bem.save(ds, tmp)
        if kw["infinite_frequency"]:
            _check_database(tmp, config_path, options, bodies)
        else:
            print("mfm hydro: note: infinite_frequency = false: no A∞, so mfm.load cannot use this "
                  "file (a capytaine dataset for other uses)")
        os.replace(tmp, out)
    finally:
        if tmp.exists():
            tmp.unlink()
    n_w = int(np.isfinite(ds["omega"].values).sum())
    inf = " + ∞" if kw["infinite_frequency"] else ""
    depth = "inf" if math.isinf(kw["water_depth"]) else f"{kw['water_depth']:g} m"
    panels = int(ds.attrs["nb_hull_panels"]) + int(ds.attrs["nb_lid_panels"])
    how = "cache hit" if ds.attrs.get("cache_status") == "hit" else f"{wall:.1f} s"
    print(f"mfm hydro: wrote {out} ({len(specs)} bodies, {n_w} ω{inf}, "
          f"{len(settings['headings_deg'])} heading(s), dx {kw['dx']:g} m, depth {depth}, "
          f"{panels} panels, symmetry {ds.attrs['symmetry_used']}, {how}, "
          f"{_human(out.stat().st_size)})")
    return out
