"""Forward kinematics and the B-matrix by walking the tree with frame connections.

Each body c hangs from its parent p by ``E_c = E_p · G_c(q)`` with the joint connection
``G_c = E_{J/p} · Exp(θ₁ξ̂₁) ⋯ Exp(θ_kξ̂_k) · E_{c/J}`` (seed 001 eqs. 6–7): a constant placement of
the joint frame on the parent (parallel to the parent frame, at the joint point), the joint's
elementary motions (unit twists ξ: a rotation axis or a sliding direction), and the constant
placement of the child CoM frame on the joint frame.

Body twists follow by the same walk (seed 001 eqs. 15–27 in SE(3) form): with ``V = (E⁻¹Ė)^∨``,

    V_c = Ad_{G_c⁻¹} V_p + Σ_k θ̇_k Ad_{T_k⁻¹} ξ_k,   T_k = Exp(θ_{k+1}ξ̂_{k+1}) ⋯ Exp(θ_kξ̂_k) E_{c/J},

so the body-twist Jacobian of c is ``Ad_{G_c⁻¹}`` times its parent's plus one column per joint
coordinate. The B-matrix of seed 001 eq. 28 stacks, per body, the CoM velocity in inertial axes
(``R v``) over the angular velocity in body axes (ω): ``X = B(q) q̇`` with X of size 6n.
"""
from __future__ import annotations

from typing import NamedTuple

import jax
import jax.numpy as jnp

from . import se3
from .model import Model


class Kinematics(NamedTuple):
    """Poses and velocity Jacobians at one q.

    E: (n, 4, 4) CoM frame connections (inertial ← body).
    B: (n, 6, n_q) per-body rows of the B-matrix: [ẋ (inertial); ω (body axes)] = B q̇.
    joint_frame: (n, 4, 4) the joint frames E_p · E_{J/p}·(joint motion) at the child side, i.e. the
        frame at the joint point that moves with the child (inertial ← joint).
    """
    E: jnp.ndarray
    B: jnp.ndarray
    joint_frame: jnp.ndarray


def _motion(kind: str, axis, theta):
    if kind == "R":
        return se3.make(se3.so3_exp(axis * theta), jnp.zeros(3))
    return se3.make(jnp.eye(3), axis * theta)


def _unit_twist(kind: str, axis):
    z = jnp.zeros(3)
    return jnp.concatenate([z, axis]) if kind == "R" else jnp.concatenate([axis, z])


def kinematics(model: Model, q) -> Kinematics:
    """Walk the tree once: CoM frames, joint frames and the B-matrix at configuration q."""
    q = jnp.asarray(q, dtype=jnp.float64)
    n_q = model.n_coordinates
    E_list, Bb_list, B_list, J_list = [], [], [], []
    for i in range(model.n_bodies):
        p = model.parents[i]
        E_p = jnp.eye(4) if p < 0 else E_list[p]
        com_p = jnp.zeros(3) if p < 0 else model.com[p]
        E_Jp = se3.make(jnp.eye(3), model.joint_point[i] - com_p)
        E_cJ = se3.make(jnp.eye(3), model.com[i] - model.joint_point[i])
        motions = model.motions[i]
        axes = model.motion_axes[i]
        Ms = [_motion(kind, axes[k], q[qi]) for k, (kind, qi) in enumerate(motions)]
        # tails T_k = M_{k+1} ⋯ M_m E_{c/J}, built from the end
        tails = [None] * len(Ms)
        T = E_cJ
        for k in range(len(Ms) - 1, -1, -1):
            tails[k] = T
            T = Ms[k] @ T
        G = E_Jp @ T  # T is now M_1 ⋯ M_m E_{c/J}
        E_c = E_p @ G
        Bb = jnp.zeros((6, n_q)) if p < 0 else se3.adjoint_inverse(G) @ Bb_list[p]
        for k, (kind, qi) in enumerate(motions):
            col = se3.adjoint_inverse(tails[k]) @ _unit_twist(kind, axes[k])
            Bb = Bb.at[:, qi].add(col)
        R = E_c[:3, :3]
        E_list.append(E_c)
        Bb_list.append(Bb)
        B_list.append(jnp.concatenate([R @ Bb[:3], Bb[3:]], axis=0))
        J_list.append(E_c @ se3.inverse(E_cJ))
    return Kinematics(E=jnp.stack(E_list), B=jnp.stack(B_list), joint_frame=jnp.stack(J_list))


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
