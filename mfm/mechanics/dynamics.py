"""MFM equations of motion (Lande-Sudall et al. eq. 46), generalised forces and joint reaction loads.

    M* q̈ = Bᵀ F + Q − N* q̇,   M* = Bᵀ M B,   N* = Bᵀ (M Ḃ + D M B)

with M = blockdiag(m_i I₃, J_i) (J_i about the CoM, body axes) and D = blockdiag(0, ω̂_i), the
gyroscopic term. F stacks Cartesian loads per body (force in inertial axes, moment about the CoM in
body axes). Q holds loads acting directly on joint coordinates (a rotary PTO torque on a hinge does
virtual power τ θ̇_rel, so it enters Q without reaching F). Gravity acts exactly as the weights
m_i g at the CoMs through Bᵀ.
"""
from __future__ import annotations

from typing import NamedTuple

import jax
import jax.numpy as jnp

from .. import backend as _xla
from . import se3
from .kinematics import Kinematics, kinematics
from .model import Model


def body_mass_blocks(model: Model) -> jnp.ndarray:
    """M_i = blockdiag(m_i I₃, J_i), shape (n, 6, 6)."""
    n = model.n_bodies
    M = jnp.zeros((n, 6, 6))
    M = M.at[:, :3, :3].set(model.mass[:, None, None] * jnp.eye(3))
    return M.at[:, 3:, 3:].set(model.inertia)


def mass_matrix(model: Model, q) -> jnp.ndarray:
    """M*(q) = Bᵀ M B, shape (n_q, n_q), symmetric positive-definite."""
    B = kinematics(model, q).B
    return jnp.einsum("nai,naj->ij", B, _apply_mass(model, B))


def gyroscopic(model: Model, X) -> jnp.ndarray:
    """D M X per body, (n, 6): zero force, ω × (J ω) moment in body axes."""
    w = X[:, 3:]
    Jw = jnp.sum(model.inertia * w[:, None, :], axis=2)
    return jnp.concatenate([jnp.zeros_like(w), jnp.cross(w, Jw)], axis=1)


def coriolis_matrix(model: Model, q, qd) -> jnp.ndarray:
    """N*(q, q̇) = Bᵀ (M Ḃ + D M B), shape (n_q, n_q) (Lande-Sudall et al. eq. 46)."""
    q = jnp.asarray(q, jnp.float64)
    qd = jnp.asarray(qd, jnp.float64)
    B, Bdot = jax.jvp(lambda x: kinematics(model, x).B, (q,), (qd,))
    Mb = body_mass_blocks(model)
    X = jnp.einsum("nai,i->na", B, qd)
    w = X[:, 3:]
    D = jnp.zeros((model.n_bodies, 6, 6)).at[:, 3:, 3:].set(jax.vmap(se3.hat)(w))
    inner = jnp.einsum("nab,nbi->nai", Mb, Bdot) + jnp.einsum("nab,nbc,nci->nai", D, Mb, B)
    return jnp.einsum("naj,nai->ji", B, inner)


def gravity_loads(model: Model) -> jnp.ndarray:
    """Weights m_i g (−z, inertial) at each CoM, as Cartesian loads (n, 6)."""
    F = jnp.zeros((model.n_bodies, 6))
    return F.at[:, 2].set(-model.mass * model.gravity)


def joint_loads(model: Model, q, qd) -> jnp.ndarray:
    """Q of the joint spring–dampers: −k (q − rest) − c q̇, shape (n_q,)."""
    return -model.stiffness * (q - model.rest) - model.damping * qd


class Evaluation(NamedTuple):
    """Everything one evaluation of the equations of motion produces (for outputs and reactions)."""
    qdd: jnp.ndarray        # (n_q,)
    kin: Kinematics
    X: jnp.ndarray          # (n, 6) Cartesian velocities
    Xdot: jnp.ndarray       # (n, 6) Cartesian accelerations [ẍ inertial; ω̇ body]
    F: jnp.ndarray          # (n, 6) Cartesian loads applied (gravity + external)
    Q: jnp.ndarray          # (n_q,) loads on coordinates (joint springs/dampers + external)


def evaluate(model: Model, q, qd, tau=None, body_loads=None, extra_mass=None,
             kin: Kinematics | None = None) -> Evaluation:
    """Solve M* q̈ = Bᵀ F + Q − N* q̇ at one state.

    tau: (n_q,) extra generalised force; body_loads: (n, 6) extra Cartesian loads (force inertial,
    moment about the CoM in body axes); extra_mass: (n_q, n_q) acceleration-proportional terms moved
    to the left-hand side (e.g. Hᵀ A∞ H); kin: the kinematics at q if already computed.
    """
    q = jnp.asarray(q, jnp.float64)
    qd = jnp.asarray(qd, jnp.float64)
    if kin is None or kin.bias is None:
        kin = kinematics(model, q, qd)
    B, X, bias = kin.B, kin.X, kin.bias
    F = gravity_loads(model)
    if body_loads is not None:
        F = F + body_loads
    Q = joint_loads(model, q, qd)
    if tau is not None:
        Q = Q + tau
    MB = _apply_mass(model, B)                                    # M B, (n, 6, n_q)
    # the products with B as multiply–reduces (se3.rotate says why); M* only while small
    Mstar = se3.matmul_small(B, MB, transpose_x=True)
    if extra_mass is not None:
        Mstar = Mstar + extra_mass
    G = F - _apply_mass(model, bias) - gyroscopic(model, X)
    rhs = jnp.sum(B * G[:, :, None], axis=(0, 1)) + Q
    qdd = spd_solve(Mstar, rhs)
    Xdot = jnp.sum(B * qdd, axis=2) + bias
    return Evaluation(qdd=qdd, kin=kin, X=X, Xdot=Xdot, F=F, Q=Q)


# up to this size the solve is unrolled elimination (n fused kernels); above it, a Cholesky
# factorisation and two triangular solves (three library calls of ~1 µs each on XLA CPU whatever
# n). With the time loop compiled whole (mfm.runner.xla) library calls are not allowed in it at all (they
# would send it back to kernel-by-kernel dispatch), so elimination goes further there.
_UNROLLED_SOLVE = 64 if _xla.LOOPS_COMPILED_WHOLE else 12


def spd_solve(A, b):
    """x = A⁻¹ b for a symmetric positive-definite A (n, n), b (n,).

    For n ≤ 12 (n ≤ 64 with the time loop compiled whole, :mod:`mfm.runner.xla`) by Gauss–Jordan elimination without pivoting, unrolled: the k-th step takes row k
    over its pivot and removes column k from the others, [A | b] ← [A | b] − (a_k − e_k) r_k / a_kk
    (a_k the k-th column, r_k the k-th row, so that row k becomes r_k / a_kk). No pivoting is
    needed: every pivot of an SPD matrix is positive (a ratio of leading principal minors) and the
    elimination is backward stable for SPD matrices. Measured 0.7 µs against 1.8 µs for Cholesky
    at n = 7 (XLA CPU, one core). Larger n: Cholesky (LAPACK). A singular matrix gives non-finite values
    either way (a zero pivot); M* + HᵀA∞H is never indefinite.
    """
    n = A.shape[0]
    if n > _UNROLLED_SOLVE:
        return jax.scipy.linalg.cho_solve(jax.scipy.linalg.cho_factor(A), b)
    Ab = jnp.concatenate([A, b[:, None]], axis=1)
    eye = jnp.eye(n)
    for k in range(n):
        # one fused update: [A | b] − (a_k − e_k) ⊗ r_k / a_kk (row k becomes r_k / a_kk)
        Ab = Ab - (Ab[:, k:k + 1] - eye[:, k:k + 1]) * (Ab[k] / Ab[k, k])[None, :]
    return Ab[:, n]


def _apply_mass(model: Model, Y):
    """M Y per body without forming M: (m Y_lin, J Y_ang), Y of shape (n, 6, ...) ."""
    extra = (None,) * (Y.ndim - 2)
    lin = model.mass[(slice(None), None) + extra] * Y[:, :3]
    J = model.inertia[(slice(None), slice(None), slice(None)) + extra]
    ang = jnp.sum(J * Y[:, None, 3:], axis=2)
    return jnp.concatenate([lin, ang], axis=1)


def forward_dynamics(model: Model, q, qd, tau=None) -> jnp.ndarray:
    """q̈ from M* q̈ = Bᵀ F_gravity + Q_joints + τ − N* q̇. Shapes (n_q,) → (n_q,)."""
    return evaluate(model, q, qd, tau=tau).qdd


def reaction_loads(model: Model, ev: Evaluation):
    """Loads that each joint transmits from the parent (or the inertial frame) to its child.

    From each body's Newton–Euler residual r_i = M_i Ẋ_i + D_i M_i X_i − F_i (the constraint and
    joint-actuator load the body receives), summed from the leaves up: the joint of body c carries
    r_c plus what c passes on to its children. Returns force (n, 3) N and moment about the joint
    point (n, 3) N m, both in inertial axes. Along a joint's free directions these equal the joint's
    generalised loads (zero for an unloaded free root); across them they are the constraint loads.
    """
    r = _apply_mass(model, ev.Xdot) + gyroscopic(model, ev.X) - ev.F
    R = ev.kin.E[:, :3, :3]
    x = ev.kin.E[:, :3, 3]
    pJ = ev.kin.joint_frame[:, :3, 3]
    f = [r[i, :3] for i in range(model.n_bodies)]
    m = [R[i] @ r[i, 3:] + jnp.cross(x[i] - pJ[i], r[i, :3]) for i in range(model.n_bodies)]
    for i in range(model.n_bodies - 1, -1, -1):  # tree order: children come after parents
        p = model.parents[i]
        if p >= 0:
            f[p] = f[p] + f[i]
            m[p] = m[p] + m[i] + jnp.cross(pJ[i] - pJ[p], f[i])
    return jnp.stack(f), jnp.stack(m)


def energies(model: Model, q, qd, kin=None):
    """Kinetic ½ q̇ᵀM*q̇ and potential (gravity Σ m g z_i + joint springs) energy, J. ``kin``:
    the kinematics at (q, q̇) where the caller has them (one copy less to compile)."""
    kin = kinematics(model, q, qd) if kin is None else kin
    T = 0.5 * jnp.sum(kin.X * _apply_mass(model, kin.X))
    V = jnp.sum(model.mass * model.gravity * kin.E[:, 2, 3])
    V = V + 0.5 * jnp.sum(model.stiffness * (q - model.rest) ** 2)
    return T, V
