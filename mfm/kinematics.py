"""Forward kinematics and the B-matrix by walking the tree with frame connections.

Each body c hangs from its parent p by ``E_c = E_p · G_c(q)`` with the joint connection
``G_c = E_{J/p} · Exp(θ₁ξ̂₁) ⋯ Exp(θ_kξ̂_k) · E_{c/J}`` (seed 001 eqs. 6–7): a constant placement of
the joint frame on the parent (parallel to the parent frame, at the joint point), the joint's
elementary motions (unit twists ξ: a rotation axis or a sliding direction), and the constant
placement of the child CoM frame on the joint frame.

Velocities follow by the same walk, one factor at a time (seed 001 eqs. 15–27): a rigid placement
by d adds ω × d to the origin velocity, a revolute motion adds θ̇ a to ω (a = the axis in inertial
axes), a prismatic motion adds θ̇ a to the origin velocity. The B-matrix of seed 001 eq. 28 stacks,
per body, the CoM velocity in inertial axes over the angular velocity in body axes:
``X = B(q) q̇`` with X of size 6n. The same walk gives Ḃ q̇ (the velocity-product accelerations,
from ȧ = ω × a); the jvp of B along q̇ (:func:`b_matrix_dot`) is its independent check.
"""
from __future__ import annotations

from typing import NamedTuple

import jax
import jax.numpy as jnp

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


def _mv(R, v):
    """R v for a 3×3 R, written as a fused multiply–reduce (tiny dots are slow on XLA CPU)."""
    return jnp.sum(R * v[None, :], axis=1)


def _mm(A, B):
    return jnp.sum(A[:, :, None] * B[None, :, :], axis=1)


def _cross_cols(J, d):
    """Column-wise J[:, k] × d for J (3, n_q) and d (3,)."""
    return jnp.stack([J[1] * d[2] - J[2] * d[1], J[2] * d[0] - J[0] * d[2], J[0] * d[1] - J[1] * d[0]])


def _rodrigues(u, theta):
    """Rotation by θ about the unit axis u: I + sin θ û + (1 − cos θ) û²."""
    U = se3.hat(u)
    return jnp.eye(3) + jnp.sin(theta) * U + (1.0 - jnp.cos(theta)) * _mm(U, U)


class _Frame(NamedTuple):
    """A moving frame during the walk: rotation R and origin o (inertial), the origin velocity
    Jacobian Jv and angular velocity Jacobian Jw (inertial axes, (3, n_q)), and, given q̇, the
    velocities v, w and the velocity-product accelerations a (origin) and b (angular)."""
    R: jnp.ndarray
    o: jnp.ndarray
    Jv: jnp.ndarray
    Jw: jnp.ndarray
    v: jnp.ndarray
    w: jnp.ndarray
    a: jnp.ndarray
    b: jnp.ndarray


def _offset(f: _Frame, d) -> _Frame:
    """Rigid placement by d (in the frame's own axes): E ← E · [I, d]."""
    dw = _mv(f.R, d)
    return f._replace(o=f.o + dw, Jv=f.Jv + _cross_cols(f.Jw, dw), v=f.v + jnp.cross(f.w, dw),
                      a=f.a + jnp.cross(f.b, dw) + jnp.cross(f.w, jnp.cross(f.w, dw)))


def _rotate(f: _Frame, u, theta, theta_d, k) -> _Frame:
    """Revolute motion E ← E · Exp(θ (0, u)^): the axis a = R u turns with the frame (ȧ = w × a)."""
    ax = _mv(f.R, u)
    return f._replace(R=_mm(f.R, _rodrigues(u, theta)), Jw=f.Jw.at[:, k].add(ax),
                      w=f.w + ax * theta_d, b=f.b + jnp.cross(f.w, ax) * theta_d)


def _translate(f: _Frame, u, theta, theta_d, k) -> _Frame:
    """Prismatic motion E ← E · Exp(θ (u, 0)^)."""
    ax = _mv(f.R, u)
    d = ax * theta
    wxa = jnp.cross(f.w, ax)
    return f._replace(o=f.o + d, Jv=(f.Jv + _cross_cols(f.Jw, d)).at[:, k].add(ax),
                      v=f.v + jnp.cross(f.w, d) + ax * theta_d,
                      a=f.a + jnp.cross(f.b, d) + jnp.cross(f.w, jnp.cross(f.w, d)) + 2.0 * wxa * theta_d)


def kinematics(model: Model, q, qd=None) -> Kinematics:
    """Walk the tree once: CoM frames, joint frames and the B-matrix at configuration q, and, when
    q̇ is given, the Cartesian velocities X = B q̇ and the velocity-product accelerations Ḃ q̇.

    The walk composes, for each body, the parent's frame with the joint connection
    ``E_{J/p} · Exp(θ₁ξ̂₁) ⋯ Exp(θ_kξ̂_k) · E_{c/J}`` one factor at a time, carrying the velocity
    Jacobians along (seed 001 eqs. 15–27: ẋ_c = ẋ_p + ω_p × s + joint terms, ω_c = ω_p + joint
    terms); the acceleration terms are their time derivatives. Everything is in inertial axes until
    the end, where ω is turned into body axes (ω_body = Rᵀ ω, ω̇_body = Rᵀ ω̇).
    """
    q = jnp.asarray(q, dtype=jnp.float64)
    n_q = model.n_coordinates
    qd_ = jnp.zeros(n_q) if qd is None else jnp.asarray(qd, dtype=jnp.float64)
    z3 = jnp.zeros(3)
    world = _Frame(R=jnp.eye(3), o=z3, Jv=jnp.zeros((3, n_q)), Jw=jnp.zeros((3, n_q)),
                   v=z3, w=z3, a=z3, b=z3)
    frames, joints = [], []
    for i in range(model.n_bodies):
        p = model.parents[i]
        f = world if p < 0 else frames[p]
        com_p = z3 if p < 0 else model.com[p]
        if not model.motions[i]:
            # a welded body: with no motion between them the two placements are one,
            # (j − c_p) + (c − j) = c − c_p (each placement is linear in its offset); the joint
            # frame's pose alone is kept for the outputs, so the walk carries one placement
            joints.append(f._replace(o=f.o + _mv(f.R, model.joint_point[i] - com_p)))
            frames.append(_offset(f, model.com[i] - com_p))
            continue
        f = _offset(f, model.joint_point[i] - com_p)
        for k, (kind, qi) in enumerate(model.motions[i]):
            step = _rotate if kind == "R" else _translate
            f = step(f, model.motion_axes[i][k], q[qi], qd_[qi], qi)
        joints.append(f)
        f = _offset(f, model.com[i] - model.joint_point[i])
        frames.append(f)
    R = jnp.stack([f.R for f in frames])
    x = jnp.stack([f.o for f in frames])
    Rt = jnp.swapaxes(R, 1, 2)
    Jw_body = jnp.sum(Rt[:, :, :, None] * jnp.stack([f.Jw for f in frames])[:, None, :, :], axis=2)
    B = jnp.concatenate([jnp.stack([f.Jv for f in frames]), Jw_body], axis=1)
    E = _pose(R, x)
    J = _pose(jnp.stack([f.R for f in joints]), jnp.stack([f.o for f in joints]))
    if qd is None:
        return Kinematics(E=E, B=B, joint_frame=J)
    w_body = jnp.sum(Rt * jnp.stack([f.w for f in frames])[:, None, :], axis=2)
    b_body = jnp.sum(Rt * jnp.stack([f.b for f in frames])[:, None, :], axis=2)
    X = jnp.concatenate([jnp.stack([f.v for f in frames]), w_body], axis=1)
    bias = jnp.concatenate([jnp.stack([f.a for f in frames]), b_body], axis=1)
    return Kinematics(E=E, B=B, joint_frame=J, X=X, bias=bias)


def _pose(R, x):
    top = jnp.concatenate([R, x[:, :, None]], axis=2)
    bottom = jnp.broadcast_to(jnp.array([0.0, 0.0, 0.0, 1.0]), (R.shape[0], 1, 4))
    return jnp.concatenate([top, bottom], axis=1)


def b_matrix(model: Model, q) -> jnp.ndarray:
    """The B-matrix (6n, n_q) of seed 001 eq. 28: ``X = B(q) q̇`` with X stacking, per body in tree
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
