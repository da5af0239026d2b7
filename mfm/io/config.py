"""TOML float-tree configs → validated :class:`~mfm.mechanics.tree.BodySpec` lists.

Format (every key is checked; an unknown key is an error)::

    [model]
    name = "double pendulum"     # optional
    gravity = 9.81               # m/s², acts along −z (default 9.81)

    [[bodies]]
    name = "link1"
    mass = 1.0                                  # kg, > 0 (0: a hull welded to its parent,
                                                #   whose mass the parent carries)
    com = [0.0, 0.0, -0.5]                      # m, inertial axes at q = 0
    inertia = [[0.1, 0, 0], [0, 0.1, 0], [0, 0, 0.01]]   # kg m² about the CoM, or instead:
    # principal_inertia = [Ixx, Iyy, Izz]       #   body axes = inertial axes at q = 0
    # radii_of_gyration = [rx, ry, rz]          #   m, I = m r²
    # parent = "..."                            # omitted for a root body
    [bodies.joint]
    type = "revolute"        # free | planar | revolute | prismatic | fixed
    axis = [0.0, 1.0, 0.0]   # revolute / prismatic: unit direction, inertial axes at q = 0
    point = [0.0, 0.0, 0.0]  # revolute: a point on the axis, m
    damping = 0.0            # optional linear damper on the joint coordinate (N m s/rad, N s/m)
    stiffness = 0.0          # optional linear spring (N m/rad, N/m) about `rest`
    rest = 0.0

The root may use ``free`` (6 coordinates: surge, sway, heave, roll, pitch, yaw), ``planar`` (surge,
heave, pitch) or ``free`` with ``dofs = [...]`` (any subset), or a revolute/prismatic/fixed joint to
the inertial frame. For a root with several coordinates, ``damping``/``stiffness``/``rest`` take
one value per coordinate. Several roots (bodies without ``parent``) each hang from the inertial
frame: bodies that interact only through the water (or through loads such as moorings). A
revolute, prismatic or fixed root beside floating (free, planar) roots must say
``parent = "earth"``: without it, a missing ``parent`` is the likelier reading, and it is refused.
"""
from __future__ import annotations

import tomllib
from pathlib import Path
from typing import Any

import numpy as np

from ..loads.registry import TABLES as LOAD_TABLES
from ..loads.registry import load_class
from ..validation import number as _number
from ..validation import unknown as _unknown
from ..validation import vector as _vector
from ..errors import ConfigError
from ..mechanics.tree import (JOINT_KINDS, PLANAR_DOFS, ROOT_DOFS, BodySpec, JointSpec,
                              check_inertia, tree_order)

# the tables of loads (moorings, ptos, ...) come from the load registry (mfm.loads.registry)
TOP_KEYS = {"model", "bodies", "hydro"} | set(LOAD_TABLES)
HYDRO_KEYS = {"database", "names", "body_coupling", "added_mass_inf", "rho", "g", "bem", "notes",
              "hydrostatics", "nonlinear_dt", "drag_flow", "drift"}
HYDROSTATICS = ("linear", "nonlinear")
DRIFTS = ("off", "mean", "newman")
BODY_HYDRO_KEYS = {"body", "drag_coefficient", "drag_area", "notes"}
MODEL_KEYS = {"name", "gravity", "description"}
BODY_KEYS = {"name", "mass", "com", "inertia", "principal_inertia", "radii_of_gyration", "parent",
             "joint", "hydro", "geometry", "hull", "notes"}
JOINT_KEYS = {"type", "axis", "point", "dofs", "damping", "stiffness", "rest", "locked", "notes"}


def _per_coordinate(value, n, where):
    if n == 0:
        raise ConfigError(f"{where}: a fixed joint has no coordinate to carry a spring or damper")
    if isinstance(value, (int, float)) and not isinstance(value, bool):
        return np.full(n, _number(value, where))
    return _vector(value, n, where)


def _parse_joint(raw: Any, where: str, is_root: bool) -> JointSpec:
    if not isinstance(raw, dict):
        raise ConfigError(f"{where}: expected a table such as {{ type = \"revolute\", axis = [0, 1, "
                          f"0], point = [0, 0, 0] }}, got {raw!r}")
    _unknown(raw, JOINT_KEYS, where)
    if "type" not in raw:
        raise ConfigError(f"{where}.type: missing; accepted: {list(JOINT_KINDS)}")
    kind = raw["type"]
    if kind not in JOINT_KINDS:
        raise ConfigError(f"{where}.type: {kind!r} is not a joint type; accepted: {list(JOINT_KINDS)}")
    axis = point = None
    dofs: tuple[str, ...] = ()
    if kind in ("revolute", "prismatic"):
        if "axis" not in raw:
            raise ConfigError(f"{where}.axis: missing; a {kind} joint needs a unit axis, e.g. [0, 1, 0]")
        axis = _vector(raw["axis"], 3, f"{where}.axis")
        norm = np.linalg.norm(axis)
        if norm < 1e-12:
            raise ConfigError(f"{where}.axis: {raw['axis']!r} is a zero vector; give the direction "
                              "of the joint axis, e.g. [0, 1, 0]")
        axis = axis / norm
    elif "axis" in raw:
        raise ConfigError(f"{where}.axis: a {kind} joint has no axis; remove the key")
    if kind == "revolute":
        if "point" not in raw:
            raise ConfigError(f"{where}.point: missing; a revolute joint needs a point on its axis (m)")
        point = _vector(raw["point"], 3, f"{where}.point")
    elif "point" in raw:
        raise ConfigError(f"{where}.point: only a revolute joint takes a point; remove the key")
    if kind in ("free", "planar"):
        if kind == "planar":
            if "dofs" in raw:
                raise ConfigError(f"{where}.dofs: a planar joint is {list(PLANAR_DOFS)}; use "
                                  "type = \"free\" with dofs = [...] for another subset")
            dofs = PLANAR_DOFS
        else:
            req = raw.get("dofs", list(ROOT_DOFS))
            if not isinstance(req, list) or not req:
                raise ConfigError(f"{where}.dofs: {req!r} is not a non-empty list of {list(ROOT_DOFS)}")
            for d in req:
                if d not in ROOT_DOFS:
                    raise ConfigError(f"{where}.dofs: {d!r} is not a root dof; accepted: {list(ROOT_DOFS)}")
            if len(set(req)) != len(req):
                raise ConfigError(f"{where}.dofs: {req!r} repeats a dof")
            dofs = tuple(d for d in ROOT_DOFS if d in req)
    elif "dofs" in raw:
        raise ConfigError(f"{where}.dofs: only a free root takes dofs; remove the key")
    locked = raw.get("locked", False)
    if not isinstance(locked, bool):
        raise ConfigError(f"{where}.locked: {locked!r} is not true or false")
    if locked and kind not in ("revolute", "prismatic"):
        raise ConfigError(f"{where}.locked: only a revolute or prismatic joint can be locked")
    if locked:
        # a locked hinge (Wu & Yuan 2025, severe seas) is rigid at its q = 0 position: no coordinate
        for key in ("damping", "stiffness", "rest"):
            if key in raw:
                raise ConfigError(f"{where}.{key}: a locked joint has no coordinate; remove the key")
        return JointSpec(kind="fixed", axis=axis, point=point, locked=True)
    spec = JointSpec(kind=kind, axis=axis, point=point, dofs=dofs)
    n = spec.n_coordinates
    loads = {}
    for key in ("stiffness", "damping", "rest"):
        loads[key] = (_per_coordinate(raw[key], n, f"{where}.{key}") if key in raw else np.zeros(n))
    for key in ("stiffness", "damping"):
        if np.any(loads[key] < 0):
            raise ConfigError(f"{where}.{key}: {raw[key]!r} is negative; a passive spring or damper "
                              "needs a value ≥ 0")
    return JointSpec(kind=kind, axis=axis, point=point, dofs=dofs, **loads)


def _parse_inertia(raw: dict, mass: float, where: str) -> np.ndarray:
    given = [k for k in ("inertia", "principal_inertia", "radii_of_gyration") if k in raw]
    if len(given) != 1:
        raise ConfigError(f"{where}: give exactly one of inertia (3×3), principal_inertia (3) or "
                          f"radii_of_gyration (3); found {given or 'none'}")
    key = given[0]
    if key == "inertia":
        try:
            J = np.asarray(raw[key], dtype=float)
        except (TypeError, ValueError):
            raise ConfigError(f"{where}.inertia: {raw[key]!r} is not a 3×3 matrix of numbers") from None
    elif key == "principal_inertia":
        J = np.diag(_vector(raw[key], 3, f"{where}.{key}"))
    else:
        r = _vector(raw[key], 3, f"{where}.{key}")
        if np.any(r <= 0):
            raise ConfigError(f"{where}.{key}: {raw[key]!r} must be positive lengths (m)")
        J = np.diag(mass * r**2)
    return check_inertia(J, f"{where}.{key}")


def _parse_body_hydro(raw, where, name):
    if not isinstance(raw, dict):
        raise ConfigError(f"{where}: expected a table such as {{ body = \"float\" }}")
    _unknown(raw, BODY_HYDRO_KEYS, where)
    out = {"body": raw.get("body", name)}
    if not isinstance(out["body"], str):
        raise ConfigError(f"{where}.body: {out['body']!r} is not a database body name")
    cd = _vector(raw.get("drag_coefficient", [0, 0, 0]), 3, f"{where}.drag_coefficient")
    area = _vector(raw.get("drag_area", [0, 0, 0]), 3, f"{where}.drag_area")
    for key, v in (("drag_coefficient", cd), ("drag_area", area)):
        if np.any(v < 0):
            raise ConfigError(f"{where}.{key}: {v.tolist()} has a negative entry; give values ≥ 0 "
                              "per inertial axis x, y, z")
    out["drag"] = cd * area
    return out


def _parse_hydro(raw, source):
    if not isinstance(raw, dict):
        raise ConfigError("hydro: expected a table")
    _unknown(raw, HYDRO_KEYS, "hydro")
    if "database" not in raw or not isinstance(raw["database"], str):
        raise ConfigError("hydro.database: missing; the path (relative to the config) of a hydro "
                          "database: a NetCDF from `mfm hydro`/capytaine, or WAMIT output (.out)")
    out = {"database": raw["database"], "names": raw.get("names"),
           "body_coupling": raw.get("body_coupling", True),
           "added_mass_inf": raw.get("added_mass_inf", "consistent"),
           "rho": raw.get("rho"), "g": raw.get("g"), "bem": raw.get("bem"),
           "hydrostatics": raw.get("hydrostatics", "linear"),
           "drag_flow": raw.get("drag_flow", "body"),
           "drift": raw.get("drift", "off")}
    if "nonlinear_dt" in raw:
        out["nonlinear_dt"] = raw["nonlinear_dt"]
    if out["drift"] not in DRIFTS:
        raise ConfigError(f"hydro.drift: {out['drift']!r}; accepted: {list(DRIFTS)} (mean: the "
                          "constant mean wave drift force; newman: its slow drift in irregular "
                          "seas by Newman's approximation; both need the database's mean_drift)")
    if out["drag_flow"] not in ("body", "relative"):
        raise ConfigError(f"hydro.drag_flow: {out['drag_flow']!r}; accepted: 'body' (quadratic "
                          "drag on each reference point's velocity) or 'relative' (on its "
                          "velocity relative to the incident wave's flow there)")
    if out["hydrostatics"] not in HYDROSTATICS:
        raise ConfigError(f"hydro.hydrostatics: {out['hydrostatics']!r}; accepted: "
                          f"{list(HYDROSTATICS)} (nonlinear: hydrostatics and Froude–Krylov on the "
                          "instantaneous wetted hull of each body's [bodies.hull])")
    if "nonlinear_dt" in out:
        v = out["nonlinear_dt"]
        if isinstance(v, bool) or not isinstance(v, (int, float)) or not np.isfinite(v) or v <= 0:
            raise ConfigError(f"hydro.nonlinear_dt: {v!r} is not a positive number of seconds; "
                              "give the interval at which the hull pressure is sampled (a whole "
                              "multiple of the run's dt, e.g. 4 × dt), or leave the key out to "
                              "evaluate it at every stage of every step")
        if out["hydrostatics"] != "nonlinear":
            raise ConfigError(f"hydro.nonlinear_dt: {v!r} is given but hydro.hydrostatics is "
                              f"{out['hydrostatics']!r}: the interval is the nonlinear level's "
                              "(the hull pressure sampled every nonlinear_dt s); set "
                              "hydro.hydrostatics = \"nonlinear\" or remove hydro.nonlinear_dt")
    for key, unit, typical in (("rho", "kg/m³", "1025 for sea water, 1000 for fresh water"),
                               ("g", "m/s²", "9.81")):
        v = out[key]
        if v is not None and (isinstance(v, bool) or not isinstance(v, (int, float))
                              or not np.isfinite(v) or v <= 0):
            raise ConfigError(f"hydro.{key}: {v!r} is not a positive number; give the "
                              f"{'water density' if key == 'rho' else 'gravity'} in {unit} "
                              f"(e.g. {typical}), or leave the key out to use the database's value")
    if out["bem"] is not None and not isinstance(out["bem"], dict):
        raise ConfigError("hydro.bem: expected a table of BEM settings (see mfm.bemgen)")
    if not isinstance(out["body_coupling"], bool):
        raise ConfigError(f"hydro.body_coupling: {out['body_coupling']!r} is not true or false")
    if out["added_mass_inf"] not in ("consistent", "database"):
        raise ConfigError(f"hydro.added_mass_inf: {out['added_mass_inf']!r}; accepted: "
                          "'consistent', 'database'")
    if out["names"] is not None and (not isinstance(out["names"], list)
                                     or not all(isinstance(n, str) for n in out["names"])):
        raise ConfigError(f"hydro.names: {out['names']!r} is not a list of body names (WAMIT "
                          "bodies in file order)")
    return out


def parse_config(data: dict, source: str = "<config>") -> tuple[dict, list[BodySpec]]:
    """Validate a parsed TOML document. Returns (model options, bodies in tree order)."""
    _unknown(data, TOP_KEYS, source)
    model = data.get("model", {})
    if not isinstance(model, dict):
        raise ConfigError(f"{source}: [model] must be a table")
    _unknown(model, MODEL_KEYS, "model")
    options = {"name": str(model.get("name", Path(source).stem)),
               "gravity": _number(model.get("gravity", 9.81), "model.gravity"),
               "description": str(model.get("description", ""))}
    if options["gravity"] < 0:
        raise ConfigError(f"model.gravity: {options['gravity']} is negative; give the magnitude "
                          "(m/s², gravity acts along −z)")
    raw_bodies = data.get("bodies")
    if not isinstance(raw_bodies, list) or not raw_bodies:
        raise ConfigError(f"{source}: no [[bodies]]; a config needs at least one body")
    bodies = []
    earthed = set()      # bodies given parent = "earth": jointed to the inertial frame on purpose
    for i, raw in enumerate(raw_bodies):
        where = f"bodies[{i}]"
        if not isinstance(raw, dict):
            raise ConfigError(f"{where}: expected a table")
        _unknown(raw, BODY_KEYS, where)
        name = raw.get("name")
        if not isinstance(name, str) or not name:
            raise ConfigError(f"{where}.name: {name!r}; every body needs a non-empty string name")
        where = f"bodies[{i}] ({name!r})"
        if "__" in name or any(c.isspace() for c in name):
            raise ConfigError(f"{where}.name: {name!r} contains '__' or white space; those are "
                              "reserved for hydro dof labels such as 'float__Heave'")
        if "mass" not in raw:
            raise ConfigError(f"{where}.mass: missing (kg, > 0)")
        mass = _number(raw["mass"], f"{where}.mass")
        massless_hull = mass == 0 and isinstance(raw.get("joint"), dict) \
            and raw["joint"].get("type") == "fixed" and raw.get("parent") is not None
        if mass < 0 or (mass == 0 and not massless_hull):
            raise ConfigError(f"{where}.mass: {raw['mass']!r} is not positive; give the mass in kg "
                              "(0 only for a hull welded to its parent, joint type \"fixed\", whose "
                              "mass the parent carries)")
        if "com" not in raw:
            raise ConfigError(f"{where}.com: missing; the centre of mass [x, y, z] in m at q = 0")
        com = _vector(raw["com"], 3, f"{where}.com")
        if massless_hull and not any(k in raw for k in ("inertia", "principal_inertia",
                                                          "radii_of_gyration")):
            inertia = np.zeros((3, 3))   # a massless hull: its `com` is its hydro reference point
        else:
            inertia = _parse_inertia(raw, mass, where)
        if name == EARTH:
            raise ConfigError(f"{where}.name: {name!r} is reserved: parent = \"{EARTH}\" joints a "
                              "body to the inertial frame; give the body another name")
        parent = raw.get("parent")
        if parent is not None and not isinstance(parent, str):
            raise ConfigError(f"{where}.parent: {parent!r} is not a body name")
        if parent == EARTH:
            parent = None
            earthed.add(name)
        if "joint" not in raw:
            raise ConfigError(f"{where}.joint: missing; accepted types: {list(JOINT_KINDS)}")
        joint = _parse_joint(raw["joint"], f"{where}.joint", parent is None)
        # geometry (hull shape for `mfm hydro`) is checked by hydro.geometry when a BEM runs
        extra = {k: raw[k] for k in ("notes", "geometry") if k in raw}
        if "hull" in raw:
            # the closed hull of the nonlinear level (hydro.wetted.hull_mesh), checked here
            from hydro.wetted import hull_mesh

            # a hull of shape "geometry" is placed as `mfm hydro` places the geometry (mfm.bemgen:
            # the axis under the CoM unless its origin says otherwise)
            geometry = raw.get("geometry")
            if isinstance(geometry, dict):
                geometry = {"origin": [float(com[0]), float(com[1]), 0.0], **geometry}
            # a mesh file is read from the config's folder; a config given as a dict or text
            # learns its folder (mfm.load's base) when it loads: its table's keys only, here
            from_file = not source.startswith("<")
            try:
                hull_mesh(raw["hull"], where=f"{where}.hull", geometry=geometry,
                          base=Path(source).parent if from_file else None, read_files=from_file)
            except ValueError as e:
                raise ConfigError(str(e)) from None
            extra["hull"] = dict(raw["hull"])
            extra["hull_geometry"] = geometry
        if "hydro" in raw:
            extra["hydro"] = _parse_body_hydro(raw["hydro"], f"{where}.hydro", name)
        bodies.append(BodySpec(name=name, mass=mass, com=com, inertia=inertia, parent=parent,
                               joint=joint, extra=extra))
    _check_roots(bodies, earthed)
    ordered = tree_order(bodies)
    if "hydro" in data:
        options["hydro"] = _parse_hydro(data["hydro"], source)
    # each load table is checked by its own load (mfm.loads): one place per idea
    options["loads"] = {table: load_class(table).parse_table(data[table], [b.name for b in bodies])
                        for table in LOAD_TABLES if table in data}
    return options, ordered


# parent = "earth": a body jointed to the inertial frame (a revolute, prismatic or fixed root),
# said so where the tree also has floating roots
EARTH = "earth"


def _check_roots(bodies, earthed):
    """A tree with floating roots (free, planar) and a body whose hinge, slider or weld hangs from
    the inertial frame only because its ``parent`` is missing is refused: one root was likely
    meant (RM3's float without ``parent = "spar"`` would slide on the earth, not on the spar). A
    body jointed to the earth on purpose beside floating ones says ``parent = "earth"``."""
    roots = [b for b in bodies if b.parent is None]
    floating = [b.name for b in roots if b.joint.kind in ("free", "planar")]
    hanging = [b for b in roots if b.joint.kind not in ("free", "planar") and b.name not in earthed]
    if floating and hanging:
        b = hanging[0]
        raise ConfigError(
            f"bodies ({b.name!r}): no parent, so its {b.joint.kind} joint hangs from the inertial "
            f"frame, beside the floating root(s) {floating}: a tree with {len(roots)} roots. If "
            f"{b.name!r} is jointed to another body, give parent = \"<that body>\" (e.g. parent = "
            f"\"{floating[0]}\"); if it is jointed to the earth on purpose, give parent = "
            f"\"{EARTH}\"")


def load_config(path: str | Path) -> tuple[dict, list[BodySpec]]:
    """Read and validate a TOML config file: (options, bodies)."""
    _, options, bodies = read_config(path)
    return options, bodies


def read_config_data(data, source: str = "<config>") -> tuple[dict, dict, list[BodySpec]]:
    """:func:`read_config` of a config given in Python: ``data`` a dict (the tables TOML would
    parse to) or a TOML text (a str). ``source`` names it in errors and provenance. Returns (the
    config as a dict, options, bodies)."""
    if isinstance(data, str):
        try:
            data = tomllib.loads(data)
        except tomllib.TOMLDecodeError as e:
            raise ConfigError(f"{source}: not valid TOML: {e}") from None
    elif not isinstance(data, dict):
        raise ConfigError(f"{source}: {type(data).__name__}; give a dict of the config's tables "
                          "or its TOML text")
    options, bodies = parse_config(data, source)
    options["source"] = source
    return data, options, bodies


def read_config(path: str | Path) -> tuple[dict, dict, list[BodySpec]]:
    """Read and validate a TOML config file: (the TOML as read, options, bodies), the file read
    and parsed once for every use (:func:`mfm.io.build.load` and its database check)."""
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise ConfigError(f"config file {str(path)!r} not found") from None
    except IsADirectoryError:
        raise ConfigError(f"config {str(path)!r} is a directory; give a TOML file, e.g. "
                          "configs/rm3.toml") from None
    except UnicodeDecodeError as e:
        raise ConfigError(f"config file {str(path)!r} is not UTF-8 text (byte {e.object[e.start:e.start + 1]!r} "
                          f"at offset {e.start}): a binary file, or the wrong file? A config is a "
                          "TOML text file such as configs/rm3.toml") from None
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as e:
        raise ConfigError(f"{path}: not valid TOML: {e}") from None
    options, bodies = parse_config(data, str(path))
    options["source"] = str(path)
    return data, options, bodies
