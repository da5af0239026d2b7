"""Config → tree → model: the one place that assembles a :class:`~mfm.model.Model`.

:func:`load` reads and checks a TOML config (:mod:`mfm.config`), compiles the body tree
(:func:`compile_tree`), attaches the water's :class:`~hydro.prepare.HydroSpec` when the config has
a ``[hydro]`` table, and adds the loads of its other tables through the registry
(:mod:`mfm.loads.registry`): data flow one way, and the model type knows nothing of how it is made.
"""
from __future__ import annotations

import dataclasses
import hashlib
import warnings
from pathlib import Path

import jax.numpy as jnp
import numpy as np

from .config import load_config
from .loads.registry import TABLES, load_class
from .model import Model
from .tree import BodySpec

# Elementary motions of a root joint in chain order: translations along inertial x, y, z, then the
# intrinsic rotations yaw (z), pitch (y), roll (x), so that R = R_z(yaw) R_y(pitch) R_x(roll).
_ROOT_CHAIN = (("surge", "T", (1.0, 0.0, 0.0)), ("sway", "T", (0.0, 1.0, 0.0)),
               ("heave", "T", (0.0, 0.0, 1.0)), ("yaw", "R", (0.0, 0.0, 1.0)),
               ("pitch", "R", (0.0, 1.0, 0.0)), ("roll", "R", (1.0, 0.0, 0.0)))


def compile_tree(bodies: list[BodySpec], *, name: str = "model", gravity: float = 9.81) -> Model:
    """Compile validated bodies (in tree order) into a :class:`Model`."""
    names = tuple(b.name for b in bodies)
    index = {n: i for i, n in enumerate(names)}
    parents, kinds, motions, axes_list, points, coords = [], [], [], [], [], []
    stiff, damp, rest = [], [], []
    for b in bodies:
        parents.append(-1 if b.parent is None else index[b.parent])
        j = b.joint
        kinds.append(j.kind)
        body_motions, body_axes = [], []
        if j.kind in ("free", "planar"):
            start = len(coords)
            for dof in j.dofs:  # coordinates in ROOT_DOFS order
                coords.append(f"{b.name}.{dof}")
            for dof, mkind, ax in _ROOT_CHAIN:  # motions in chain order
                if dof in j.dofs:
                    body_motions.append((mkind, start + j.dofs.index(dof)))
                    body_axes.append(ax)
            point = b.com
        elif j.kind in ("revolute", "prismatic"):
            coords.append(f"{b.name}.{'angle' if j.kind == 'revolute' else 'stroke'}")
            body_motions.append(("R" if j.kind == "revolute" else "T", len(coords) - 1))
            body_axes.append(tuple(j.axis))
            point = j.point if j.kind == "revolute" else b.com
        else:  # fixed
            point = b.com
        stiff.extend(j.stiffness)
        damp.extend(j.damping)
        rest.extend(j.rest)
        motions.append(tuple(body_motions))
        axes_list.append(jnp.asarray(np.array(body_axes, dtype=float).reshape(-1, 3)))
        points.append(point)
    return Model(
        name=name, body_names=names, parents=tuple(parents), joint_kinds=tuple(kinds),
        motions=tuple(motions), coordinates=tuple(coords),
        mass=jnp.asarray([b.mass for b in bodies], dtype=jnp.float64),
        inertia=jnp.asarray(np.stack([b.inertia for b in bodies])),
        com=jnp.asarray(np.stack([b.com for b in bodies])),
        joint_point=jnp.asarray(np.stack(points)),
        motion_axes=tuple(axes_list),
        gravity=jnp.asarray(gravity, dtype=jnp.float64),
        stiffness=jnp.asarray(np.array(stiff, dtype=float)),
        damping=jnp.asarray(np.array(damp, dtype=float)),
        rest=jnp.asarray(np.array(rest, dtype=float)),
    )


def load(path: str | Path, hydro: bool = True, body_coupling: bool | None = None) -> Model:
    """Load a TOML float-tree config and compile it.

    hydro: with True (default) and a ``[hydro]`` table in the config, the model carries its water
        (database, reference points, drag; see :mod:`mfm.loads.water`); False gives the
        mechanics-only model (bodies, joints, joint spring–dampers, the config's other loads).
    body_coupling: overrides ``hydro.body_coupling`` (hydrodynamic interaction between bodies: the
        cross-body blocks of A∞, A(ω), B(ω) and K); True, False or None (the config's value).
    """
    if not isinstance(hydro, bool):
        raise ValueError(f"hydro: {hydro!r}; accepted: True (with the config's [hydro] table) or False")
    if body_coupling is not None and not isinstance(body_coupling, bool):
        raise ValueError(f"body_coupling: {body_coupling!r}; accepted: True, False or None (the "
                         "config's hydro.body_coupling)")
    options, bodies = load_config(path)
    model = compile_tree(bodies, name=options["name"], gravity=options["gravity"])
    model = dataclasses.replace(model, source=str(path),
                                source_sha256=hashlib.sha256(Path(path).read_bytes()).hexdigest())
    if hydro and "hydro" in options:
        from hydro.database import HydroDatabaseWarning

        from .bemgen import database_is_stale
        from .loads.water import load_hydro_spec

        # a database made from other hulls or BEM settings than the config has now
        stale, why = database_is_stale(path)
        if stale:
            warnings.warn(why, HydroDatabaseWarning, stacklevel=2)
        model = dataclasses.replace(model, hydro=load_hydro_spec(
            model, bodies, options["hydro"], Path(path).parent, body_coupling))
    # loads in registry order; each sees the model with the loads before it (a damping ratio is
    # set from the linearisation of the model as built so far)
    for table in TABLES:
        parsed = options.get("loads", {}).get(table)
        if parsed:
            model = dataclasses.replace(model, loads=model.loads + (load_class(table).from_parsed(parsed, model),))
    return model
