"""Points fixed on bodies, and the B-like rows of their motion (hydro reference points, PTO
attachment points)."""
from __future__ import annotations

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from ..backend import device_array
from . import se3


class BodyPoints(eqx.Module):
    """Points fixed on bodies (hydro reference points, PTO attachment points), each with a
    6-dof small-motion vector ξ = (displacement of the point, rotation vector of its body).

    Its velocity is a row block of a B-like matrix, ξ̇ = H(q) q̇ with H = T·B, T moving the CoM
    velocity to the point and turning the body-axis ω into inertial axes (DESIGN §2, "generalise
    the idea"). Static: ``body_index``; arrays: ``d_ref`` (K, 3) point − CoM at q = 0 (body axes),
    ``ref0`` (K, 3) the points at q = 0 (inertial). Every method handles all points at once.
    """
    body_index: tuple[int, ...] = eqx.field(static=True)
    d_ref: jnp.ndarray      # (K, 3) reference point − CoM at q = 0
    ref0: jnp.ndarray       # (K, 3) reference points at q = 0 (inertial)

    def _frames(self, kin):
        idx = np.asarray(self.body_index)
        R = kin.E[idx, :3, :3]
        rho = se3.rotate(R, self.d_ref)
        return idx, R, rho

    def h_matrix(self, kin):
        """H (6K, n_q): ξ̇ = H q̇; and the rotation matrices (K, 3, 3), lever arms ρ (K, 3)."""
        idx, R, rho = self._frames(kin)
        w_cols = jnp.sum(R[:, :, :, None] * kin.B[idx, 3:][:, None], axis=2)   # inertial ω Jacobian
        lin = kin.B[idx, :3] - jnp.cross(rho[:, :, None], w_cols, axis=1)   # v + ω × ρ
        H = jnp.concatenate([lin, w_cols], axis=1)
        return H.reshape(-1, H.shape[-1]), R, rho

    def xi(self, kin):
        """ξ (6K,): displacement of each reference point and its rotation vector."""
        idx, R, rho = self._frames(kin)
        r = kin.E[idx, :3, 3] + rho - self.ref0
        return jnp.concatenate([r, jax.vmap(se3.so3_log)(R)], axis=1).reshape(-1)

    def velocity_and_bias(self, kin):
        """ξ̇ (6K,) and Ḣ q̇ (6K,) from the tree walk's velocities and velocity-product terms."""
        idx, R, rho = self._frames(kin)
        w = se3.rotate(R, kin.X[idx, 3:])
        beta = se3.rotate(R, kin.bias[idx, 3:])     # d/dt(R ω_b) = R ω̇_b
        v = jnp.concatenate([kin.X[idx, :3] + jnp.cross(w, rho), w], axis=1)
        a = jnp.concatenate([kin.bias[idx, :3] + jnp.cross(beta, rho)
                             + jnp.cross(w, jnp.cross(w, rho)), beta], axis=1)
        return v.reshape(-1), a.reshape(-1)

    def to_body_wrench(self, F, kin, n_bodies, point_offset=None):
        """Loads F (6K: force at r_k, moment about r_k, inertial) → body wrenches (n, 6): force,
        and moment about the CoM in body axes Rᵀ(m + ρ × f). ``point_offset`` (K, 3) replaces ρ
        (the point of application relative to the CoM, inertial) when given."""
        idx, R, rho = self._frames(kin)
        rho = rho if point_offset is None else point_offset
        F = F.reshape(-1, 6)
        f, m = F[:, :3], F[:, 3:]
        mb = se3.rotate_t(R, m + jnp.cross(rho, f))
        # summed onto the bodies by a static 0/1 matrix rather than a scatter-add: a scatter keeps
        # XLA from compiling the time loop as one function (mfm.runner.xla)
        S = np.zeros((n_bodies, len(idx)))
        S[idx, np.arange(len(idx))] = 1.0
        return jnp.sum(S[:, :, None] * jnp.concatenate([f, mb], axis=1)[None], axis=1)

    @classmethod
    def on_bodies(cls, com, body_index, points) -> "BodyPoints":
        """Points given in inertial axes at q = 0 (K, 3), fixed on the bodies ``body_index``
        whose centres of mass at q = 0 are ``com`` (n, 3)."""
        points = np.asarray(points, dtype=float).reshape(-1, 3)
        d = points - np.asarray(com)[list(body_index)]
        return cls(body_index=tuple(int(i) for i in body_index), d_ref=device_array(d),
                   ref0=device_array(points))

    def positions(self, kin):
        """Inertial positions of the points (K, 3)."""
        idx, R, rho = self._frames(kin)
        return kin.E[idx, :3, 3] + rho


@eqx.filter_jit
def h_matrix_at(points: BodyPoints, kin):
    """``points.h_matrix(kin)[0]`` compiled: H (6K, n_q) at one configuration, for the host (the
    frequency domain's maps at q₀). Op by op, each primitive of it is compiled on its own, and
    no cache keeps those (Stansby & Li's first frequency response: ~1.5 s)."""
    return points.h_matrix(kin)[0]
