"""Float trees: the validated, host-side description of a multi-body system.

A tree is a list of bodies; each body hangs from its parent (or from the inertial frame, for a
root: usually one, several for bodies that are not connected, such as two floats that interact only
through the water) by a joint. Everything here is plain numpy and Python: it is checked once, when a config
is loaded, and then compiled into a :class:`mfm.mechanics.model.Model` of jax arrays.

Conventions (DESIGN §2): inertial frame with origin on the still-water line, z up. Each body frame
sits at the body's centre of mass and is parallel to the inertial frame at q = 0. Joint axes and
points are given in inertial axes at q = 0.
"""
from __future__ import annotations

import dataclasses
from typing import Sequence

import numpy as np

from ..errors import ConfigError

JOINT_KINDS = ("free", "planar", "revolute", "prismatic", "fixed")
ROOT_DOFS = ("surge", "sway", "heave", "roll", "pitch", "yaw")
PLANAR_DOFS = ("surge", "heave", "pitch")


@dataclasses.dataclass(frozen=True)
class JointSpec:
    """How a body hangs from its parent.

    kind: one of ``JOINT_KINDS``.
    axis: unit vector (3,), inertial axes at q = 0 (revolute: rotation axis, right-handed;
        prismatic: sliding direction). None for free/planar/fixed.
    point: (3,) m, a point on a revolute axis (inertial, q = 0). None otherwise.
    dofs: for free/planar roots, the subset of ``ROOT_DOFS`` that move, in ``ROOT_DOFS`` order.
    stiffness, damping, rest: a linear spring–damper on the joint coordinate(s),
        Q = −stiffness (q − rest) − damping q̇ (N/m, N s/m or N m/rad, N m s/rad). One value per
        coordinate of the joint.
    """

    kind: str
    axis: np.ndarray | None = None
    point: np.ndarray | None = None
    dofs: tuple[str, ...] = ()
    stiffness: np.ndarray = dataclasses.field(default_factory=lambda: np.zeros(0))
    damping: np.ndarray = dataclasses.field(default_factory=lambda: np.zeros(0))
    rest: np.ndarray = dataclasses.field(default_factory=lambda: np.zeros(0))
    locked: bool = False

    @property
    def n_coordinates(self) -> int:
        if self.kind in ("free", "planar"):
            return len(self.dofs)
        return 0 if self.kind == "fixed" else 1


@dataclasses.dataclass(frozen=True)
class BodySpec:
    """One rigid body: mass (kg), centre of mass (3,) m in inertial axes at q = 0, inertia (3, 3)
    kg m² about the CoM in body axes (parallel to inertial at q = 0), parent name (None for the
    root, which hangs from the inertial frame) and joint."""

    name: str
    mass: float
    com: np.ndarray
    inertia: np.ndarray
    parent: str | None
    joint: JointSpec
    extra: dict = dataclasses.field(default_factory=dict, compare=False)


def check_inertia(inertia: np.ndarray, where: str) -> np.ndarray:
    """Check a 3×3 inertia about the CoM: finite, symmetric, positive-definite, and its principal
    moments obeying the triangle inequality I₁ + I₂ ≥ I₃ (a real mass distribution must)."""
    J = np.asarray(inertia, dtype=float)
    if J.shape != (3, 3) or not np.all(np.isfinite(J)):
        raise ConfigError(f"{where}: {J.tolist()} is not a finite 3×3 matrix; give inertia as "
                          "[[Ixx, Ixy, Ixz], [Ixy, Iyy, Iyz], [Ixz, Iyz, Izz]] in kg m²")
    scale = max(np.abs(J).max(), 1e-300)
    if np.abs(J - J.T).max() > 1e-9 * scale:
        raise ConfigError(f"{where}: {J.tolist()} is not symmetric; an inertia tensor must be "
                          "symmetric (check the off-diagonal products of inertia)")
    ev = np.linalg.eigvalsh(0.5 * (J + J.T))
    if ev[0] <= 0.0:
        raise ConfigError(f"{where}: principal moments {ev.tolist()} are not all positive; an "
                          "inertia tensor must be positive-definite")
    if ev[0] + ev[1] < ev[2] * (1.0 - 1e-9):
        raise ConfigError(f"{where}: principal moments {ev.tolist()} violate the triangle "
                          f"inequality ({ev[0]:.6g} + {ev[1]:.6g} < {ev[2]:.6g}); no mass "
                          "distribution has this inertia")
    return 0.5 * (J + J.T)


def tree_order(bodies: Sequence[BodySpec]) -> list[BodySpec]:
    """Validate the topology and return the bodies in tree order (depth-first from the root,
    children in the order given; several roots in the order given, each hanging from the inertial
    frame: two free bodies coupled only through the water). Errors: duplicate names, unknown
    parent, cycles, no root, free/planar joints below a root."""
    names = [b.name for b in bodies]
    seen: set[str] = set()
    for i, n in enumerate(names):
        if n in seen:
            raise ConfigError(f"bodies[{i}].name: {n!r} is used twice; body names must be unique")
        seen.add(n)
    for i, b in enumerate(bodies):
        if b.parent is not None and b.parent not in seen:
            raise ConfigError(f"bodies[{i}] ({b.name!r}).parent: {b.parent!r} is not a body of this "
                              f"tree; known bodies: {names}")
        if b.parent == b.name:
            raise ConfigError(f"bodies[{i}] ({b.name!r}).parent: a body cannot be its own parent")
    roots = [b.name for b in bodies if b.parent is None]
    if not roots:
        raise ConfigError("bodies: no root body (every body has a parent, so the parents form a "
                          f"cycle); leave `parent` out of the body (or bodies) that hang from the "
                          f"inertial frame. Bodies: {names}")
    by_name = {b.name: b for b in bodies}
    # cycle detection: walk up from each body
    for i, b in enumerate(bodies):
        path = [b.name]
        p = b.parent
        while p is not None:
            if p in path:
                cyc = " -> ".join(path[path.index(p):] + [p])
                raise ConfigError(f"bodies[{i}] ({b.name!r}).parent: the parents form a cycle "
                                  f"({cyc}); a float tree must be a tree")
            path.append(p)
            p = by_name[p].parent
    children: dict[str | None, list[BodySpec]] = {}
    for b in bodies:
        children.setdefault(b.parent, []).append(b)
    ordered: list[BodySpec] = []

    def visit(b: BodySpec) -> None:
        ordered.append(b)
        for c in children.get(b.name, []):
            visit(c)

    for r in roots:  # several roots: bodies that each hang from the inertial frame
        visit(by_name[r])
    for i, b in enumerate(bodies):
        if b.parent is not None and b.joint.kind in ("free", "planar"):
            raise ConfigError(f"bodies[{i}] ({b.name!r}).joint.type: {b.joint.kind!r} is only "
                              "allowed for a root body (no parent); below a root use revolute, "
                              "prismatic or fixed, or leave out `parent` to make it a root of its own")
    return ordered
