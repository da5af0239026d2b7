"""SE(3) frame connections against scipy's Rotation and the group identities."""
import jax
import numpy as np
import pytest
import scipy.linalg
from scipy.spatial.transform import Rotation

from mfm.mechanics import se3

RNG = np.random.default_rng(7)
# Identities of exact algebra evaluated in float64: a few ulps of the O(1) entries.
TOL = 1e-12


def random_rotvecs(n):
    v = RNG.normal(size=(n, 3))
    v /= np.linalg.norm(v, axis=1, keepdims=True)
    angles = np.concatenate([RNG.uniform(0, np.pi, n - 4), [1e-9, 1e-5, np.pi - 1e-7, np.pi - 1e-3]])
    return v * angles[:, None]


def random_transforms(n):
    return [np.asarray(se3.make(Rotation.from_rotvec(w).as_matrix(), RNG.normal(size=3)))
            for w in random_rotvecs(n)]


def test_hat_vee():
    for _ in range(10):
        w, u = RNG.normal(size=3), RNG.normal(size=3)
        W = np.asarray(se3.hat(w))
        np.testing.assert_allclose(W @ u, np.cross(w, u), atol=TOL)
        np.testing.assert_allclose(W, -W.T, atol=0)
        np.testing.assert_allclose(se3.vee(W), w, atol=TOL)


@pytest.mark.parametrize("w", list(random_rotvecs(20)))
def test_so3_exp_log_against_scipy(w):
    R_ref = Rotation.from_rotvec(w).as_matrix()
    np.testing.assert_allclose(se3.so3_exp(w), R_ref, atol=TOL)
    # log near π loses digits as sqrt(eps)/(π − θ) at most: 1e-9 is still far below any use here
    np.testing.assert_allclose(se3.so3_log(R_ref), Rotation.from_matrix(R_ref).as_rotvec(), atol=1e-9)


def test_se3_exp_is_matrix_exponential_and_log_inverts_it():
    for _ in range(10):
        xi = np.concatenate([RNG.normal(size=3), random_rotvecs(5)[RNG.integers(0, 4)]])
        E = np.asarray(se3.se3_exp(xi))
        np.testing.assert_allclose(E, scipy.linalg.expm(np.asarray(se3.twist_hat(xi))), atol=1e-11)
        np.testing.assert_allclose(se3.se3_log(E), xi, atol=1e-9)


def test_inverse_composition_adjoint():
    Es = random_transforms(12)
    for E1, E2 in zip(Es[:-1], Es[1:]):
        np.testing.assert_allclose(E1 @ np.asarray(se3.inverse(E1)), np.eye(4), atol=TOL)
        np.testing.assert_allclose(se3.inverse(E1), np.linalg.inv(E1), atol=1e-11)
        np.testing.assert_allclose(se3.compose(E1, E2), E1 @ E2, atol=TOL)
        xi = RNG.normal(size=6)
        lhs = E1 @ np.asarray(se3.twist_hat(xi)) @ np.linalg.inv(E1)
        np.testing.assert_allclose(se3.twist_hat(np.asarray(se3.adjoint(E1)) @ xi), lhs, atol=1e-11)
        np.testing.assert_allclose(se3.adjoint(E1 @ E2),
                                   np.asarray(se3.adjoint(E1)) @ np.asarray(se3.adjoint(E2)), atol=1e-11)
        np.testing.assert_allclose(se3.adjoint_inverse(E1), np.linalg.inv(se3.adjoint(E1)), atol=1e-11)


def test_euler_zyx_against_scipy():
    for w in random_rotvecs(20)[:-4]:
        R = Rotation.from_rotvec(w)
        yaw, pitch, roll = R.as_euler("ZYX")
        np.testing.assert_allclose(se3.euler_zyx(R.as_matrix()), [roll, pitch, yaw], atol=1e-10)
        np.testing.assert_allclose(se3.rot_z(yaw) @ se3.rot_y(pitch) @ se3.rot_x(roll), R.as_matrix(),
                                   atol=TOL)


def test_exp_log_gradients_finite_at_identity():
    g = jax.grad(lambda w: se3.so3_exp(w)[0, 1])(np.zeros(3))
    assert np.all(np.isfinite(g))
    np.testing.assert_allclose(g, [0, 0, -1], atol=TOL)  # d/dw R₀₁ = −w_z at identity
    g = jax.grad(lambda w: se3.so3_log(se3.so3_exp(w))[2])(np.array([1e-12, 0.0, 0.0]))
    np.testing.assert_allclose(g, [0, 0, 1], atol=1e-9)
