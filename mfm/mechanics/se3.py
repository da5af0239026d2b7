"""SE(3) frame connections as 4×4 matrices (Lande-Sudall et al. eqs. 4–12).

A frame connection ``E = [[R, x], [0, 1]]`` places a child frame in a parent frame: ``R`` turns
child axes into parent axes and ``x`` is the child origin in parent axes. Composition is the matrix
product (eq. 7) and the inverse is analytic (eq. 8): ``E⁻¹ = [[Rᵀ, −Rᵀx], [0, 1]]``.

Twists are ordered ``ξ = (v, ω)``: linear part first, angular part second, with
``ξ̂ = [[ω̂, v], [0, 0]]``. A body twist ``(E⁻¹ Ė)^∨`` holds ``v = Rᵀ ẋ`` and ω in body axes (eq. 12).

All functions are pure jax and work on float64 arrays; batch them with ``jax.vmap``.
"""
from __future__ import annotations

import jax
import jax.numpy as jnp

from .. import backend as _xla

# Below this rotation angle the closed forms of exp/log switch to Taylor series (their relative
# error there is below 1e-16 in float64).
_SMALL_ANGLE = 1e-4


def rotate(R, v):
    """R v for stacks of 3×3 R (..., 3, 3) and vectors v (..., 3), written as a multiply–reduce.

    The small products of the time step (3×3 rotations, B-matrix rows of a few coordinates) are
    written this way rather than as einsum/matmul: XLA on a CPU turns those into library dot calls
    of about a microsecond each whatever their size, while a multiply–reduce fuses with its
    neighbours (benchmarks/RESULTS.md, "Where the M4 134 step's time goes")."""
    return jnp.sum(R * v[..., None, :], axis=-1)


def rotate_t(R, v):
    """Rᵀ v for stacks (..., 3, 3) and (..., 3), as :func:`rotate`."""
    return jnp.sum(R * v[..., :, None], axis=-2)


# products X Y (m, k) × (k, p) up to this many multiplications are written as a multiply–reduce,
# wider ones as a dot: XLA makes a wide multiply–reduce one slow library fusion (Wu & Yuan's BᵀMB,
# 96 × 18 × 18: 55 µs/step traced, against a dot's few). With the time loop compiled whole
# (mfm.runner.xla, library fusions off) a multiply–reduce up to _COLUMNS_LIMIT: the inline dot is the
# slow one there (the same product 28 µs/step)
_REDUCE_LIMIT = 8192
# With the time loop compiled whole on a CPU, products of more than this many multiplications are
# made column by column (:func:`_by_columns`): XLA emits a multiply–reduce there as one scalar
# chain per output element (Wu & Yuan's A∞ H, 75 × 75 × 18: 82 µs an iteration of a loop, and
# with Hᵀ(A∞ H) half of the model's evaluation), a matrix–vector product as a vectorised tiled
# loop (16 µs; 36 × 36 × 12: 12.4 against 2.3 µs; python benchmarks/wide_products.py). Below it
# the multiply–reduce, which fuses with its operands' making, is as fast or faster (M4 134's
# 24 × 24 × 7: its loop 15–19 µs an evaluation against 20–21 µs by columns).
_COLUMNS_LIMIT = 8192


def _by_columns(X, Y):
    """X Y for X (m, k), Y (k, p) as p matrix–vector products X Y[:, l], in a loop (one copy of
    the product in the compiled program: unrolled, the p copies cost Wu & Yuan's first run 8 s
    more compilation for the same speed). Sums in another order than the multiply–reduce: the
    same to round-off."""
    YT = Y.T                                   # (p, k): the columns as contiguous rows

    def column(l, GT):
        y = jax.lax.dynamic_index_in_dim(YT, l, axis=0, keepdims=False)
        return jax.lax.dynamic_update_index_in_dim(GT, X @ y, l, axis=0)

    GT = jax.lax.fori_loop(0, YT.shape[0], column,
                           jnp.zeros((YT.shape[0], X.shape[0]), jnp.result_type(X, Y)))
    return GT.T


def matmul_small(X, Y, *, transpose_x=False):
    """X Y for 2-D X (m, k), Y (k, p); with ``transpose_x``, Xᵀ Y for X (..., m), Y (..., p),
    summed over all leading axes. A multiply–reduce while m k p ≤ 8,192 (see :func:`rotate` for
    why), a dot above. With the time loop compiled whole (:mod:`mfm.runner.xla`) a multiply–reduce up
    to the same size (XLA's inline dot of Wu & Yuan's BᵀMB cost 28 µs/step there), and on a CPU
    column by column above (:func:`_by_columns`). Xᵀ Y is reduced over X's leading axes
    directly: a transposed or reshaped operand costs XLA extra copy kernels."""
    if transpose_x:
        m, k = X.shape[-1], X.size // X.shape[-1]
    else:
        m, k = X.shape
    p = Y.shape[-1]
    if (_xla.LOOPS_COMPILED_WHOLE and m * k * p > _COLUMNS_LIMIT
            and jax.default_backend() == "cpu"):
        if transpose_x:
            return _by_columns(X.reshape(k, m).T, Y.reshape(k, p))
        return _by_columns(X, Y)
    if _xla.LOOPS_COMPILED_WHOLE or m * k * p <= _REDUCE_LIMIT:
        if transpose_x:
            return jnp.sum(X[..., :, None] * Y[..., None, :], axis=tuple(range(X.ndim - 1)))
        return jnp.sum(X[:, :, None] * Y[None, :, :], axis=1)
    if transpose_x:
        return X.reshape(k, m).T @ Y.reshape(k, -1)
    return X @ Y


def hat(w):
    """Skew matrix ``ŵ`` of a 3-vector, so that ``ŵ u = w × u``. Shape (3,) → (3, 3)."""
    w = jnp.asarray(w)
    z = jnp.zeros_like(w[0])
    return jnp.array([[z, -w[2], w[1]], [w[2], z, -w[0]], [-w[1], w[0], z]])


def vee(W):
    """Inverse of :func:`hat`: the 3-vector of a skew matrix (its skew part). (3, 3) → (3,)."""
    return 0.5 * jnp.array([W[2, 1] - W[1, 2], W[0, 2] - W[2, 0], W[1, 0] - W[0, 1]])


def _sinc_terms(theta):
    """Return ``sin θ/θ``, ``(1 − cos θ)/θ²`` and ``(θ − sin θ)/θ³``, safe at θ → 0 (and for grad)."""
    small = theta < _SMALL_ANGLE
    t = jnp.where(small, 1.0, theta)  # keeps the unused branch finite for gradients
    t2 = theta * theta
    a = jnp.where(small, 1.0 - t2 / 6.0 + t2 * t2 / 120.0, jnp.sin(t) / t)
    b = jnp.where(small, 0.5 - t2 / 24.0 + t2 * t2 / 720.0, (1.0 - jnp.cos(t)) / (t * t))
    c = jnp.where(small, 1.0 / 6.0 - t2 / 120.0 + t2 * t2 / 5040.0, (t - jnp.sin(t)) / (t * t * t))
    return a, b, c


def _norm(w):
    # sqrt of a sum of squares with a safe gradient at zero
    n2 = jnp.sum(w * w)
    safe = n2 > 0.0
    return jnp.where(safe, jnp.sqrt(jnp.where(safe, n2, 1.0)), 0.0)


def so3_exp(w):
    """Rodrigues: ``Exp(ŵ) = I + (sin θ/θ) ŵ + ((1 − cos θ)/θ²) ŵ²``, θ = |w|. (3,) → (3, 3)."""
    theta = _norm(w)
    a, b, _ = _sinc_terms(theta)
    W = hat(w)
    return jnp.eye(3) + a * W + b * (W @ W)


def so3_log(R):
    """Rotation vector w with ``so3_exp(w) = R``, |w| ≤ π. (3, 3) → (3,).

    Uses ``θ = atan2(|vee(R − Rᵀ)|/2, (tr R − 1)/2)``; near θ = π the axis comes from the symmetric
    part ``(R + I)/2 = I + (1 − cos θ)/θ² ŵ²`` instead, where the skew part carries no information.
    """
    cos_t = jnp.clip((jnp.trace(R) - 1.0) * 0.5, -1.0, 1.0)
    s = vee(R)  # = sin θ · axis
    sin_t = _norm(s)
    theta = jnp.arctan2(sin_t, cos_t)
    small = theta < _SMALL_ANGLE
    a, _, _ = _sinc_terms(theta)
    w_generic = s / jnp.where(small, 1.0, a)
    w_generic = jnp.where(small, s * (1.0 + theta * theta / 6.0), w_generic)
    # near π the skew part vanishes; the symmetric part (R + Rᵀ)/2 = cos θ I + (1 − cos θ) n nᵀ
    # gives n nᵀ exactly, and the skew part still fixes the sign of n.
    # (the unused branch is kept finite so that gradients through jnp.where stay finite)
    near_pi = cos_t < -0.99
    nnT = (0.5 * (R + R.T) - cos_t * jnp.eye(3)) / jnp.where(near_pi, 1.0 - cos_t, 1.0)
    k = jnp.argmax(jnp.diagonal(nnT))
    n = nnT[:, k] / jnp.sqrt(jnp.where(near_pi, nnT[k, k], 1.0))
    n = jnp.where(jnp.dot(n, s) < 0.0, -n, n)
    return jnp.where(near_pi, theta * n, w_generic)


def _left_jacobian(w):
    """SO(3) left Jacobian ``J(w) = I + ((1 − cos θ)/θ²) ŵ + ((θ − sin θ)/θ³) ŵ²``."""
    theta = _norm(w)
    _, b, c = _sinc_terms(theta)
    W = hat(w)
    return jnp.eye(3) + b * W + c * (W @ W)


def _left_jacobian_inv(w):
    """Inverse of the SO(3) left Jacobian: ``I − ½ŵ + (1/θ² − (1 + cos θ)/(2θ sin θ)) ŵ²``."""
    theta = _norm(w)
    small = theta < _SMALL_ANGLE
    t = jnp.where(small, 1.0, theta)
    coef = jnp.where(small, 1.0 / 12.0 + theta * theta / 720.0,
                     1.0 / (t * t) - (1.0 + jnp.cos(t)) / (2.0 * t * jnp.sin(t)))
    W = hat(w)
    return jnp.eye(3) - 0.5 * W + coef * (W @ W)


def make(R, x):
    """Frame connection ``[[R, x], [0, 1]]`` from a rotation (3, 3) and a translation (3,)."""
    top = jnp.concatenate([jnp.asarray(R), jnp.asarray(x)[:, None]], axis=1)
    return jnp.concatenate([top, jnp.array([[0.0, 0.0, 0.0, 1.0]], dtype=top.dtype)], axis=0)


def rotation(E):
    return E[:3, :3]


def translation(E):
    return E[:3, 3]


def inverse(E):
    """Analytic inverse (Lande-Sudall et al. eq. 8): ``[[Rᵀ, −Rᵀx], [0, 1]]``."""
    R, x = E[:3, :3], E[:3, 3]
    return make(R.T, -R.T @ x)


def compose(*Es):
    """Product ``E₁ E₂ ⋯`` of frame connections (closure of SE(3), eq. 7)."""
    out = Es[0]
    for E in Es[1:]:
        out = out @ E
    return out


def twist_hat(xi):
    """``ξ̂ = [[ω̂, v], [0, 0]]`` for ξ = (v, ω). (6,) → (4, 4)."""
    xi = jnp.asarray(xi)
    top = jnp.concatenate([hat(xi[3:]), xi[:3, None]], axis=1)
    return jnp.concatenate([top, jnp.zeros((1, 4), dtype=top.dtype)], axis=0)


def twist_vee(X):
    """Inverse of :func:`twist_hat`. (4, 4) → (6,)."""
    return jnp.concatenate([X[:3, 3], vee(X[:3, :3])])


def se3_exp(xi):
    """``Exp(ξ̂) = [[Exp(ω̂), J(ω) v], [0, 1]]`` with J the SO(3) left Jacobian. (6,) → (4, 4)."""
    xi = jnp.asarray(xi)
    v, w = xi[:3], xi[3:]
    return make(so3_exp(w), _left_jacobian(w) @ v)


def se3_log(E):
    """Twist ξ = (v, ω) with ``se3_exp(ξ) = E``, |ω| ≤ π. (4, 4) → (6,)."""
    w = so3_log(E[:3, :3])
    v = _left_jacobian_inv(w) @ E[:3, 3]
    return jnp.concatenate([v, w])


def adjoint(E):
    """Adjoint ``Ad_E = [[R, x̂R], [0, R]]`` acting on twists (v, ω): ``(E ξ̂ E⁻¹)^∨ = Ad_E ξ``."""
    R, x = E[:3, :3], E[:3, 3]
    top = jnp.concatenate([R, hat(x) @ R], axis=1)
    bottom = jnp.concatenate([jnp.zeros((3, 3), dtype=R.dtype), R], axis=1)
    return jnp.concatenate([top, bottom], axis=0)


def adjoint_inverse(E):
    """``Ad_{E⁻¹} = [[Rᵀ, −Rᵀx̂], [0, Rᵀ]]`` without forming E⁻¹."""
    R, x = E[:3, :3], E[:3, 3]
    Rt = R.T
    top = jnp.concatenate([Rt, -Rt @ hat(x)], axis=1)
    bottom = jnp.concatenate([jnp.zeros((3, 3), dtype=R.dtype), Rt], axis=1)
    return jnp.concatenate([top, bottom], axis=0)


def rot_x(a):
    c, s = jnp.cos(a), jnp.sin(a)
    o, z = jnp.ones_like(a), jnp.zeros_like(a)
    return jnp.array([[o, z, z], [z, c, -s], [z, s, c]])


def rot_y(a):
    c, s = jnp.cos(a), jnp.sin(a)
    o, z = jnp.ones_like(a), jnp.zeros_like(a)
    return jnp.array([[c, z, s], [z, o, z], [-s, z, c]])


def rot_z(a):
    c, s = jnp.cos(a), jnp.sin(a)
    o, z = jnp.ones_like(a), jnp.zeros_like(a)
    return jnp.array([[c, -s, z], [s, c, z], [z, z, o]])


def euler_zyx(R):
    """Roll, pitch, yaw (φ, θ, ψ) with ``R = R_z(ψ) R_y(θ) R_x(φ)``; θ ∈ [−π/2, π/2]."""
    pitch = jnp.arcsin(jnp.clip(-R[2, 0], -1.0, 1.0))
    roll = jnp.arctan2(R[2, 1], R[2, 2])
    yaw = jnp.arctan2(R[1, 0], R[0, 0])
    return jnp.array([roll, pitch, yaw])
