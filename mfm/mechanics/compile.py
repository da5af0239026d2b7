"""Validated bodies (in tree order) → a :class:`~mfm.mechanics.model.Model`: static topology, jax-array
parameters. The step of :mod:`mfm.build` that knows nothing of configs or loads."""
from __future__ import annotations

import numpy as np

from ..backend import device_array

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
        axes_list.append(device_array(np.array(body_axes, dtype=float).reshape(-1, 3)))
        points.append(point)
    return Model(
        name=name, body_names=names, parents=tuple(parents), joint_kinds=tuple(kinds),
        motions=tuple(motions), coordinates=tuple(coords),
        # numpy onto the device as it is (backend.device_array: no conversion program each)
        mass=device_array([b.mass for b in bodies], np.float64),
        inertia=device_array(np.stack([b.inertia for b in bodies])),
        com=device_array(np.stack([b.com for b in bodies])),
        joint_point=device_array(np.stack(points)),
        motion_axes=tuple(axes_list),
        gravity=device_array(gravity, np.float64),
        stiffness=device_array(np.array(stiff, dtype=float)),
        damping=device_array(np.array(damp, dtype=float)),
        rest=device_array(np.array(rest, dtype=float)),
    )
