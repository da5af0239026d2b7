"""The compiled model: static topology plus jax-array parameters.

A :class:`Model` is an immutable pytree (an ``equinox.Module``). Its topology — parents, joint kinds,
which coordinate drives which elementary motion — is static metadata, so it is baked into the
compiled code; every physical parameter (masses, inertias, centres of mass, joint points and axes,
spring and damper constants, gravity) is a float64 jax array leaf. Changing a parameter therefore
never recompiles, and a parameter sweep is a ``jax.vmap`` over a batched model.
"""
from __future__ import annotations

import dataclasses
from pathlib import Path
from typing import NamedTuple

import equinox as eqx
import jax.numpy as jnp
import numpy as np

from .config import load_config
from .tree import BodySpec

# Elementary motions of a root joint in chain order: translations along inertial x, y, z, then the
# intrinsic rotations yaw (z), pitch (y), roll (x), so that R = R_z(yaw) R_y(pitch) R_x(roll).
_ROOT_CHAIN = (("surge", "T", (1.0, 0.0, 0.0)), ("sway", "T", (0.0, 1.0, 0.0)),
               ("heave", "T", (0.0, 0.0, 1.0)), ("yaw", "R", (0.0, 0.0, 1.0)),
               ("pitch", "R", (0.0, 1.0, 0.0)), ("roll", "R", (1.0, 0.0, 0.0)))


class Joint(NamedTuple):
    kind: str
    axis: np.ndarray | None
    point: np.ndarray | None
    coordinates: tuple[str, ...]


class Body(NamedTuple):
    """Read-only view of one body of a model (host side)."""
    name: str
    parent: str | None
    mass: float
    com: np.ndarray
    inertia: np.ndarray
    joint: Joint


class Model(eqx.Module):
    """A compiled float tree.

    Static: ``name``, ``body_names``, ``parents`` (index of each body's parent, −1 for the inertial
    frame), ``joint_kinds``, ``motions`` (per body, the joint's elementary motions in chain order as
    ``("R" | "T", coordinate index)``), ``coordinates`` (names of q).

    Arrays (float64): ``mass`` (n,) kg; ``inertia`` (n, 3, 3) kg m² about the CoM, body axes;
    ``com`` (n, 3) m, inertial at q = 0; ``joint_point`` (n, 3) m, the joint frame origin in inertial
    axes at q = 0 (the CoM for free, planar, prismatic and fixed joints); ``motion_axes``: per body an
    array (k, 3) of unit axes in the joint frame (parallel to inertial at q = 0); ``gravity`` m/s²
    (scalar, along −z); ``stiffness``, ``damping``, ``rest`` (n_q,) of the joint spring–dampers.
    """

    name: str = eqx.field(static=True)
    body_names: tuple[str, ...] = eqx.field(static=True)
    parents: tuple[int, ...] = eqx.field(static=True)
    joint_kinds: tuple[str, ...] = eqx.field(static=True)
    motions: tuple[tuple[tuple[str, int], ...], ...] = eqx.field(static=True)
    coordinates: tuple[str, ...] = eqx.field(static=True)
    mass: jnp.ndarray
    inertia: jnp.ndarray
    com: jnp.ndarray
    joint_point: jnp.ndarray
    motion_axes: tuple[jnp.ndarray, ...]
    gravity: jnp.ndarray
    stiffness: jnp.ndarray
    damping: jnp.ndarray
    rest: jnp.ndarray
    hydro: object = eqx.field(static=True, default=None)
    moorings: object = None
    ptos: object = None

    @property
    def n_bodies(self) -> int:
        return len(self.body_names)

    @property
    def n_coordinates(self) -> int:
        return len(self.coordinates)

    def body_index(self, name: str) -> int:
        try:
            return self.body_names.index(name)
        except ValueError:
            raise KeyError(f"body {name!r} is not in model {self.name!r}; bodies: "
                           f"{list(self.body_names)}") from None

    def coordinate_index(self, name: str) -> int:
        try:
            return self.coordinates.index(name)
        except ValueError:
            raise KeyError(f"coordinate {name!r} is not in model {self.name!r}; coordinates: "
                           f"{list(self.coordinates)}") from None

    def joint_coordinates(self, body: str | int) -> tuple[int, ...]:
        """Indices into q of the coordinates of a body's joint (in q order)."""
        i = body if isinstance(body, int) else self.body_index(body)
        return tuple(sorted(k for _, k in self.motions[i]))

    @property
    def bodies(self) -> tuple[Body, ...]:
        """Per-body view: name, parent, mass, com, inertia and joint (kind, axis, point, coords)."""
        out = []
        for i, name in enumerate(self.body_names):
            kind = self.joint_kinds[i]
            axis = point = None
            if kind in ("revolute", "prismatic"):
                axis = np.asarray(self.motion_axes[i][0])
            if kind == "revolute":
                point = np.asarray(self.joint_point[i])
            coords = tuple(self.coordinates[k] for k in self.joint_coordinates(i))
            p = self.parents[i]
            out.append(Body(name=name, parent=None if p < 0 else self.body_names[p],
                            mass=float(self.mass[i]), com=np.asarray(self.com[i]),
                            inertia=np.asarray(self.inertia[i]),
                            joint=Joint(kind=kind, axis=axis, point=point, coordinates=coords)))
        return tuple(out)

    def replace(self, **changes) -> "Model":
        """A copy with some array parameters replaced (e.g. ``model.replace(damping=d)``)."""
        return dataclasses.replace(self, **{k: _as_f64(v) for k, v in changes.items()})

    def set_damping(self, coordinate: str, value) -> "Model":
        return self.replace(damping=self.damping.at[self.coordinate_index(coordinate)].set(value))

    def set_mass(self, body: str, value) -> "Model":
        return self.replace(mass=self.mass.at[self.body_index(body)].set(value))


def _as_f64(v):
    if isinstance(v, tuple):
        return tuple(_as_f64(x) for x in v)
    return jnp.asarray(v, dtype=jnp.float64)


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
        (database, reference points, drag; see :mod:`mfm.water`); False gives the mechanics-only
        model (bodies, joints, joint spring–dampers, moorings, gravity).
    body_coupling: overrides ``hydro.body_coupling`` (hydrodynamic interaction between bodies: the
        cross-body blocks of A∞, A(ω), B(ω) and K).
    """
    options, bodies = load_config(path)
    model = compile_tree(bodies, name=options["name"], gravity=options["gravity"])
    if options["moorings"]:
        from .loads import PointSprings
        from .points import BodyPoints

        M = options["moorings"]
        model = dataclasses.replace(model, moorings=PointSprings(
            points=BodyPoints.on_bodies(model.com, [model.body_index(m["body"]) for m in M],
                                        [m["point"] for m in M]),
            stiffness=jnp.asarray(np.stack([m["stiffness"] for m in M]))))
    if options["ptos"]:
        from .points import BodyPoints
        from .ptos import HydraulicPTO

        P = options["ptos"]
        ia = [model.body_index(p["body"]) for p in P]
        ib = [model.body_index(p["anchor_body"]) if p["anchor_body"] else 0 for p in P]
        model = dataclasses.replace(model, ptos=HydraulicPTO(
            a=BodyPoints.on_bodies(model.com, ia, [p["point"] for p in P]),
            b=BodyPoints.on_bodies(model.com, ib, [p["anchor"] for p in P]),
            mu=jnp.asarray([p["mu"] for p in P]), beta=jnp.asarray([p["beta"] for p in P]),
            kappa=jnp.asarray([p["kappa"] for p in P]),
            length0=jnp.asarray([np.linalg.norm(p["point"] - p["anchor"]) for p in P]),
            b_fixed=tuple(p["anchor_body"] is None for p in P), names=tuple(p["name"] for p in P)))
    if hydro and "hydro" in options:
        from .water import load_hydro_spec

        model = dataclasses.replace(model, hydro=load_hydro_spec(
            model, bodies, options["hydro"], Path(path).parent, body_coupling))
    return model
