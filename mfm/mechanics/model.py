"""The compiled model: static topology plus jax-array parameters.

A :class:`Model` is an immutable pytree (an ``equinox.Module``). Its topology — parents, joint kinds,
which coordinate drives which elementary motion — is static metadata, so it is baked into the
compiled code; every physical parameter (masses, inertias, centres of mass, joint points and axes,
spring and damper constants, gravity) is a float64 jax array leaf. Changing a parameter therefore
never recompiles, and a parameter sweep is a ``jax.vmap`` over a batched model.
"""
from __future__ import annotations

import dataclasses
from typing import NamedTuple

import equinox as eqx
import jax.numpy as jnp
import numpy as np

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

    Also: ``hydro`` (static) the :class:`~hydro.prepare.HydroSpec` of a model with water;
    ``loads`` the loads the config gives (moorings, PTOs, body matrices, joint loads, body-point
    outputs: :mod:`mfm.loads`), the water excepted (it is built per sea state); ``source`` and
    ``source_sha256`` (static) the config file and its hash, for provenance.
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
    loads: tuple = ()
    source: str = eqx.field(static=True, default="")
    source_sha256: str = eqx.field(static=True, default="")

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
        return dataclasses.replace(self, **{k: v if k in ("loads", "hydro") else _as_f64(v)
                                            for k, v in changes.items()})

    def keyed(self) -> "Model":
        """This model as compiled functions are handed it: the fields only the host reads (its
        name, config path and hash, its HydroSpec) blanked, so that models differing only in
        numbers share one compilation (static fields are part of jit's key); traced code reads
        none of them (:func:`mfm.loads.assembly.compile_view`)."""
        return dataclasses.replace(self, name="", hydro=None, source="", source_sha256="")

    def set_damping(self, coordinate: str, value) -> "Model":
        return self.replace(damping=self.damping.at[self.coordinate_index(coordinate)].set(value))

    def set_mass(self, body: str, value) -> "Model":
        return self.replace(mass=self.mass.at[self.body_index(body)].set(value))


def _as_f64(v):
    if isinstance(v, tuple):
        return tuple(_as_f64(x) for x in v)
    return jnp.asarray(v, dtype=jnp.float64)
