"""Forward kinematics and the B-matrix by walking the tree with frame connections.

Each body c hangs from its parent p by ``E_c = E_p · G_c(q)`` with the joint connection
``G_c = E_{J/p} · Exp(θ₁ξ̂₁) ⋯ Exp(θ_kξ̂_k) · E_{c/J}`` (Lande-Sudall et al. eqs. 6–7): a constant placement of
the joint frame on the parent (parallel to the parent frame, at the joint point), the joint's
elementary motions (unit twists ξ: a rotation axis or a sliding direction), and the constant
placement of the child CoM frame on the joint frame.

Velocities follow by the same walk, one factor at a time (Lande-Sudall et al. eqs. 15–27): a rigid placement
by d adds ω × d to the origin velocity, a revolute motion adds θ̇ a to ω (a = the axis in inertial
axes), a prismatic motion adds θ̇ a to the origin velocity. The B-matrix of Lande-Sudall et al. eq. 28 stacks,
per body, the CoM velocity in inertial axes over the angular velocity in body axes:
``X = B(q) q̇`` with X of size 6n. The same walk gives Ḃ q̇ (the velocity-product accelerations,
from ȧ = ω × a); the jvp of B along q̇ (:func:`b_matrix_dot`) is its independent check.
"""
from __future__ import annotations

import functools
from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from . import se3
from .model import Model


class Kinematics(NamedTuple):
    """Poses, velocity Jacobians and (given q̇) velocities at one state.

    E: (n, 4, 4) CoM frame connections (inertial ← body).
    B: (n, 6, n_q) per-body rows of the B-matrix: [ẋ (inertial); ω (body axes)] = B q̇.
    joint_frame: (n, 4, 4) the joint frame on the child side (at the joint point, after the joint
        motion; inertial ← joint).
    X: (n, 6) Cartesian velocities B q̇, or None when q̇ was not given.
    bias: (n, 6) Ḃ q̇, the velocity-product part of the Cartesian accelerations (Ẋ = B q̈ + Ḃ q̇),
        or None when q̇ was not given.
    """
    E: jnp.ndarray
    B: jnp.ndarray
    joint_frame: jnp.ndarray
    X: jnp.ndarray | None = None
    bias: jnp.ndarray | None = None


_mv = se3.rotate


def _mm(A, B):
    return jnp.sum(A[..., :, :, None] * B[..., None, :, :], axis=-2)


def _cross(a, b):
    return jnp.cross(a, b, axis=-1)


def _cross_cols(J, d):
    """Column-wise J[..., :, k] × d for J (..., 3, n_q) and d (..., 3)."""
    d = d[..., :, None]
    return jnp.stack([J[..., 1, :] * d[..., 2, :] - J[..., 2, :] * d[..., 1, :],
                      J[..., 2, :] * d[..., 0, :] - J[..., 0, :] * d[..., 2, :],
                      J[..., 0, :] * d[..., 1, :] - J[..., 1, :] * d[..., 0, :]], axis=-2)


def _rodrigues(u, theta):
    """Rotations by θ (m,) about the unit axes u (m, 3): I + sin θ û + (1 − cos θ) û²."""
    U = jax.vmap(se3.hat)(u)
    s, c = jnp.sin(theta)[:, None, None], (1.0 - jnp.cos(theta))[:, None, None]
    return jnp.eye(3) + s * U + c * _mm(U, U)


class _Frame(NamedTuple):
    """The moving frames of a group of bodies during the walk, stacked (m bodies): rotations R
    (m, 3, 3) and origins o (m, 3) (inertial), origin-velocity and angular-velocity Jacobians Jv, Jw
    (m, 3, n_q) (inertial axes), and, given q̇, the velocities v, w and the velocity-product
    accelerations a (origin) and b (angular), each (m, 3)."""
    R: jnp.ndarray
    o: jnp.ndarray
    Jv: jnp.ndarray
    Jw: jnp.ndarray
    v: jnp.ndarray
    w: jnp.ndarray
    a: jnp.ndarray
    b: jnp.ndarray


def _offset(f: _Frame, d) -> _Frame:
    """Rigid placement by d (m, 3) (in each frame's own axes): E ← E · [I, d]."""
    dw = _mv(f.R, d)
    wxd = _cross(f.w, dw)
    return f._replace(o=f.o + dw, Jv=f.Jv + _cross_cols(f.Jw, dw), v=f.v + wxd,
                      a=f.a + _cross(f.b, dw) + _cross(f.w, wxd))


def _rotate(f: _Frame, u, theta, theta_d, onehot) -> _Frame:
    """Revolute motions E ← E · Exp(θ (0, u)^): the axis a = R u turns with the frame (ȧ = w × a).
    ``onehot`` (m, n_q) marks each body's coordinate."""
    ax = _mv(f.R, u)
    return f._replace(R=_mm(f.R, _rodrigues(u, theta)), Jw=f.Jw + ax[:, :, None] * onehot[:, None, :],
                      w=f.w + ax * theta_d[:, None], b=f.b + _cross(f.w, ax) * theta_d[:, None])


def _translate(f: _Frame, u, theta, theta_d, onehot) -> _Frame:
    """Prismatic motions E ← E · Exp(θ (u, 0)^)."""
    ax = _mv(f.R, u)
    d = ax * theta[:, None]
    wxa = _cross(f.w, ax)
    wxd = _cross(f.w, d)
    return f._replace(o=f.o + d,
                      Jv=f.Jv + _cross_cols(f.Jw, d) + ax[:, :, None] * onehot[:, None, :],
                      v=f.v + wxd + ax * theta_d[:, None],
                      a=f.a + _cross(f.b, d) + _cross(f.w, wxd) + 2.0 * wxa * theta_d[:, None])


class _Group(NamedTuple):
    """Bodies of one tree level that share the kinds of their joint's motions (static)."""
    bodies: tuple[int, ...]
    parents: tuple[int, ...]
    kinds: tuple[str, ...]                      # "R" | "T" per motion, in chain order
    coords: tuple[tuple[int, ...], ...]         # per motion, the coordinate of each body


@functools.lru_cache(maxsize=256)
def _groups(parents: tuple[int, ...], motions) -> tuple[_Group, ...]:
    """The walk's schedule: bodies grouped by tree level, then by the kinds of their motions.

    A group's bodies are placed together, one stacked operation per factor of the joint
    connection, so the walk costs one body's operations per group rather than per body: XLA on a
    CPU pays a fixed fraction of a microsecond per kernel whatever its size (benchmarks/RESULTS.md).
    """
    depth = []
    for p in parents:
        depth.append(0 if p < 0 else depth[p] + 1)
    keys = {}
    for i, (d, mo) in enumerate(zip(depth, motions)):
        keys.setdefault((d, tuple(k for k, _ in mo)), []).append(i)
    out = []
    for (d, kinds), bodies in sorted(keys.items(), key=lambda kv: (kv[0][0], kv[1][0])):
        coords = tuple(tuple(motions[i][k][1] for i in bodies) for k in range(len(kinds)))
        out.append(_Group(tuple(bodies), tuple(parents[i] for i in bodies), kinds, coords))
    return tuple(out)


def _take(arrays, rows):
    """Rows of a stack (static indices): a slice or a broadcast where the indices allow one."""
    rows = np.asarray(rows)
    if len(set(rows.tolist())) == 1:
        return jnp.broadcast_to(arrays[rows[0]], (len(rows),) + arrays.shape[1:])
    if np.array_equal(rows, np.arange(rows[0], rows[0] + len(rows))):
        return arrays[rows[0]:rows[0] + len(rows)]
    return arrays[rows]


def kinematics(model: Model, q, qd=None) -> Kinematics:
    """Walk the tree once: CoM frames, joint frames and the B-matrix at configuration q, and, when
    q̇ is given, the Cartesian velocities X = B q̇ and the velocity-product accelerations Ḃ q̇.

    The walk composes, for each body, the parent's frame with the joint connection
    ``E_{J/p} · Exp(θ₁ξ̂₁) ⋯ Exp(θ_kξ̂_k) · E_{c/J}`` one factor at a time, carrying the velocity
    Jacobians along (Lande-Sudall et al. eqs. 15–27: ẋ_c = ẋ_p + ω_p × s + joint terms, ω_c = ω_p + joint
    terms); the acceleration terms are their time derivatives. Everything is in inertial axes until
    the end, where ω is turned into body axes (ω_body = Rᵀ ω, ω̇_body = Rᵀ ω̇). The bodies of one
    tree level with the same kinds of motion are walked together (:func:`_groups`).
    """
    q = jnp.asarray(q, dtype=jnp.float64)
    n, n_q = model.n_bodies, model.n_coordinates
    qd_ = jnp.zeros(n_q) if qd is None else jnp.asarray(qd, dtype=jnp.float64)
    groups = _groups(model.parents, model.motions)
    where = {}                     # body -> (group number, row in the group)
    done, joints = [], []
    for g in groups:
        m = len(g.bodies)
        b = np.asarray(g.bodies)
        if g.parents[0] < 0:       # a level holds either roots or children, never both
            z = jnp.zeros((m, 3))
            f = _Frame(R=jnp.broadcast_to(jnp.eye(3), (m, 3, 3)), o=z, Jv=jnp.zeros((m, 3, n_q)),
                       Jw=jnp.zeros((m, 3, n_q)), v=z, w=z, a=z, b=z)
            com_p = jnp.zeros((m, 3))
        else:
            src = sorted({where[p][0] for p in g.parents})
            base = np.cumsum([0] + [len(groups[s].bodies) for s in src])
            rows = [base[src.index(where[p][0])] + where[p][1] for p in g.parents]
            parts = [done[s] for s in src]
            stacked = parts[0] if len(parts) == 1 else _Frame(
                *(jnp.concatenate(x) for x in zip(*parts)))
            f = _Frame(*(_take(x, rows) for x in stacked))
            com_p = model.com[np.asarray(g.parents)]
        if not g.kinds:
            # welded bodies: with no motion between them the two placements are one,
            # (j − c_p) + (c − j) = c − c_p (each placement is linear in its offset); the joint
            # frame's pose alone is kept for the outputs, so the walk carries one placement
            joints.append(f._replace(o=f.o + _mv(f.R, model.joint_point[b] - com_p)))
            f = _offset(f, model.com[b] - com_p)
        else:
            f = _offset(f, model.joint_point[b] - com_p)
            for k, kind in enumerate(g.kinds):
                c = np.asarray(g.coords[k])
                u = jnp.stack([model.motion_axes[i][k] for i in g.bodies])
                onehot = np.eye(n_q)[c]
                step = _rotate if kind == "R" else _translate
                f = step(f, u, q[c], qd_[c], onehot)
            joints.append(f)
            f = _offset(f, model.com[b] - model.joint_point[b])
        for r, i in enumerate(g.bodies):
            where[i] = (len(done), r)
        done.append(f)
    order = np.argsort(np.concatenate([np.asarray(g.bodies) for g in groups]))
    whole = [x[order] if len(groups) > 1 else x for x in
             (jnp.concatenate(x) for x in zip(*done))]
    fr = _Frame(*whole)
    jR = jnp.concatenate([j.R for j in joints])[order]
    jo = jnp.concatenate([j.o for j in joints])[order]
    R, x = fr.R, fr.o
    Rt = jnp.swapaxes(R, 1, 2)
    Jw_body = jnp.sum(Rt[:, :, :, None] * fr.Jw[:, None, :, :], axis=2)
    B = jnp.concatenate([fr.Jv, Jw_body], axis=1)
    E = _pose(R, x)
    J = _pose(jR, jo)
    if qd is None:
        return Kinematics(E=E, B=B, joint_frame=J)
    w_body = jnp.sum(Rt * fr.w[:, None, :], axis=2)
    b_body = jnp.sum(Rt * fr.b[:, None, :], axis=2)
    X = jnp.concatenate([fr.v, w_body], axis=1)
    bias = jnp.concatenate([fr.a, b_body], axis=1)
    return Kinematics(E=E, B=B, joint_frame=J, X=X, bias=bias)


def _pose(R, x):
    top = jnp.concatenate([R, x[:, :, None]], axis=2)
    bottom = jnp.broadcast_to(jnp.array([0.0, 0.0, 0.0, 1.0]), (R.shape[0], 1, 4))
    return jnp.concatenate([top, bottom], axis=1)


def b_matrix(model: Model, q) -> jnp.ndarray:
    """The B-matrix (6n, n_q) of Lande-Sudall et al. eq. 28: ``X = B(q) q̇`` with X stacking, per body in tree
    order, the CoM velocity (inertial axes, m/s) and the angular velocity (body axes, rad/s)."""
    B = kinematics(model, q).B
    return B.reshape(6 * model.n_bodies, model.n_coordinates)


def b_matrix_dot(model: Model, q, qd) -> jnp.ndarray:
    """Ḃ = dB/dt along q̇: the jvp of :func:`b_matrix` (exact, no hand derivation)."""
    return jax.jvp(lambda x: b_matrix(model, x), (jnp.asarray(q, jnp.float64),),
                   (jnp.asarray(qd, jnp.float64),))[1]


def body_poses(model: Model, q):
    """CoM positions (n, 3) m and rotation matrices (n, 3, 3) (inertial ← body) at q."""
    E = kinematics(model, q).E
    return E[:, :3, 3], E[:, :3, :3]
